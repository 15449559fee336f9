// The distributed paint re-assembles only the changed rows (issue 32):
// DistributedVertexSolver's changed-rows update (SetChangedRowsUpdate, on by
// default) against the same solver re-assembling its whole piece
// (SetChangedRowsUpdate(false), the same history: the same kept
// hierarchies) and against a fresh solver (a cold, full assembly) of the
// painted material. These tests run on MPI_COMM_WORLD: on one rank as
// discovered by ctest (an MPI singleton) and on 2 and 3 ranks through
// mpiexec (Testing/Solvers/CMakeLists.txt, Solvers.DistributedPaintRows2/3).
// Every rank runs the same steps in the same order (the calls are
// collective) and checks with EXPECT (no early return before a collective).
//
// What must hold after every stroke: the owned rows of the three matrices
// equal the fresh solver's bit for bit (the rows are summed in the order of
// a full assembly) and the whole re-assembly's; the fluence equals the
// whole re-assembly's bit for bit (the same matrices under the same kept
// hierarchies) and the fresh solve's to 1e-10 (both to RelTol 1e-12).
#include "DistributedSlabs.h"
#include "DistributedVertexSolver.h"
#include "HypreSolver.h"
#include "TestProblems.h"

#include <gtest/gtest.h>

#include <mpi.h>

#include <cstring>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

using namespace translucency;
using translucency::testing::MakeScene;
using translucency::testing::PieceMaterial;
using translucency::testing::PiecePoints;
using translucency::testing::Rank;
using translucency::testing::RelativeDifference;
using translucency::testing::Scene;
using translucency::testing::Size;
using translucency::testing::TetsNear;

namespace
{

long long SumOverRanks(long long mine)
{
  long long all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  return all;
}

/// Channel c's owned rows of `a` and `b`: the same pattern, values bit for bit.
void ExpectSameMatrices(const DistributedVertexSolver& a, const DistributedVertexSolver& b,
  const std::string& what)
{
  SCOPED_TRACE(what);
  EXPECT_EQ(a.GetOwnedRowOffsets(), b.GetOwnedRowOffsets());
  EXPECT_EQ(a.GetOwnedColumns(), b.GetOwnedColumns());
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    const std::vector<double>& x = a.GetOwnedValues(c);
    const std::vector<double>& y = b.GetOwnedValues(c);
    ASSERT_EQ(x.size(), y.size()) << "channel " << c;
    std::size_t differ = 0;
    for (std::size_t k = 0; k < x.size(); ++k)
      differ += std::memcmp(&x[k], &y[k], sizeof(double)) != 0 ? 1 : 0;
    EXPECT_EQ(differ, 0u) << "channel " << c << ": " << differ << " of " << x.size()
                          << " owned entries differ, relative " << RelativeDifference(x, y);
  }
}

/// A stroke: what it changes in the whole mesh's material.
struct Stroke
{
  std::string What;
  std::function<void(const Scene&, OpticalProperties&)> Paint;
};

/// mu_a x `factor` in every channel of the tets near `centre`.
void ScaleAbsorption(const Scene& s, OpticalProperties& m, const std::array<double, 3>& centre,
  double radius, double factor)
{
  for (const int t : TetsNear(s.Whole, centre, radius))
  {
    for (int c = 0; c < 3; ++c)
      m.AbsorptionCoefficient[3 * static_cast<std::size_t>(t) + c] *= factor;
  }
}

/// The strokes of every run, in order: inside a rank and across the slab
/// boundaries of 2 and 3 ranks, through the boundary with a new index (the
/// Robin terms: the divergence's boundary measures are summed over the
/// ranks at the owner), one channel only, undone, extreme, and one beyond
/// MaximumChangedFraction (the whole piece assembled again).
std::vector<Stroke> Strokes()
{
  std::vector<Stroke> strokes;
  strokes.push_back({ "interior, across x = 2.5 (2 ranks' boundary)",
    [](const Scene& s, OpticalProperties& m) { ScaleAbsorption(s, m, { 2.5, 2.6, 2.4 }, 0.8, 5.0); } });
  strokes.push_back({ "across x = 5/3 (3 ranks' boundary)",
    [](const Scene& s, OpticalProperties& m) { ScaleAbsorption(s, m, { 5.0 / 3.0, 2.0, 3.0 }, 0.7, 5.0); } });
  // Through the top face at every slab boundary of 2 and 3 ranks: sigma_s'
  // of one channel and eta.
  const auto surface = [](const Scene& s, OpticalProperties& m, bool undo) {
    for (const double x : { 5.0 / 3.0, 2.5, 10.0 / 3.0 })
    {
      for (const int t : TetsNear(s.Whole, { x, 2.5, 5.0 }, 0.7))
      {
        const std::size_t k = static_cast<std::size_t>(t);
        m.ReducedScatteringCoefficient[3 * k + 1] = undo ? s.Material.ReducedScatteringCoefficient[3 * k + 1]
                                                         : 3.0 * s.Material.ReducedScatteringCoefficient[3 * k + 1];
        m.RefractiveIndex[k] = undo ? s.Material.RefractiveIndex[k] : 1.45;
      }
    }
  };
  strokes.push_back({ "surface, across every boundary, new index",
    [surface](const Scene& s, OpticalProperties& m) { surface(s, m, false); } });
  strokes.push_back({ "one channel's mu_a",
    [](const Scene& s, OpticalProperties& m) {
      for (const int t : TetsNear(s.Whole, { 1.0, 1.0, 1.0 }, 0.8))
        m.AbsorptionCoefficient[3 * static_cast<std::size_t>(t) + 2] *= 2.0;
    } });
  strokes.push_back({ "surface stroke undone",
    [surface](const Scene& s, OpticalProperties& m) { surface(s, m, true); } });
  strokes.push_back({ "extreme: mu_a x 1000",
    [](const Scene& s, OpticalProperties& m) { ScaleAbsorption(s, m, { 3.5, 1.5, 1.5 }, 0.9, 1000.0); } });
  strokes.push_back({ "a third of the tets (beyond MaximumChangedFraction)",
    [](const Scene& s, OpticalProperties& m) { ScaleAbsorption(s, m, { 2.5, 2.5, 2.5 }, 2.2, 1.5); } });
  return strokes;
}

/// Tets of the whole mesh whose coefficients differ between a and b.
long long ChangedTets(const OpticalProperties& a, const OpticalProperties& b)
{
  long long n = 0;
  for (std::size_t t = 0; t < a.RefractiveIndex.size(); ++t)
  {
    n += std::memcmp(&a.AbsorptionCoefficient[3 * t], &b.AbsorptionCoefficient[3 * t], 3 * sizeof(double)) != 0 ||
        std::memcmp(&a.ReducedScatteringCoefficient[3 * t], &b.ReducedScatteringCoefficient[3 * t],
          3 * sizeof(double)) != 0 ||
        a.RefractiveIndex[t] != b.RefractiveIndex[t]
      ? 1
      : 0;
  }
  return n;
}

/// The strokes on a partition over `ranks` ranks (the others empty); with
/// `beam` the extended-moments collimated model of a directional light (its
/// beam kept across the strokes, and the Robin terms of the moments rule).
void RunStrokes(
  int ranks, const std::string& discretization, const std::string& linear, bool beam = false)
{
  SCOPED_TRACE(discretization + " " + (linear.empty() ? "(default linear solver)" : linear) + ", " +
    std::to_string(ranks) + " ranks with tets" + (beam ? ", extended-moments beam" : ""));
  const Scene s = MakeScene(ranks);
  OpticalProperties whole = s.Material;
  const std::vector<double> q = PiecePoints(s, translucency::testing::RandomIrradiance(s.Whole, 41));
  const Communicator world = MakeCommunicator(GetWorldCommunicator());
  auto configure = [&](DistributedVertexSolver& solver) {
    solver.SetCommunicator(world);
    solver.SetRelTol(1e-12);
    solver.SetMaxIter(500);
    if (!linear.empty())
      solver.SetLinearSolver(linear);
  };
  // `hinted` is told each stroke's changed tets of this rank's piece
  // (SetChangedTets: the promise DiffusionFrontEnd makes for its kept
  // material) instead of comparing and validating the whole material.
  DistributedVertexSolver rows(discretization), values(discretization), hinted(discretization);
  configure(rows);
  configure(values);
  configure(hinted);
  values.SetChangedRowsUpdate(false);
  EXPECT_TRUE(rows.GetChangedRowsUpdate());

  std::vector<Stroke> strokes = Strokes();
  strokes.insert(strokes.begin(), { "cold", [](const Scene&, OpticalProperties&) {} });
  for (std::size_t k = 0; k < strokes.size(); ++k)
  {
    const Stroke& stroke = strokes[k];
    SCOPED_TRACE(stroke.What);
    const OpticalProperties before = whole;
    stroke.Paint(s, whole);
    const long long changed = ChangedTets(before, whole);
    const OpticalProperties material = PieceMaterial(s, whole);
    const OpticalProperties pieceBefore = PieceMaterial(s, before);
    std::vector<int> pieceChanged;
    for (std::size_t t = 0; t < material.RefractiveIndex.size(); ++t)
    {
      if (std::memcmp(&material.AbsorptionCoefficient[3 * t], &pieceBefore.AbsorptionCoefficient[3 * t],
            3 * sizeof(double)) != 0 ||
        std::memcmp(&material.ReducedScatteringCoefficient[3 * t],
          &pieceBefore.ReducedScatteringCoefficient[3 * t], 3 * sizeof(double)) != 0 ||
        material.RefractiveIndex[t] != pieceBefore.RefractiveIndex[t])
        pieceChanged.push_back(static_cast<int>(t));
    }
    DiffusionProblem problem;
    problem.Mesh = s.Piece.get();
    problem.Material = &material;
    problem.Irradiance = &q;
    problem.PointKeys = &s.Keys;
    if (beam)
    {
      problem.Lights = { DirectionalLight({ 0.13, -1.0, -0.77 }, { 1.0, 0.7, 0.4 }) };
      problem.Shadows = true;
      problem.Collimated = CollimatedModel::ExtendedMoments;
    }
    std::vector<double> fluence, wholeFluence, freshFluence;
    SolverReport report, wholeReport, freshReport;
    ASSERT_TRUE(rows.Solve(problem, fluence, report));
    ASSERT_TRUE(values.Solve(problem, wholeFluence, wholeReport));
    std::vector<double> hintedFluence;
    SolverReport hintedReport;
    hinted.SetChangedTets(pieceChanged); // (the cold solve: no kept material, ignored)
    ASSERT_TRUE(hinted.Solve(problem, hintedFluence, hintedReport));
    DistributedVertexSolver fresh(discretization);
    configure(fresh);
    ASSERT_TRUE(fresh.Solve(problem, freshFluence, freshReport));

    // What ran: the changed rows for a stroke within the fraction, on every
    // rank (the changed tets counted over the ranks), the whole piece else.
    const bool within = k > 0 &&
      static_cast<double>(changed) <= rows.GetMaximumChangedFraction() * s.Whole.GetNumberOfTets();
    if (k > 0)
      ASSERT_GT(changed, 0);
    if (Rank() == 0)
    {
      std::cout << stroke.What << ": " << changed << " of " << s.Whole.GetNumberOfTets()
                << " tets changed, owned rows written on rank 0 " << rows.GetNumberOfChangedRows()
                << ", set-up '" << report.LinearSetup << "' against '" << wholeReport.LinearSetup
                << "', iterations " << report.Iterations[0] << " " << report.Iterations[1] << " "
                << report.Iterations[2] << (report.Resolved ? " (re-solved)" : "") << "\n";
    }
    if (within)
    {
      EXPECT_EQ(SumOverRanks(rows.GetNumberOfChangedTets()), changed);
      EXPECT_EQ(report.Assembly, "values-only");
      if (!report.Resolved)
        EXPECT_EQ(report.LinearSetup.rfind("rows (", 0), 0u) << report.LinearSetup;
      if (!wholeReport.Resolved)
        EXPECT_EQ(wholeReport.LinearSetup.rfind("values (", 0), 0u) << wholeReport.LinearSetup;
      EXPECT_GT(SumOverRanks(rows.GetNumberOfChangedRows()), 0);
    }
    else
    {
      EXPECT_EQ(rows.GetNumberOfChangedTets(), -1);
    }
    EXPECT_EQ(values.GetNumberOfChangedTets(), -1);
    EXPECT_EQ(hinted.GetNumberOfChangedTets(), rows.GetNumberOfChangedTets());
    EXPECT_EQ(hintedReport.Assembly, report.Assembly);
    EXPECT_EQ(hintedReport.LinearSetup, report.LinearSetup);
    EXPECT_EQ(report.Resolved, wholeReport.Resolved);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      EXPECT_LE(report.Residual[c], 1e-12) << "channel " << c;
      EXPECT_EQ(report.Iterations[c], wholeReport.Iterations[c]) << "channel " << c;
    }

    // The matrices: bit for bit a full assembly's.
    ExpectSameMatrices(rows, fresh, "changed rows against a fresh solver");
    ExpectSameMatrices(rows, values, "changed rows against the whole re-assembly");
    // The fluence: the whole re-assembly's bit for bit (the same matrices
    // under the same kept hierarchies), the fresh solve's to the tolerance.
    EXPECT_EQ(fluence, wholeFluence);
    EXPECT_EQ(hintedFluence, fluence);
    ExpectSameMatrices(hinted, rows, "told the changed tets against comparing");
    const double difference = fluence.empty() ? 0.0 : RelativeDifference(fluence, freshFluence);
    EXPECT_LT(difference, 1e-10);
  }
}

} // namespace

TEST(DistributedPaintRows, EqualAWholeReassemblyAndAFreshSolve)
{
  for (const std::string discretization : { "divergence", "fem" })
    RunStrokes(Size(), discretization, "");
}

// The aggregation Schwarz solver (its UpdateRows: the changed rows into the
// hypre matrix, the block hierarchy's values on every level) gets the same
// matrices.
TEST(DistributedPaintRows, WithTheAggregationSolver)
{
  RunStrokes(Size(), "divergence", "cg/aggregation");
}

// Under the extended-moments model (the default lights' in Solve Diffusion):
// the kept beam and the moments rule's Robin terms, whose boundary
// measures and coefficients are kept while no eta changes.
TEST(DistributedPaintRows, UnderTheExtendedMomentsModel)
{
  RunStrokes(Size(), "divergence", "", true);
}

// SetChangedTets' promise skips the comparison and the validation of the
// rest, not of the promised tets: an invalid value there is refused on every
// rank with the message of a full validation (the lowest invalid tet), and
// the next solve, told nothing, compares and works.
TEST(DistributedPaintRows, ThePromisedTetsAreValidated)
{
  const Scene s = MakeScene(Size());
  const std::vector<double> q = PiecePoints(s, translucency::testing::RandomIrradiance(s.Whole, 41));
  DistributedVertexSolver solver("divergence");
  solver.SetCommunicator(MakeCommunicator(GetWorldCommunicator()));
  solver.SetRelTol(1e-10);
  OpticalProperties material = PieceMaterial(s, s.Material);
  DiffusionProblem problem;
  problem.Mesh = s.Piece.get();
  problem.Material = &material;
  problem.Irradiance = &q;
  problem.PointKeys = &s.Keys;
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(solver.Solve(problem, fluence, report));
  // Rank 0 paints a negative mu_a into its first tet and promises it.
  std::vector<int> promised;
  if (Rank() == 0 && !material.RefractiveIndex.empty())
  {
    material.AbsorptionCoefficient[1] = -2.0;
    promised.push_back(0);
  }
  solver.SetChangedTets(promised);
  std::string message;
  try
  {
    solver.Solve(problem, fluence, report);
  }
  catch (const Error& e)
  {
    message = e.what();
  }
  EXPECT_NE(message.find("AbsorptionCoefficient of tet 0, channel G is -2"), std::string::npos)
    << message;
  // Undone, told nothing: the solver compares with what it kept and solves.
  if (Rank() == 0 && !material.RefractiveIndex.empty())
    material.AbsorptionCoefficient[1] = PieceMaterial(s, s.Material).AbsorptionCoefficient[1];
  std::vector<double> again;
  ASSERT_TRUE(solver.Solve(problem, again, report));
  DistributedVertexSolver fresh("divergence");
  fresh.SetCommunicator(MakeCommunicator(GetWorldCommunicator()));
  fresh.SetRelTol(1e-10);
  std::vector<double> expected;
  ASSERT_TRUE(fresh.Solve(problem, expected, report));
  if (!expected.empty())
    EXPECT_LT(RelativeDifference(again, expected), 1e-8);
}

// The last rank's piece empty: it takes part in every exchange, with no
// tets and no rows.
TEST(DistributedPaintRows, AnEmptyRankTakesPart)
{
  if (Size() < 2)
  {
    GTEST_SKIP() << "needs 2 or more ranks";
  }
  for (const std::string discretization : { "divergence", "fem" })
    RunStrokes(Size() - 1, discretization, "");
}
