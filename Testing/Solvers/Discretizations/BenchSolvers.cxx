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
#include "DiffusionSolverFactory.h"
#include "DiscreteDivergence.h"
#include "FiniteElement.h"
#include "LightSources.h"
#include "MonteCarlo.h"
#include "QuadGraph.h"
#include "RayCaster.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TetMesh.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <random>

namespace
{

using namespace translucency;
using translucency::testing::MakeProblem;

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

/// The first assembly after a geometry change (a new discretisation object
/// each time: the per-tet geometry is computed and cached, as after a cut or
/// a deformation). Same-run baseline of BM_Assemble, which re-assembles on an
/// unchanged geometry (a material or light change) from the cache.
void BM_AssembleNewGeometry(benchmark::State& state)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  DiffusionSystem system;
  DiscreteDivergence().Assemble(p.Mesh, p.Material, p.Irradiance, system); // allocate once
  for (auto _ : state)
  {
    DiscreteDivergence divergence;
    divergence.Assemble(p.Mesh, p.Material, p.Irradiance, system);
    benchmark::DoNotOptimize(system.Values[2].data());
  }
  SetSizeCounters(state, p);
}

/// The first assembly of a new problem, as a first solve (and
/// `translucency bench --runs 1`) meets it: a new system (its allocation and
/// first touch) and a new discretisation (the per-tet geometry computed and
/// cached) each time; freeing them is not timed. Same-run baselines:
/// BM_Assemble (warm) and BM_AssembleNewGeometry (system kept).
void BM_AssembleCold(benchmark::State& state)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  for (auto _ : state)
  {
    auto system = std::make_unique<DiffusionSystem>();
    auto divergence = std::make_unique<DiscreteDivergence>();
    divergence->Assemble(p.Mesh, p.Material, p.Irradiance, *system);
    benchmark::DoNotOptimize(system->Values[2].data());
    state.PauseTiming();
    system.reset();
    divergence.reset();
    state.ResumeTiming();
  }
  SetSizeCounters(state, p);
}

/// Painting (TransCut Sec. 5.2): about 1 % of the tets, a ball around a point
/// of the top face (a paint stroke), change their mu_a; UpdateTets rebuilds
/// only the rows of their vertices. Same-run baseline: BM_Assemble (full
/// re-assembly) on the same mesh.
void BM_UpdateTets1Percent(benchmark::State& state)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  DiscreteDivergence divergence;
  DiffusionSystem system;
  divergence.Assemble(p.Mesh, p.Material, p.Irradiance, system);
  // The 1 % of tets whose centroids are closest to (10, 10, 20).
  const int numTets = p.Mesh.GetNumberOfTets();
  std::vector<std::pair<double, int>> distance(numTets);
  for (int t = 0; t < numTets; ++t)
  {
    const int* tv = p.Mesh.GetTet(t);
    double d2 = 0.0;
    const double centre[3] = { 10.0, 10.0, 20.0 };
    for (int d = 0; d < 3; ++d)
    {
      const double x = 0.25 * (p.Mesh.GetPoint(tv[0])[d] + p.Mesh.GetPoint(tv[1])[d] +
                                p.Mesh.GetPoint(tv[2])[d] + p.Mesh.GetPoint(tv[3])[d]);
      d2 += (x - centre[d]) * (x - centre[d]);
    }
    distance[t] = { d2, t };
  }
  const int numChanged = numTets / 100;
  std::nth_element(distance.begin(), distance.begin() + numChanged, distance.end());
  std::vector<int> changed(numChanged);
  OpticalProperties material = p.Material;
  for (int k = 0; k < numChanged; ++k)
  {
    changed[k] = distance[k].second;
    material.AbsorptionCoefficient[3 * changed[k]] *= 10.0;
  }
  for (auto _ : state)
  {
    divergence.UpdateTets(p.Mesh, material, p.Irradiance, changed, system);
    benchmark::DoNotOptimize(system.Values[2].data());
  }
  SetSizeCounters(state, p);
  state.counters["changed"] = numChanged;
}

/// The consistent P1 Galerkin assembly ("fem"); same-run baseline:
/// BM_Assemble (the divergence assembly) on the same mesh.
void BM_AssembleFem(benchmark::State& state)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  FiniteElement fem;
  DiffusionSystem system;
  fem.Assemble(p.Mesh, p.Material, p.Irradiance, system); // allocate once
  for (auto _ : state)
  {
    fem.Assemble(p.Mesh, p.Material, p.Irradiance, system);
    benchmark::DoNotOptimize(system.Values[2].data());
  }
  SetSizeCounters(state, p);
  state.counters["boundary_triangles"] = p.Mesh.GetNumberOfBoundaryTriangles();
}

/// A vertex solver through the common interface (assembly + CG to 1e-6, no
/// warm start); counters setup_ms and solve_ms from its SolverReport. The
/// "divergence" case is the same-run baseline of the "fem" case.
void BM_VertexSolver(benchmark::State& state, const char* name)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver(name);
  solver->SetWarmStart(false);
  DiffusionProblem problem = MakeProblem(p.Mesh, p.Material, p.Irradiance);
  std::vector<double> fluence;
  SolverReport report;
  double setup = 0.0, solve = 0.0;
  for (auto _ : state)
  {
    solver->Solve(problem, fluence, report);
    benchmark::DoNotOptimize(fluence.data());
    setup += report.SetupMilliseconds;
    solve += report.SolveMilliseconds;
  }
  SetSizeCounters(state, p);
  state.counters["setup_ms"] = setup / static_cast<double>(state.iterations());
  state.counters["solve_ms"] = solve / static_cast<double>(state.iterations());
  state.counters["iterations"] =
    report.Iterations[0] + report.Iterations[1] + report.Iterations[2];
}

/// The Monte Carlo reference on the same mesh and material, lit from +z by a
/// directional light, 20,000 photons per channel (60,000 in all); arguments
/// (cells, threads). Counters: photons per second and per second per thread
/// (tracing only), setup_ms (walk structure, per-light irradiance, source
/// table), solve_ms. Same-run baseline: BM_VertexSolver/divergence.
void BM_MonteCarlo(benchmark::State& state)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  MonteCarloSolver solver;
  solver.SetNumberOfPhotons(20000);
  solver.SetNumberOfThreads(static_cast<int>(state.range(1)));
  DiffusionProblem problem = MakeProblem(p.Mesh, p.Material, p.Irradiance);
  LightSource light;
  light.Direction = { 0.0, 0.0, -1.0 };
  problem.Lights = { light };
  std::vector<double> fluence;
  SolverReport report;
  double setup = 0.0, solve = 0.0;
  for (auto _ : state)
  {
    solver.Solve(problem, fluence, report);
    benchmark::DoNotOptimize(fluence.data());
    setup += report.SetupMilliseconds;
    solve += report.SolveMilliseconds;
  }
  SetSizeCounters(state, p);
  const double n = static_cast<double>(state.iterations());
  state.counters["setup_ms"] = setup / n;
  state.counters["solve_ms"] = solve / n;
  state.counters["photons_per_second"] =
    static_cast<double>(solver.GetNumberOfPhotonsTraced()) / (solve / n * 1e-3);
  state.counters["photons_per_second_per_thread"] = solver.GetPhotonsPerSecondPerThread();
  long long steps = 0;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    steps += solver.GetPowerBalance(c).Steps;
  }
  state.counters["steps_per_photon"] =
    static_cast<double>(steps) / static_cast<double>(solver.GetNumberOfPhotonsTraced());
}

/// The regular-grid solver (polygrid eq. 8-9) through the common interface,
/// BiCGSTAB to 1e-6, a new solver each time (setup_ms = grid construction +
/// assembly), no warm start. Arguments (cells, multi-level, spacing): spacing
/// 0 = automatic (volume / tets)^(1/3), about one node per tet; 1 = (volume /
/// points)^(1/3), about as many unknowns as the vertex solvers. Same-run
/// baseline: BM_VertexSolver/divergence on the same mesh.
void BM_GridSolver(benchmark::State& state)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  DiffusionProblem problem = MakeProblem(p.Mesh, p.Material, p.Irradiance);
  std::vector<double> fluence;
  SolverReport report;
  double setup = 0.0, solve = 0.0;
  for (auto _ : state)
  {
    std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver("grid");
    solver->SetWarmStart(false);
    solver->SetOptions(SolverOptions{
      { DiffusionOption::MultiLevel, state.range(1) != 0 ? 1.0 : 0.0 },
      { DiffusionOption::GridSpacing,
        state.range(2) == 0 ? 0.0 : std::cbrt(20.0 * 20.0 * 20.0 / p.Mesh.GetNumberOfPoints()) } });
    solver->Solve(problem, fluence, report);
    benchmark::DoNotOptimize(fluence.data());
    setup += report.SetupMilliseconds;
    solve += report.SolveMilliseconds;
  }
  SetSizeCounters(state, p);
  const double n = static_cast<double>(state.iterations());
  state.counters["setup_ms"] = setup / n;
  state.counters["solve_ms"] = solve / n;
  state.counters["unknowns"] = static_cast<double>(report.NumberOfUnknowns);
  state.counters["grid_nnz"] = static_cast<double>(report.NumberOfNonZeros);
  state.counters["memory_MB"] = static_cast<double>(report.MemoryBytes) / 1e6;
  state.counters["iterations"] =
    report.Iterations[0] + report.Iterations[1] + report.Iterations[2];
}

/// QuadGraph finite differences (QuadGraph, eq. 5-6) through the
/// common interface, BiCGSTAB to 1e-6, a new solver each time (setup_ms =
/// graph build + assembly; graph_ms = the graph build alone), no warm start;
/// argument 1 = multi-level initialisation (eq. 10; its coarse levels are
/// part of graph_ms). Same-run baseline: BM_VertexSolver/divergence.
void BM_QuadGraph(benchmark::State& state)
{
  Problem& p = GetProblem(static_cast<int>(state.range(0)));
  DiffusionProblem problem = MakeProblem(p.Mesh, p.Material, p.Irradiance);
  std::vector<double> fluence;
  SolverReport report;
  double setup = 0.0, solve = 0.0, graph = 0.0;
  for (auto _ : state)
  {
    QuadGraphSolver solver;
    solver.SetWarmStart(false);
    solver.SetMultiLevel(state.range(1) != 0);
    solver.Solve(problem, fluence, report);
    benchmark::DoNotOptimize(fluence.data());
    setup += report.SetupMilliseconds;
    solve += report.SolveMilliseconds;
    graph += solver.GetGraphMilliseconds();
  }
  SetSizeCounters(state, p);
  const double n = static_cast<double>(state.iterations());
  state.counters["setup_ms"] = setup / n;
  state.counters["graph_ms"] = graph / n;
  state.counters["solve_ms"] = solve / n;
  state.counters["unknowns"] = static_cast<double>(report.NumberOfUnknowns);
  state.counters["graph_nnz"] = static_cast<double>(report.NumberOfNonZeros);
  state.counters["memory_MB"] = static_cast<double>(report.MemoryBytes) / 1e6;
  state.counters["iterations"] =
    report.Iterations[0] + report.Iterations[1] + report.Iterations[2];
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

/// The scale of issue 31 (is the assembly linear in the tets?): 55 and 118
/// cells per side, 998,250 and 9,857,832 tets (about 2.5 GB for the 10M
/// problem). Run: BenchSolvers --benchmark_filter='scale:'
void ScaleSizes(benchmark::internal::Benchmark* b)
{
  b->ArgName("scale")
    ->Arg(55)
    ->Arg(118)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);
}

BENCHMARK(BM_BuildMesh)->Apply(Sizes);
BENCHMARK(BM_SpMV)->Apply(Sizes);
BENCHMARK(BM_Assemble)->Apply(Sizes);
BENCHMARK(BM_AssembleNewGeometry)->Apply(Sizes);
BENCHMARK(BM_AssembleCold)->Apply(Sizes);
BENCHMARK(BM_SpMV)->Apply(ScaleSizes);
BENCHMARK(BM_Assemble)->Apply(ScaleSizes);
BENCHMARK(BM_AssembleNewGeometry)->Apply(ScaleSizes);
BENCHMARK(BM_AssembleCold)->Apply(ScaleSizes);
BENCHMARK(BM_UpdateTets1Percent)->Apply(Sizes);
BENCHMARK(BM_AssembleFem)->Apply(Sizes);
BENCHMARK_CAPTURE(BM_VertexSolver, divergence, "divergence")
  ->Arg(26)
  ->Arg(55)
  ->Unit(benchmark::kMillisecond)
  ->UseRealTime()
  ->Repetitions(5)
  ->ReportAggregatesOnly(true);
BENCHMARK_CAPTURE(BM_VertexSolver, fem, "fem")
  ->Arg(26)
  ->Arg(55)
  ->Unit(benchmark::kMillisecond)
  ->UseRealTime()
  ->Repetitions(5)
  ->ReportAggregatesOnly(true);
BENCHMARK(BM_MonteCarlo)
  ->Args({ 26, 1 })
  ->Args({ 26, 2 })
  ->Unit(benchmark::kMillisecond)
  ->UseRealTime()
  ->Repetitions(5)
  ->ReportAggregatesOnly(true);
BENCHMARK(BM_GridSolver)
  ->Args({ 26, 0, 0 })
  ->Args({ 26, 1, 0 })
  ->Args({ 26, 0, 1 })
  ->Args({ 55, 0, 0 })
  ->Unit(benchmark::kMillisecond)
  ->UseRealTime()
  ->Repetitions(5)
  ->ReportAggregatesOnly(true);
BENCHMARK(BM_QuadGraph)
  ->Args({ 26, 0 })
  ->Args({ 26, 1 })
  ->Args({ 55, 0 })
  ->Unit(benchmark::kMillisecond)
  ->UseRealTime()
  ->Repetitions(5)
  ->ReportAggregatesOnly(true);
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
