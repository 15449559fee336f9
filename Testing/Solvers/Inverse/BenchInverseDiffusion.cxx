// Benchmarks of the inverse diffusion (Polygrid, Sec. 4) on grid blocks
// of NX x NX x NX/4 voxels (6 tets each), 16 back-lit patterns (4x4), one
// channel. Linked into BenchSolvers (its main):
//   BenchSolvers --benchmark_filter=Inverse
// Arguments: NX = 16, 32, 64 (64 -> the 64x64x16 grid).
//  - BM_InverseForwardPass: one objective evaluation = assemble + factorise
//    + 16 blocked back-solves (the unit of the line search).
//  - BM_InverseGradient: forward pass + adjoint pass (16 more back-solves and
//    the per-element accumulation): the cost of one gradient.
//  - BM_InverseFactorOnly: assemble + factorise (the baseline of the two above).
//  - BM_InversePatternsCG: the same 16 forward solves by Jacobi-CG (the
//    alternative to a factorisation), warm-started from the fluences at
//    parameters 5 % away (what a line search offers), to relative residual
//    1e-8.
#include "ConjugateGradient.h"
#include "DiffusionForwardModel.h"
#include "InverseDiffusion.h"
#include "TetMesh.h"

#include <benchmark/benchmark.h>

#include <map>
#include <memory>

using namespace translucency;

namespace
{

struct InverseProblem
{
  TetMesh Mesh;
  std::unique_ptr<DiffusionForwardModel> Model;
  std::unique_ptr<InverseDiffusion> Inverse;
  std::vector<double> Kappa, Mu;
  std::vector<std::vector<double>> Patterns;
};

InverseProblem& GetInverseProblem(int nx)
{
  static std::map<int, std::unique_ptr<InverseProblem>> cache;
  auto& p = cache[nx];
  if (p)
    return *p;
  p = std::make_unique<InverseProblem>();
  // One BLAS thread, as InverseDiffusion::Run uses per channel thread.
  DiffusionForwardModel::SetBlasThreads(1);
  const int nz = std::max(1, nx / 4);
  const double origin[3] = { 0, 0, 0 }, size[3] = { 0.25 * nx, 0.25 * nx, 0.25 * nz };
  std::vector<double> points;
  std::vector<int> tets, element;
  BuildGridBlock(nx, nx, nz, origin, size, points, tets, element);
  p->Mesh.SetGeometry(points, tets);
  const int numElements = nx * nx * nz;
  p->Model = std::make_unique<DiffusionForwardModel>(
    p->Mesh, element, numElements, std::vector<double>(p->Mesh.GetNumberOfTets(), 1.3));
  std::vector<std::vector<unsigned char>> observed;
  MakeBlockPatterns(points, 4, 4, AcquisitionSetup::Back, 1.0, p->Patterns, observed);
  std::vector<double> kappa3(3 * numElements), mu3(3 * numElements);
  p->Kappa.resize(numElements);
  p->Mu.resize(numElements);
  for (int e = 0; e < numElements; ++e)
  {
    const double m = 0.03 * (1.0 + 0.5 * ((e * 7919) % 13) / 13.0);
    p->Mu[e] = m;
    p->Kappa[e] = 1.0 / (3.0 * (m + 1.2));
    for (int c = 0; c < 3; ++c)
    {
      kappa3[3 * e + c] = p->Kappa[e];
      mu3[3 * e + c] = m;
    }
  }
  const auto radiance = InverseDiffusion::PredictRadiance(*p->Model, kappa3, mu3, p->Patterns);
  p->Inverse = std::make_unique<InverseDiffusion>(*p->Model);
  p->Inverse->SetMeasurements(p->Patterns, radiance, observed);
  // Evaluate away from the truth (otherwise the adjoint sources vanish).
  for (int e = 0; e < numElements; ++e)
  {
    p->Kappa[e] *= 1.1;
    p->Mu[e] *= 0.9;
  }
  return *p;
}

void Counters(benchmark::State& state, const InverseProblem& p)
{
  state.counters["points"] = p.Mesh.GetNumberOfPoints();
  state.counters["elements"] = p.Model->GetNumberOfElements();
}

void BM_InverseFactorOnly(benchmark::State& state)
{
  InverseProblem& p = GetInverseProblem(static_cast<int>(state.range(0)));
  DiffusionForwardModel::Factor factor;
  p.Model->Factorize(p.Kappa.data(), p.Mu.data(), factor); // symbolic analysis, once
  for (auto _ : state)
  {
    p.Model->Factorize(p.Kappa.data(), p.Mu.data(), factor);
  }
  Counters(state, p);
}

void BM_InverseForwardPass(benchmark::State& state)
{
  InverseProblem& p = GetInverseProblem(static_cast<int>(state.range(0)));
  p.Inverse->Objective(0, p.Kappa, p.Mu); // warm-up
  for (auto _ : state)
  {
    benchmark::DoNotOptimize(p.Inverse->Objective(0, p.Kappa, p.Mu));
  }
  Counters(state, p);
}

void BM_InverseGradient(benchmark::State& state)
{
  InverseProblem& p = GetInverseProblem(static_cast<int>(state.range(0)));
  std::vector<double> gk, gm;
  for (auto _ : state)
  {
    benchmark::DoNotOptimize(p.Inverse->Objective(0, p.Kappa, p.Mu, &gk, &gm));
  }
  Counters(state, p);
}

void BM_InversePatternsCG(benchmark::State& state)
{
  InverseProblem& p = GetInverseProblem(static_cast<int>(state.range(0)));
  const Eigen::SparseMatrix<double> m = p.Model->Matrix(p.Kappa.data(), p.Mu.data());
  std::vector<double> near(p.Kappa);
  for (double& k : near)
    k *= 1.05;
  const int n = static_cast<int>(m.rows());
  DiffusionSystem system;
  system.NumberOfUnknowns = n;
  system.RowOffsets.assign(m.outerIndexPtr(), m.outerIndexPtr() + n + 1);
  system.ColumnIndices.assign(m.innerIndexPtr(), m.innerIndexPtr() + m.nonZeros());
  // 15 patterns as 5 solves of 3 "channels" (same matrix in each).
  std::vector<std::array<Eigen::VectorXd, 3>> rhs(5), start(5);
  DiffusionForwardModel::Factor nearFactor;
  p.Model->Factorize(near.data(), p.Mu.data(), nearFactor);
  for (int k = 0; k < 5; ++k)
    for (int c = 0; c < 3; ++c)
    {
      Eigen::VectorXd q(n);
      for (int i = 0; i < n; ++i)
        q[i] = p.Patterns[3 * k + c][3 * i];
      rhs[k][c] = p.Model->Source(q);
      nearFactor.Solve(rhs[k][c], start[k][c]); // the fluence at nearby parameters
    }
  for (int c = 0; c < 3; ++c)
    system.Values[c].assign(m.valuePtr(), m.valuePtr() + m.nonZeros());
  ConjugateGradient cg;
  cg.SetRelTol(1e-8);
  cg.SetMaxIter(20000);
  long long iterations = 0;
  for (auto _ : state)
  {
    iterations = 0;
    for (int k = 0; k < 5; ++k)
    {
      system.RightHandSide = rhs[k];
      std::array<Eigen::VectorXd, 3> x = start[k];
      cg.Solve(system, x, true);
      for (int c = 0; c < 3; ++c)
        iterations += cg.GetNumIterations(c);
    }
  }
  Counters(state, p);
  state.counters["cg_iterations_per_pattern"] = iterations / 15.0;
}

void InverseSizes(benchmark::internal::Benchmark* b)
{
  b->Arg(16)
    ->Arg(32)
    ->Arg(64)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
}

} // namespace

BENCHMARK(BM_InverseFactorOnly)->Apply(InverseSizes);
BENCHMARK(BM_InverseForwardPass)->Apply(InverseSizes);
BENCHMARK(BM_InverseGradient)->Apply(InverseSizes);
BENCHMARK(BM_InversePatternsCG)->Apply(InverseSizes);
