// Benchmarks of the numerical core on structured box meshes (vertices and
// tets in Z-order, as the VTK filters hand them over), with a plain sparse
// matrix-vector product on the same matrix as the baseline, so that timings
// can be quoted as multiples of one SpMV.
//
// Run (not a ctest test):
//   BenchSolvers                      # all, medians of 5 repetitions
//   BenchSolvers --benchmark_filter=Assemble
// The argument of each benchmark is the number of cells per side of the cube
// (6 tets per cell): 26 -> 105,456 tets, 55 -> 998,250 tets.

#include "ConjugateGradient.h"
#include "DiscreteDivergence.h"
#include "TestMeshes.h"
#include "TetMesh.h"

#include <benchmark/benchmark.h>

#include <map>
#include <memory>

namespace
{

using namespace translucency;

struct Problem
{
  testing::MeshData Data;
  TetMesh Mesh;
  OpticalProperties Material;
  std::vector<double> Irradiance;
  DiffusionSystem System;
};

/// Mesh, marble material, unit irradiance and assembled system, built once per size.
Problem& GetProblem(int cells)
{
  static std::map<int, std::unique_ptr<Problem>> cache;
  std::unique_ptr<Problem>& p = cache[cells];
  if (!p)
  {
    p = std::make_unique<Problem>();
    const testing::MeshData box = testing::CubeMesh(cells, 20.0, 0.2, 1);
    std::vector<int> pointOrder, tetOrder;
    TetMesh::ComputeSpatialOrder(box.Points, box.Tets, pointOrder, tetOrder);
    p->Data = testing::Permute(box, pointOrder, tetOrder);
    p->Mesh.SetGeometry(p->Data.Points, p->Data.Tets);
    const MaterialPreset& marble = FindMaterialPreset("marble");
    p->Material = OpticalProperties::Uniform(p->Mesh.GetNumberOfTets(), marble.Absorption,
      marble.ReducedScattering, marble.RefractiveIndex);
    p->Irradiance.assign(3 * p->Mesh.GetNumberOfPoints(), 0.0);
    for (int i : p->Mesh.GetBoundaryPoints())
    {
      // Light from +z: irradiance on the top half of the surface.
      const double z = p->Mesh.GetPoint(i)[2];
      for (int c = 0; c < 3; ++c)
      {
        p->Irradiance[3 * i + c] = z > 10.0 ? 1.0 : 0.0;
      }
    }
    DiscreteDivergence().Assemble(p->Mesh, p->Material, p->Irradiance, p->System);
  }
  return *p;
}

void SetSizeCounters(benchmark::State& state, const Problem& p)
{
  state.counters["tets"] = p.Mesh.GetNumberOfTets();
  state.counters["points"] = p.Mesh.GetNumberOfPoints();
  state.counters["nnz"] = p.Mesh.GetNumberOfNonZeros();
}

void BM_BuildMesh(benchmark::State& state)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  for (auto _ : state)
  {
    TetMesh mesh;
    mesh.SetGeometry(p.Data.Points, p.Data.Tets);
    benchmark::DoNotOptimize(mesh.GetNumberOfNonZeros());
  }
  SetSizeCounters(state, p);
  state.counters["colours"] = p.Mesh.GetScatterSchedule().GetNumberOfColours();
}

void BM_Assemble(benchmark::State& state)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  DiscreteDivergence divergence;
  DiffusionSystem system;
  divergence.Assemble(p.Mesh, p.Material, p.Irradiance, system); // allocate once
  for (auto _ : state)
  {
    divergence.Assemble(p.Mesh, p.Material, p.Irradiance, system);
    benchmark::DoNotOptimize(system.Values[2].data());
  }
  SetSizeCounters(state, p);
}

/// Baseline: y = M x with Eigen's (OpenMP) row-major product, one channel.
void BM_SpMV(benchmark::State& state)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  const SparseMatrixMap m = p.System.Matrix(0);
  const Eigen::VectorXd x = Eigen::VectorXd::Ones(m.cols());
  Eigen::VectorXd y(m.rows());
  for (auto _ : state)
  {
    y.noalias() = m * x;
    benchmark::DoNotOptimize(y.data());
  }
  SetSizeCounters(state, p);
}

void BM_SolveCG(benchmark::State& state)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  ConjugateGradient cg;
  cg.SetRelTol(1e-6);
  cg.SetMaxIter(10000);
  std::array<Eigen::VectorXd, NumberOfChannels> x;
  for (auto _ : state)
  {
    cg.Solve(p.System, x);
    benchmark::DoNotOptimize(x[0].data());
  }
  SetSizeCounters(state, p);
  state.counters["iterations"] =
    cg.GetNumIterations(0) + cg.GetNumIterations(1) + cg.GetNumIterations(2);
}

void Sizes(benchmark::internal::Benchmark* b)
{
  b->Arg(26)->Arg(55)->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(5)
    ->ReportAggregatesOnly(true);
}

BENCHMARK(BM_BuildMesh)->Apply(Sizes);
BENCHMARK(BM_SpMV)->Apply(Sizes);
BENCHMARK(BM_Assemble)->Apply(Sizes);
BENCHMARK(BM_SolveCG)->Apply(Sizes)->Iterations(1);

} // namespace

BENCHMARK_MAIN();
