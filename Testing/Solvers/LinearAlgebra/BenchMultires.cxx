// Benchmarks of the linear solvers of the vertex discretisations
// (cg-jacobi, transcut-multires, multigrid-cg, multigrid-agg) on the three
// channels of one system: hierarchy/set-up, values-only set-up, cold solve to a relative
// residual of 0.03 (about 1 % boundary-fluence error) and 1e-6, and a warm
// solve after a 10-degree rotation of the directional light. Part of the
// BenchSolvers executable (run by hand, not a ctest test):
//
//   BenchSolvers --benchmark_filter=Linear
//   TRANSLUCENCY_BENCH_MESH=/tmp/bunny1M.bin BenchSolvers --benchmark_filter=Linear
//
// Argument: cells per side of a jittered cube (26 -> 105k tets, 55 -> 1M
// tets), or 0 = the mesh in the file named by TRANSLUCENCY_BENCH_MESH
// (int32 #points, int32 #tets, float64 xyz per point, int32 4 ids per tet;
// e.g. a TetGen bunny written by Testing/Solvers/write_bench_mesh.py).
// Material marble, one directional light with shadows. Counters per solve:
// red-channel iterations and SpMV-equivalents (multiply-adds / nnz) and the
// relative L2 error of the boundary fluence (all channels) against a 1e-10
// solution.

#include "AggregationMultigrid.h"
#include "DiscreteDivergence.h"
#include "LightSources.h"
#include "LinearSolver.h"
#include "MultiresSolvers.h"
#include "TestMeshes.h"
#include "TetMesh.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>

namespace
{

using namespace translucency;

struct LinearProblem
{
  TetMesh Mesh;
  OpticalProperties Material;
  DiffusionSystem System;          ///< light 1
  std::array<Eigen::VectorXd, 3> B2; ///< right-hand sides for light 2 (10 degrees)
  std::array<Eigen::VectorXd, 3> Reference1, Reference2; ///< 1e-10 solutions
  bool Ok = true;
};

std::array<Eigen::VectorXd, 3> RightHandSides(
  LinearProblem& p, const std::array<double, 3>& direction)
{
  LightSource light;
  light.Type = LightSource::Kind::Directional;
  light.Direction = direction;
  std::vector<double> eta(p.Mesh.GetNumberOfPoints(), p.Material.RefractiveIndex[0]);
  std::vector<double> q;
  ComputeBoundaryIrradiance(p.Mesh, eta, { light }, 0.0, 0, true, q);
  DiffusionSystem s;
  DiscreteDivergence().Assemble(p.Mesh, p.Material, q, s);
  return s.RightHandSide;
}

LinearProblem& GetLinearProblem(int cells)
{
  static std::map<int, std::unique_ptr<LinearProblem>> cache;
  auto& p = cache[cells];
  if (p)
  {
    return *p;
  }
  p = std::make_unique<LinearProblem>();
  testing::MeshData data;
  if (cells > 0)
  {
    const testing::MeshData box = testing::CubeMesh(cells, 20.0, 0.2, 1);
    std::vector<int> pointOrder, tetOrder;
    TetMesh::ComputeSpatialOrder(box.Points, box.Tets, pointOrder, tetOrder);
    data = testing::Permute(box, pointOrder, tetOrder);
  }
  else
  {
    const char* path = std::getenv("TRANSLUCENCY_BENCH_MESH");
    FILE* f = path ? std::fopen(path, "rb") : nullptr;
    int header[2] = { 0, 0 };
    if (!f || std::fread(header, sizeof(int), 2, f) != 2)
    {
      p->Ok = false;
      if (f)
      {
        std::fclose(f);
      }
      return *p;
    }
    data.Points.resize(3 * static_cast<std::size_t>(header[0]));
    data.Tets.resize(4 * static_cast<std::size_t>(header[1]));
    p->Ok = std::fread(data.Points.data(), sizeof(double), data.Points.size(), f) ==
        data.Points.size() &&
      std::fread(data.Tets.data(), sizeof(int), data.Tets.size(), f) == data.Tets.size();
    std::fclose(f);
    if (!p->Ok)
    {
      return *p;
    }
    std::vector<int> pointOrder, tetOrder;
    TetMesh::ComputeSpatialOrder(data.Points, data.Tets, pointOrder, tetOrder);
    data = testing::Permute(data, pointOrder, tetOrder);
  }
  p->Mesh.SetGeometry(data.Points, data.Tets);
  const MaterialPreset& marble = FindMaterialPreset("marble");
  p->Material = OpticalProperties::Uniform(p->Mesh.GetNumberOfTets(), marble.Absorption,
    marble.ReducedScattering, marble.RefractiveIndex);
  // Light 1 from (0.3, -1, -0.5); light 2 rotated 10 degrees about z.
  const std::array<double, 3> d1{ 0.3, -1.0, -0.5 };
  const double a = 10.0 * M_PI / 180.0;
  const std::array<double, 3> d2{ std::cos(a) * d1[0] - std::sin(a) * d1[1],
    std::sin(a) * d1[0] + std::cos(a) * d1[1], d1[2] };
  {
    LightSource light;
    light.Direction = d1;
    std::vector<double> eta(p->Mesh.GetNumberOfPoints(), marble.RefractiveIndex);
    std::vector<double> q;
    ComputeBoundaryIrradiance(p->Mesh, eta, { light }, 0.0, 0, true, q);
    DiscreteDivergence().Assemble(p->Mesh, p->Material, q, p->System);
  }
  p->B2 = RightHandSides(*p, d2);
  MultigridConjugateGradient reference;
  reference.SetRelTol(1e-10);
  reference.SetMaxIter(10000);
  reference.Setup(p->System, &p->Mesh, true);
  std::array<LinearSolveStats, 3> stats;
  reference.Solve(p->System, p->Reference1, false, stats);
  const auto b1 = p->System.RightHandSide;
  p->System.RightHandSide = p->B2;
  reference.Solve(p->System, p->Reference2, false, stats);
  p->System.RightHandSide = b1;
  return *p;
}

/// Relative L2 error of the boundary values, all channels together.
double BoundaryError(const LinearProblem& p, const std::array<Eigen::VectorXd, 3>& x,
  const std::array<Eigen::VectorXd, 3>& reference)
{
  double num = 0.0, den = 0.0;
  for (int i : p.Mesh.GetBoundaryPoints())
  {
    for (int c = 0; c < 3; ++c)
    {
      num += std::pow(x[c][i] - reference[c][i], 2);
      den += std::pow(reference[c][i], 2);
    }
  }
  return std::sqrt(num / den);
}

void Counters(benchmark::State& state, const LinearProblem& p,
  const std::array<LinearSolveStats, 3>& stats, double error)
{
  state.counters["points"] = p.Mesh.GetNumberOfPoints();
  state.counters["tets"] = p.Mesh.GetNumberOfTets();
  state.counters["iter_R"] = stats[0].Iterations;
  state.counters["spmv_R"] = stats[0].SpMVEquivalents;
  state.counters["bfl_err"] = error;
}

/// Setup: patternChanged = true (hierarchy build) or false (values only).
void BM_LinearSetup(benchmark::State& state, const char* name, bool pattern)
{
  LinearProblem& p = GetLinearProblem(static_cast<int>(state.range(0)));
  if (!p.Ok)
  {
    state.SkipWithError("no mesh: set TRANSLUCENCY_BENCH_MESH");
    return;
  }
  auto solver = CreateLinearSolver(name);
  solver->Setup(p.System, &p.Mesh, true);
  for (auto _ : state)
  {
    solver->Setup(p.System, &p.Mesh, pattern);
  }
  state.counters["points"] = p.Mesh.GetNumberOfPoints();
  if (auto* m = dynamic_cast<MultiresLinearSolverBase*>(solver.get()))
  {
    state.counters["levels"] = m->GetHierarchy().GetNumberOfLevels();
    state.counters["op_complexity"] = m->GetOperatorComplexity();
    state.counters["MB"] = solver->GetMemoryBytes() / 1e6;
  }
  if (auto* m = dynamic_cast<AggregationMultigridSolver*>(solver.get()))
  {
    state.counters["levels"] = m->GetNumberOfLevels();
    state.counters["op_complexity"] = m->GetOperatorComplexity();
    state.counters["MB"] = solver->GetMemoryBytes() / 1e6;
  }
}

/// Cold solve (from zero) of the three channels to `tol`.
void BM_LinearCold(benchmark::State& state, const char* name, double tol)
{
  LinearProblem& p = GetLinearProblem(static_cast<int>(state.range(0)));
  if (!p.Ok)
  {
    state.SkipWithError("no mesh: set TRANSLUCENCY_BENCH_MESH");
    return;
  }
  auto solver = CreateLinearSolver(name);
  solver->SetRelTol(tol);
  solver->SetMaxIter(10000);
  solver->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> x;
  std::array<LinearSolveStats, 3> stats;
  for (auto _ : state)
  {
    solver->Solve(p.System, x, false, stats);
    benchmark::DoNotOptimize(x[0].data());
  }
  Counters(state, p, stats, BoundaryError(p, x, p.Reference1));
}

/// Warm relight: from the light-1 solution (to tol) to light 2, to tol.
void BM_LinearWarm(benchmark::State& state, const char* name, double tol)
{
  LinearProblem& p = GetLinearProblem(static_cast<int>(state.range(0)));
  if (!p.Ok)
  {
    state.SkipWithError("no mesh: set TRANSLUCENCY_BENCH_MESH");
    return;
  }
  auto solver = CreateLinearSolver(name);
  solver->SetRelTol(tol);
  solver->SetMaxIter(10000);
  solver->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> x1, x;
  std::array<LinearSolveStats, 3> stats;
  solver->Solve(p.System, x1, false, stats);
  DiffusionSystem& s = p.System;
  const auto b1 = s.RightHandSide;
  s.RightHandSide = p.B2;
  for (auto _ : state)
  {
    state.PauseTiming();
    x = x1;
    state.ResumeTiming();
    solver->Solve(s, x, true, stats);
    benchmark::DoNotOptimize(x[0].data());
  }
  s.RightHandSide = b1;
  Counters(state, p, stats, BoundaryError(p, x, p.Reference2));
}

void LinearSizes(benchmark::internal::Benchmark* b)
{
  b->Arg(26)->Arg(55)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(5)
    ->ReportAggregatesOnly(true);
}

BENCHMARK_CAPTURE(BM_LinearSetup, multigrid_cg_build, "multigrid-cg", true)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearSetup, multigrid_cg_values, "multigrid-cg", false)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearSetup, transcut_build, "transcut-multires", true)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearSetup, transcut_values, "transcut-multires", false)
  ->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearCold, cg_jacobi_0_03, "cg-jacobi", 0.03)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearCold, transcut_0_03, "transcut-multires", 0.03)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearCold, multigrid_cg_0_03, "multigrid-cg", 0.03)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearCold, cg_jacobi_1e_6, "cg-jacobi", 1e-6)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearCold, transcut_1e_6, "transcut-multires", 1e-6)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearCold, multigrid_cg_1e_6, "multigrid-cg", 1e-6)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearWarm, cg_jacobi_0_03, "cg-jacobi", 0.03)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearWarm, transcut_0_03, "transcut-multires", 0.03)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearWarm, multigrid_cg_0_03, "multigrid-cg", 0.03)->Apply(LinearSizes);
// multigrid-agg at the tolerances of its 1 % boundary-fluence operating
// point (Multiresolution.md): cold 0.05, warm relight 0.1; and 1e-6.
BENCHMARK_CAPTURE(BM_LinearSetup, multigrid_agg_build, "multigrid-agg", true)
  ->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearSetup, multigrid_agg_values, "multigrid-agg", false)
  ->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearCold, multigrid_agg_0_05, "multigrid-agg", 0.05)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearCold, multigrid_agg_1e_6, "multigrid-agg", 1e-6)->Apply(LinearSizes);
BENCHMARK_CAPTURE(BM_LinearWarm, multigrid_agg_0_1, "multigrid-agg", 0.1)->Apply(LinearSizes);

} // namespace
