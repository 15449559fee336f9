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
#include "LightSources.h"
#include "RayCaster.h"
#include "TestMeshes.h"
#include "TetMesh.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <random>

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
    p->Material = OpticalProperties::Uniform(p->Mesh.GetNumberOfTets(),
      marble.Absorption,
      marble.ReducedScattering,
      marble.RefractiveIndex);
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
  b->Arg(26)
    ->Arg(55)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
}

BENCHMARK(BM_BuildMesh)->Apply(Sizes);
BENCHMARK(BM_SpMV)->Apply(Sizes);
BENCHMARK(BM_Assemble)->Apply(Sizes);
BENCHMARK(BM_SolveCG)->Apply(Sizes)->Iterations(1);

// Ray casting (RayCaster) on a latitude-longitude sphere of radius 10 mm,
// 2 x 200 x 124 = 49,600 triangles (arg 125) or 2 x 283 x 176 = 99,616
// (arg 177, build only); queries on one thread.

/// Sphere with nLon = 1.6 nLat meridians: 2 nLon (nLat - 1) triangles.
void SphereSurface(int nLat, std::vector<double>& points, std::vector<int>& triangles)
{
  const double pi = 3.14159265358979323846, radius = 10.0;
  const int nLon = nLat * 8 / 5;
  points = { 0.0, 0.0, radius };
  for (int i = 1; i < nLat; ++i)
  {
    for (int j = 0; j < nLon; ++j)
    {
      const double theta = pi * i / nLat, phi = 2.0 * pi * j / nLon;
      points.insert(points.end(),
        { radius * std::sin(theta) * std::cos(phi),
          radius * std::sin(theta) * std::sin(phi),
          radius * std::cos(theta) });
    }
  }
  points.insert(points.end(), { 0.0, 0.0, -radius });
  const int south = 1 + (nLat - 1) * nLon;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * nLon + j % nLon; };
  triangles.clear();
  for (int j = 0; j < nLon; ++j)
  {
    triangles.insert(triangles.end(), { 0, ring(1, j), ring(1, j + 1) });
    for (int i = 1; i + 1 < nLat; ++i)
    {
      triangles.insert(triangles.end(), { ring(i, j), ring(i + 1, j), ring(i + 1, j + 1) });
      triangles.insert(triangles.end(), { ring(i, j), ring(i + 1, j + 1), ring(i, j + 1) });
    }
    triangles.insert(triangles.end(), { south, ring(nLat - 1, j + 1), ring(nLat - 1, j) });
  }
}

void BM_RayCasterBuild(benchmark::State& state)
{
  std::vector<double> points;
  std::vector<int> triangles;
  SphereSurface(static_cast<int>(state.range(0)), points, triangles);
  RayCaster caster;
  for (auto _ : state)
  {
    caster.Build(points, triangles);
    benchmark::DoNotOptimize(caster.GetNumberOfNodes());
  }
  state.counters["triangles"] = caster.GetNumberOfTriangles();
  state.counters["depth"] = caster.GetDepth();
}

/// Occluded() on one thread. Arg 0: 2^16 rays from random points inside the
/// sphere in random directions (all occluded). Arg 1: 2^16 shadow rays from
/// 1e-4 mm above random surface points into the cosine-weighted outer
/// hemisphere, reach 40 mm (none occluded: on a convex surface no ray can stop
/// early; rays in random order, so the tree is read from memory rather than
/// cache). Arg 2: the ray pattern of the irradiance stage: for every vertex
/// in mesh order, 32 HemisphereDirection() rays from x + offset (n + w),
/// offset 1e-5 diagonal, reach 2 diagonals (again none occluded).
void BM_RayCasterOccluded(benchmark::State& state)
{
  std::vector<double> points;
  std::vector<int> triangles;
  SphereSurface(125, points, triangles);
  RayCaster caster;
  caster.Build(points, triangles);
  const int mode = static_cast<int>(state.range(0));
  const int numVertices = static_cast<int>(points.size() / 3);
  const int numRays = mode == 2 ? 32 * numVertices : 1 << 16;
  std::vector<double> origins(3 * static_cast<size_t>(numRays)),
    directions(3 * static_cast<size_t>(numRays));
  std::mt19937_64 rng(1);
  auto uniform = [&rng]() { return testing::Uniform01(rng); };
  const double diag = 20.0 * std::sqrt(3.0);
  for (int r = 0; r < numRays; ++r)
  {
    double* o = &origins[3 * static_cast<size_t>(r)];
    double* d = &directions[3 * static_cast<size_t>(r)];
    if (mode == 2)
    {
      const int i = r / 32;
      const double* x = &points[3 * static_cast<size_t>(i)];
      const double n[3] = { x[0] / 10.0, x[1] / 10.0, x[2] / 10.0 };
      HemisphereDirection(n, r % 32, 32, std::fmod(0.6180339887498949 * i, 1.0), d);
      for (int k = 0; k < 3; ++k)
      {
        o[k] = x[k] + 1e-5 * diag * (n[k] + d[k]);
      }
      continue;
    }
    // Uniform unit vectors u and v.
    double u[3], v[3];
    for (double* w : { u, v })
    {
      const double z = 2.0 * uniform() - 1.0, phi = 6.283185307179586 * uniform();
      const double s = std::sqrt(1.0 - z * z);
      w[0] = s * std::cos(phi);
      w[1] = s * std::sin(phi);
      w[2] = z;
    }
    if (mode == 0)
    {
      const double radius = 9.9 * std::cbrt(uniform());
      for (int k = 0; k < 3; ++k)
      {
        o[k] = radius * v[k];
        d[k] = u[k];
      }
    }
    else
    {
      // Surface point 10 u, normal u; u + v is cosine-distributed about u.
      for (int k = 0; k < 3; ++k)
      {
        o[k] = (10.0 + 1e-4) * u[k];
        d[k] = u[k] + v[k];
      }
    }
  }
  const double reach =
    mode == 0 ? std::numeric_limits<double>::infinity() : (mode == 1 ? 40.0 : 2.0 * diag);
  int occluded = 0;
  for (auto _ : state)
  {
    occluded = 0;
    for (int r = 0; r < numRays; ++r)
    {
      occluded += caster.Occluded(
        &origins[3 * static_cast<size_t>(r)], &directions[3 * static_cast<size_t>(r)], reach);
    }
    benchmark::DoNotOptimize(occluded);
  }
  state.SetItemsProcessed(state.iterations() * numRays);
  state.counters["rays_per_second"] = benchmark::Counter(
    static_cast<double>(state.iterations()) * numRays, benchmark::Counter::kIsRate);
  state.counters["occluded_fraction"] = static_cast<double>(occluded) / numRays;
  state.counters["triangles"] = caster.GetNumberOfTriangles();
}

BENCHMARK(BM_RayCasterBuild)->Arg(125)->Arg(177)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RayCasterOccluded)
  ->Arg(0)
  ->Arg(1)
  ->Arg(2)
  ->Unit(benchmark::kMillisecond)
  ->UseRealTime();

} // namespace

BENCHMARK_MAIN();
