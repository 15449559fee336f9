// The distributed beam kept across paints (issue 32): DistributedCollimatedSource
// keeps the gathered surface, the rays and the loads as the serial
// CollimatedSourceCache does. These tests run on MPI_COMM_WORLD: on one rank
// as discovered by ctest (an MPI singleton) and on 2 and 3 ranks through
// mpiexec (Testing/Solvers/CMakeLists.txt, Solvers.DistributedBeamCache2/3).
// Every rank runs the same steps in the same order (the calls are
// collective) and checks with EXPECT (no early return before a collective).
//
// The independent references: a fresh DistributedCollimatedSource of the
// same arguments (nothing kept, and its surface gathered with a solver's
// numbering: Load and E_c bit for bit on this rank's points) and the serial CollimatedSourceCache on the whole mesh (E_c at
// every point and Load summed over the ranks, to rounding: the loads of a
// point shared by ranks are summed in another order, the gathered surface's
// triangles have another vertex order); and what each says it did.
#include "CollimatedSource.h"
#include "DiffusionSolverFactory.h"
#include "DistributedCollimatedSource.h"
#include "DistributedSlabs.h"
#include "DistributedVertexSolver.h"
#include "HypreSolver.h"
#include "TestProblems.h"
#include "TetMesh.h"

#include <gtest/gtest.h>

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>

using namespace translucency;
using translucency::testing::MakeScene;
using translucency::testing::PieceMaterial;
using translucency::testing::Rank;
using translucency::testing::RelativeDifference;
using translucency::testing::Scene;
using translucency::testing::Size;
using translucency::testing::TetsNear;

namespace
{

double Relative(double a, double b)
{
  return std::abs(a - b) / std::max(std::abs(b), 1e-300);
}

/// One step: the kept distributed beam against a fresh one (bit for bit)
/// and against the serial cache on the whole mesh (to rounding), and what
/// both caches say they did.
void ExpectStep(DistributedCollimatedSource& kept, CollimatedSourceCache& serial, const Scene& s,
  const OpticalProperties& whole, const std::vector<LightSource>& lights, bool shadows,
  const std::string& update, const std::string& what)
{
  SCOPED_TRACE(what);
  const OpticalProperties material = PieceMaterial(s, whole);
  CollimatedSource cached, fresh;
  kept.Compute(MPI_COMM_WORLD, s.Piece.get(), s.Keys, s.Used, material, lights, shadows, cached);
  // The fresh one with the numbering and boundary count a solver hands it
  // (GatherBoundarySurface does not build them again), the kept one
  // without: the same surface either way.
  DistributedNumbering numbering;
  numbering.Build(MPI_COMM_WORLD, s.Keys, s.Used);
  std::vector<int> rows;
  if (s.Piece)
  {
    for (const int p : s.Piece->GetBoundaryTriangles())
      rows.push_back(numbering.GetRow(p));
  }
  std::vector<char> physical;
  for (const int count : CountSharedTriangles(MPI_COMM_WORLD, rows))
    physical.push_back(count == 1 ? 1 : 0);
  DistributedCollimatedSource anew;
  anew.Compute(MPI_COMM_WORLD, s.Piece.get(), s.Keys, s.Used, material, lights, shadows, fresh,
    &numbering, &physical);
  const CollimatedSource reference = serial.Compute(s.Whole, whole, lights, shadows);

  // What each did: the same words, the same on every rank.
  EXPECT_EQ(std::string(serial.GetLastUpdate()), update);
  EXPECT_EQ(std::string(kept.GetLastUpdate()), update);
  EXPECT_EQ(std::string(anew.GetLastUpdate()), "full");
  EXPECT_LE(kept.GetTetsIntegrated(), anew.GetTetsIntegrated());
  if (Rank() == 0)
  {
    std::cout << what << ": serial " << serial.GetLastUpdate() << " " << serial.GetTetsIntegrated()
              << " tets, distributed " << kept.GetLastUpdate() << " " << kept.GetTetsIntegrated()
              << " of " << anew.GetTetsIntegrated() << " tets"
              << (kept.GetSurfaceGathered() ? ", surface gathered"
                   : kept.GetSurfaceValuesGathered() ? ", surface values gathered" : "")
              << "\n";
  }

  // Kept against fresh: bit for bit at this rank's points.
  EXPECT_EQ(cached.Fluence, fresh.Fluence);
  EXPECT_EQ(cached.Load, fresh.Load);
  ASSERT_EQ(cached.Beams.size(), fresh.Beams.size());
  for (std::size_t b = 0; b < fresh.Beams.size(); ++b)
  {
    EXPECT_EQ(cached.Beams[b].Fluence, fresh.Beams[b].Fluence) << "beam " << b;
    EXPECT_EQ(cached.Beams[b].OpticalPath, fresh.Beams[b].OpticalPath) << "beam " << b;
  }
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(cached.Entering[c], fresh.Entering[c]) << "channel " << c;
    EXPECT_LT(Relative(cached.Scattered[c], fresh.Scattered[c]), 1e-13) << "channel " << c;
    EXPECT_LT(Relative(cached.Absorbed[c], fresh.Absorbed[c]), 1e-13) << "channel " << c;
  }

  // Against the serial cache: E_c at this rank's points, Load summed over
  // the ranks at every point, the power sums.
  std::vector<double> fluence, serialFluence;
  std::vector<double> load(reference.Load.size(), 0.0);
  for (std::size_t i = 0; i < s.Points.size(); ++i)
  {
    const std::size_t p = static_cast<std::size_t>(s.Points[i]);
    for (int c = 0; c < 3; ++c)
    {
      fluence.push_back(cached.Fluence[3 * i + c]);
      serialFluence.push_back(reference.Fluence[3 * p + c]);
      load[3 * p + c] += cached.Load[3 * i + c];
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, load.data(), static_cast<int>(load.size()), MPI_DOUBLE, MPI_SUM,
    MPI_COMM_WORLD);
  const double fluenceDiff = fluence.empty() ? 0.0 : RelativeDifference(fluence, serialFluence);
  const double loadDiff = RelativeDifference(load, reference.Load);
  if (Rank() == 0)
    std::cout << "  vs serial: E_c " << fluenceDiff << ", Load " << loadDiff << "\n";
  EXPECT_LT(fluenceDiff, 1e-13);
  EXPECT_LT(loadDiff, 1e-13);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_LT(Relative(cached.Entering[c], reference.Entering[c]), 1e-12) << "channel " << c;
    EXPECT_LT(Relative(cached.Scattered[c], reference.Scattered[c]), 1e-12) << "channel " << c;
    EXPECT_LT(Relative(cached.Absorbed[c], reference.Absorbed[c]), 1e-12) << "channel " << c;
  }
}

/// The paint, relight and power steps of the serial cache's test
/// (TestCollimatedBeam, CollimatedSourceCache) on a partition over `ranks`.
void RunSteps(int ranks)
{
  Scene s = MakeScene(ranks);
  OpticalProperties whole = s.Material;
  std::vector<LightSource> lights = { DirectionalLight({ 0.13, -1.0, -0.77 }, { 1.0, 0.7, 0.4 }),
    DirectionalLight({ -0.6, -0.2, 0.4 }, { 2.5, 1.0, 0.5 }) };
  DistributedCollimatedSource kept;
  CollimatedSourceCache serial;
  ExpectStep(kept, serial, s, whole, lights, true, "full", "first call");
  ExpectStep(kept, serial, s, whole, lights, true, "kept", "the same arguments");
  EXPECT_EQ(kept.GetTetsIntegrated(), 0);
  EXPECT_FALSE(kept.GetSurfaceGathered());
  EXPECT_FALSE(kept.GetSurfaceValuesGathered());

  // An interior stroke: E_c and the surface unchanged, the stroke's tets and
  // their ring integrated again (on the ranks that hold them).
  const std::vector<int> interior = TetsNear(s.Whole, { 2.4, 2.6, 2.5 }, 0.8);
  ASSERT_GT(interior.size(), 20u);
  for (const int t : interior)
  {
    for (int c = 0; c < 3; ++c)
      whole.AbsorptionCoefficient[3 * static_cast<std::size_t>(t) + c] *= 5.0;
  }
  ExpectStep(kept, serial, s, whole, lights, true, "loads", "interior stroke");
  EXPECT_FALSE(kept.GetSurfaceGathered());
  EXPECT_FALSE(kept.GetSurfaceValuesGathered());
  EXPECT_LT(kept.GetTetsIntegrated(), s.Whole.GetNumberOfTets() / 4);

  // A stroke through the lit surface with a new index: the surface's values
  // gathered again (not its geometry), E_c changes behind it.
  const std::vector<int> surface = TetsNear(s.Whole, { 2.5, 5.0, 5.0 }, 0.8);
  for (const int t : surface)
  {
    whole.ReducedScatteringCoefficient[3 * static_cast<std::size_t>(t) + 1] *= 3.0;
    whole.RefractiveIndex[static_cast<std::size_t>(t)] = 1.45;
  }
  ExpectStep(kept, serial, s, whole, lights, true, "loads", "surface stroke, new index");
  EXPECT_FALSE(kept.GetSurfaceGathered());
  EXPECT_TRUE(kept.GetSurfaceValuesGathered());
  EXPECT_LT(kept.GetTetsIntegrated(), s.Whole.GetNumberOfTets());

  // The stroke undone.
  for (const int t : surface)
  {
    whole.ReducedScatteringCoefficient[3 * static_cast<std::size_t>(t) + 1] /= 3.0;
    whole.RefractiveIndex[static_cast<std::size_t>(t)] =
      s.Material.RefractiveIndex[static_cast<std::size_t>(t)];
  }
  ExpectStep(kept, serial, s, whole, lights, true, "loads", "surface stroke undone");

  // A brighter light: E_c everywhere (every tet, the rays kept); a turned
  // light and the shadow flag cast new rays.
  lights[1].Power = { 2.0, 3.0, 4.0 };
  ExpectStep(kept, serial, s, whole, lights, true, "loads", "brighter light");
  EXPECT_FALSE(kept.GetSurfaceGathered());
  lights[0].Direction = { 0.0, -1.0, -0.9 };
  ExpectStep(kept, serial, s, whole, lights, true, "full", "turned light");
  EXPECT_FALSE(kept.GetSurfaceGathered());
  ExpectStep(kept, serial, s, whole, lights, false, "full", "shadows off");
  EXPECT_GT(kept.GetMemoryBytes(), 0u);
  kept.Clear();
  serial.Clear();
  ExpectStep(kept, serial, s, whole, lights, false, "full", "after Clear");
  EXPECT_TRUE(kept.GetSurfaceGathered());
}

} // namespace

TEST(DistributedBeamCache, PaintsRelightsAndPowersEqualAFreshSourceAndSerial)
{
  RunSteps(Size());
}

// The same with the last rank's piece empty (it takes part in every
// collective, with no tets and no loads).
TEST(DistributedBeamCache, AnEmptyRankTakesPart)
{
  if (Size() < 2)
  {
    GTEST_SKIP() << "needs 2 or more ranks";
  }
  RunSteps(Size() - 1);
}

// Through the distributed solver: a paint reports "loads" as the serial
// solver does (SolverReport::Collimated, which Solve Diffusion's
// GetLastCollimatedUpdate() shows), and its beam and fluence equal a fresh
// distributed solver's.
TEST(DistributedBeamCache, TheSolverReportsThePaintAsTheSerialSolver)
{
  Scene s = MakeScene(Size());
  OpticalProperties whole = s.Material;
  const Communicator world = MakeCommunicator(GetWorldCommunicator());
  DistributedVertexSolver kept("divergence");
  kept.SetCommunicator(world);
  kept.SetRelTol(1e-12);
  const std::unique_ptr<DiffusionSolver> serial = CreateDiffusionSolver("divergence");
  serial->SetRelTol(1e-12);
  const std::vector<double> q(3 * s.Points.size(), 0.0);
  const std::vector<double> serialQ(3 * static_cast<std::size_t>(s.Whole.GetNumberOfPoints()), 0.0);
  const std::vector<LightSource> lights = { DirectionalLight(
    { 0.13, -1.0, -0.77 }, { 1.0, 0.7, 0.4 }) };
  const std::vector<int> interior = TetsNear(s.Whole, { 2.4, 2.6, 2.5 }, 0.8);
  for (const std::string step : { "cold", "paint" })
  {
    SCOPED_TRACE(step);
    if (step == "paint")
    {
      for (const int t : interior)
      {
        for (int c = 0; c < 3; ++c)
          whole.AbsorptionCoefficient[3 * static_cast<std::size_t>(t) + c] *= 5.0;
      }
    }
    const OpticalProperties material = PieceMaterial(s, whole);
    DiffusionProblem problem;
    problem.Mesh = s.Piece.get();
    problem.Material = &material;
    problem.Irradiance = &q;
    problem.PointKeys = &s.Keys;
    problem.Lights = lights;
    problem.Shadows = true;
    problem.Collimated = CollimatedModel::Extended;
    DiffusionProblem serialProblem = problem;
    serialProblem.Mesh = &s.Whole;
    serialProblem.Material = &whole;
    serialProblem.Irradiance = &serialQ;
    serialProblem.PointKeys = nullptr;
    std::vector<double> fluence, freshFluence, serialFluence;
    SolverReport report, freshReport, serialReport;
    ASSERT_TRUE(kept.Solve(problem, fluence, report));
    DistributedVertexSolver fresh("divergence");
    fresh.SetCommunicator(world);
    fresh.SetRelTol(1e-12);
    ASSERT_TRUE(fresh.Solve(problem, freshFluence, freshReport));
    ASSERT_TRUE(serial->Solve(serialProblem, serialFluence, serialReport));
    EXPECT_EQ(report.Collimated, serialReport.Collimated);
    EXPECT_EQ(report.Collimated, step == "cold" ? "full" : "loads");
    EXPECT_EQ(freshReport.Collimated, "full");
    EXPECT_EQ(report.CollimatedFluence, freshReport.CollimatedFluence);
    // Both solved to RelTol 1e-12 (the kept one warm-started).
    EXPECT_LT(RelativeDifference(fluence, freshFluence), 1e-9);
    std::vector<double> atPoints;
    for (const int p : s.Points)
    {
      for (int c = 0; c < 3; ++c)
        atPoints.push_back(serialFluence[3 * static_cast<std::size_t>(p) + c]);
    }
    if (!fluence.empty())
      EXPECT_LT(RelativeDifference(fluence, atPoints), 1e-8);
  }
}
