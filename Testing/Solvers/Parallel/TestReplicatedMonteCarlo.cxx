// The Monte Carlo with its photons split over the ranks (issue 32:
// "Monte Carlo splits photons over ranks on a replicated mesh"): every rank
// holds the whole problem, traces every size-th batch, and the batch sums are
// added over the ranks. The reference is independent of that code path: the
// one-process MonteCarloSolver run on each rank by itself (the same seed,
// photons and batches), whose estimates are the same batches added in
// another order. These tests run on MPI_COMM_WORLD: on one rank as
// discovered by ctest and on 2 and 3 ranks through mpiexec
// (Testing/Solvers/CMakeLists.txt, Solvers.ReplicatedMonteCarlo2/3). Every
// rank makes the same calls in the same order (EXPECT, no early return).
#include "DiffusionSolverFactory.h"
#include "DistributedSlabs.h" // Rank, Size
#include "MonteCarlo.h"
#include "ReplicatedMonteCarlo.h"
#include "TestMonteCarloScene.h"

#include <gtest/gtest.h>

#include <mpi.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

using namespace translucency;
using translucency::testing::Rank;
using translucency::testing::Size;

namespace
{

const MPI_Comm World = MPI_COMM_WORLD;

Communicator WorldCommunicator()
{
  return MakeCommunicator(&World);
}

/// Everything a Monte Carlo run hands on.
struct Outputs
{
  bool Solved = false;
  std::vector<double> Fluence, FluenceError, Radiance, RadianceError, TetFluence, Exitance;
  std::vector<DetectorReading> Readings, ReadingErrors;
  std::vector<std::vector<DetectorReading>> Gates;
  std::array<MonteCarloSolver::PowerBalance, NumberOfChannels> Balance{};
  long long Traced = 0;
};

Outputs Trace(MonteCarloSolver& solver, const DiffusionProblem& problem)
{
  Outputs r;
  SolverReport report;
  r.Solved = solver.Solve(problem, r.Fluence, report);
  r.FluenceError = report.FluenceStandardError;
  r.Radiance = report.Radiance;
  r.RadianceError = report.RadianceStandardError;
  r.TetFluence = solver.GetTetFluence();
  r.Exitance = solver.GetExitance();
  r.Readings = solver.GetDetectorReadings();
  r.ReadingErrors = solver.GetDetectorStandardErrors();
  r.Gates = solver.GetGateReadings();
  for (int c = 0; c < NumberOfChannels; ++c)
    r.Balance[c] = solver.GetPowerBalance(c);
  r.Traced = solver.GetNumberOfPhotonsTraced();
  return r;
}

/// |a - b| <= tol max(|a|, |b|) element by element (sums of the same
/// positive batch tallies in another order: round-off only).
void ExpectClose(const std::vector<double>& a, const std::vector<double>& b, double tol,
  const std::string& what)
{
  ASSERT_EQ(a.size(), b.size()) << what;
  std::size_t worst = 0, bad = 0;
  double worstRel = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k)
  {
    const double scale = std::max(std::fabs(a[k]), std::fabs(b[k]));
    const double diff = std::fabs(a[k] - b[k]);
    if (std::isnan(a[k]) != std::isnan(b[k]) || diff > tol * scale)
      ++bad;
    if (scale > 0.0 && diff / scale > worstRel)
    {
      worstRel = diff / scale;
      worst = k;
    }
  }
  EXPECT_EQ(bad, 0u) << what << ": " << bad << " of " << a.size() << " differ; worst at " << worst
                     << ", relative " << worstRel;
}

std::vector<double> Flatten(const std::vector<DetectorReading>& readings)
{
  std::vector<double> v;
  for (const DetectorReading& r : readings)
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      v.push_back(r.Fluence[c]);
      v.push_back(r.Exitance[c]);
    }
  return v;
}

/// The Monte Carlo tests' scene (a directional light, a point source and a
/// pencil beam) with the shadowed uniform light too, two detectors and time
/// gates: every tally the sums carry.
struct Case
{
  translucency::testing::MonteCarloScene Scene;
  std::vector<Detector> Detectors;
  TimeGates Gates;
  DiffusionProblem Problem;

  Case()
  {
    Detectors.resize(2);
    Detectors[0].Position = { 6.0, 5.0, 10.0 };
    Detectors[1].Position = { 10.0, 5.0, 5.0 };
    Detectors[1].Radius = 2.0;
    Gates.Start = 0.0;
    Gates.End = 40.0;
    Gates.Count = 50;
    Problem = Scene.Problem();
    Problem.UniformIrradiance = 0.001;
    Problem.Shadows = true;
  }

  void Configure(MonteCarloSolver& solver, int batches) const
  {
    solver.SetNumberOfPhotons(3000);
    solver.SetNumberOfBatches(batches);
    solver.SetSeed(11);
    solver.SetUniformLightSamples(4);
    solver.SetDetectors(Detectors);
    solver.SetTimeGates(Gates);
  }
};

void ExpectSameRun(const Outputs& shared, const Outputs& alone)
{
  ASSERT_TRUE(shared.Solved);
  ASSERT_TRUE(alone.Solved);
  // The estimates: sums of the same positive tallies in another order.
  ExpectClose(shared.Fluence, alone.Fluence, 1e-12, "Fluence");
  ExpectClose(shared.TetFluence, alone.TetFluence, 1e-12, "tet fluence");
  ExpectClose(shared.Exitance, alone.Exitance, 1e-12, "Exitance");
  ExpectClose(shared.Radiance, alone.Radiance, 1e-12, "Radiance");
  ExpectClose(Flatten(shared.Readings), Flatten(alone.Readings), 1e-12, "detectors");
  ASSERT_EQ(shared.Gates.size(), alone.Gates.size());
  for (std::size_t g = 0; g < shared.Gates.size(); ++g)
    ExpectClose(Flatten(shared.Gates[g]), Flatten(alone.Gates[g]), 1e-12,
      "gate " + std::to_string(g));
  // The standard errors: sqrt(N A2 - A1^2) / ..., a difference of sums that
  // cancels to the batch spread (a few % of the mean here), which scales the
  // round-off of the sums by up to (mean / spread)^2 ~ 1e3.
  ExpectClose(shared.FluenceError, alone.FluenceError, 1e-9, "FluenceStandardError");
  ExpectClose(shared.RadianceError, alone.RadianceError, 1e-9, "RadianceStandardError");
  ExpectClose(Flatten(shared.ReadingErrors), Flatten(alone.ReadingErrors), 1e-9,
    "detector standard errors");
  // The bookkeeping: counts exactly, powers to round-off.
  EXPECT_EQ(shared.Traced, alone.Traced);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    SCOPED_TRACE(c);
    const auto& a = shared.Balance[c];
    const auto& b = alone.Balance[c];
    EXPECT_EQ(a.Photons, b.Photons);
    EXPECT_EQ(a.Steps, b.Steps);
    EXPECT_EQ(a.LostPhotons, b.LostPhotons);
    EXPECT_NEAR(a.Injected, b.Injected, 1e-12 * b.Injected);
    EXPECT_NEAR(a.Absorbed, b.Absorbed, 1e-12 * b.Injected);
    EXPECT_NEAR(a.Escaped, b.Escaped, 1e-12 * b.Injected);
    EXPECT_NEAR(a.RouletteGain, b.RouletteGain, 1e-12 * b.Injected);
  }
}

} // namespace

TEST(ReplicatedMonteCarlo, EqualsOneProcess)
{
  const Case scene;
  // 7 batches: uneven shares on 2 and 3 ranks (4/3, 3/2/2).
  MonteCarloSolver alone;
  scene.Configure(alone, 7);
  const Outputs reference = Trace(alone, scene.Problem);

  ReplicatedMonteCarloSolver shared;
  shared.SetCommunicator(WorldCommunicator());
  scene.Configure(shared, 7);
  const Outputs run = Trace(shared, scene.Problem);
  ExpectSameRun(run, reference);
  EXPECT_EQ(reference.Traced, 3 * 3000); // three lit channels

  // Time-resolved through the interface: the gates and the CW fluence.
  TimeResolvedResult a, b;
  SolverReport ra, rb;
  ASSERT_TRUE(shared.SolveTimeResolved(scene.Problem, scene.Gates, scene.Detectors, {}, a, ra));
  ASSERT_TRUE(alone.SolveTimeResolved(scene.Problem, scene.Gates, scene.Detectors, {}, b, rb));
  ExpectClose(a.IntegratedFluence, b.IntegratedFluence, 1e-12, "time-resolved fluence");
  ASSERT_EQ(a.Readings.size(), b.Readings.size());
  for (std::size_t g = 0; g < a.Readings.size(); ++g)
    ExpectClose(Flatten(a.Readings[g]), Flatten(b.Readings[g]), 1e-12, "TPSF gate");
}

TEST(ReplicatedMonteCarlo, MoreRanksThanBatches)
{
  // 2 batches: on 3 ranks, rank 2 traces nothing and still adds its zeros.
  const Case scene;
  MonteCarloSolver alone;
  scene.Configure(alone, 2);
  ReplicatedMonteCarloSolver shared;
  shared.SetCommunicator(WorldCommunicator());
  scene.Configure(shared, 2);
  const Outputs run = Trace(shared, scene.Problem);
  ExpectSameRun(run, Trace(alone, scene.Problem));
  if (Rank() >= 2)
    EXPECT_EQ(shared.GetNumberOfThreadsUsed(), 0);
}

TEST(ReplicatedMonteCarlo, AnAbortOnOneRankIsEveryRanks)
{
  // The last rank's progress callback asks to abort half-way (the others'
  // never do): every rank returns false (no rank left waiting in a sum),
  // the outputs stay unchanged, and the next run on every rank is whole.
  const Case scene;
  ReplicatedMonteCarloSolver shared;
  shared.SetCommunicator(WorldCommunicator());
  scene.Configure(shared, 8);
  const bool aborter = Rank() == Size() - 1;
  int calls = 0;
  shared.SetProgressCallback([&](double f) { return !aborter || ++calls < 3 || f < 0.0; });
  std::vector<double> untouched = { 42.0 };
  SolverReport report;
  EXPECT_FALSE(shared.Solve(scene.Problem, untouched, report));
  EXPECT_EQ(untouched, std::vector<double>{ 42.0 });

  // An abort before the tracing (at 0 %) too.
  shared.SetProgressCallback([&](double) { return !aborter; });
  EXPECT_FALSE(shared.Solve(scene.Problem, untouched, report));
  EXPECT_EQ(untouched, std::vector<double>{ 42.0 });

  shared.SetProgressCallback(nullptr);
  MonteCarloSolver alone;
  scene.Configure(alone, 8);
  ExpectSameRun(Trace(shared, scene.Problem), Trace(alone, scene.Problem));
}

TEST(ReplicatedMonteCarlo, IsTheRegistrysReplicatedVariant)
{
  std::unique_ptr<DiffusionSolver> solver = CreateDistributedDiffusionSolver("montecarlo");
  EXPECT_NE(dynamic_cast<ReplicatedMonteCarloSolver*>(solver.get()), nullptr);
  EXPECT_EQ(solver->GetName(), "montecarlo");
  EXPECT_TRUE(GetDiffusionSolverRegistry().Get("montecarlo").Properties.Replicated);
  // The in-process solver still refuses a communicator.
  MonteCarloSolver alone;
  EXPECT_THROW(alone.SetCommunicator(WorldCommunicator()), Error);
}
