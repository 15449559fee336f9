// One three-channel distributed PCG with the serial stopping rules (issue
// 32, session 31): DistributedVertexSolver's SolveChannels
// (DistributedLinearSolver::SolveChannels, DistributedPCG.h; the channels
// one after the other, and fused, SetFusedReductions) against the
// per-channel hypre PCG it replaced (SetThreeChannelPCG(false)), the change
// rule (DiffusionSolver::SetChangeTol) against tight solves, and the guard
// after a paint (at least one iteration). These tests run on MPI_COMM_WORLD:
// on one rank as discovered by ctest (an MPI singleton) and on 2 and 3 ranks
// through mpiexec (Testing/Solvers/CMakeLists.txt, Solvers.DistributedPCG2/3);
// with them BoomerAMG's kept hierarchy after a values-only update.
// Every rank runs the same steps in the same order (the calls are
// collective) and checks with EXPECT (no early return before a collective).
#include "DistributedSlabs.h"
#include "DistributedVertexSolver.h"
#include "HypreSolver.h"
#include "InteractiveAccuracy.h"
#include "TestProblems.h"

#include <gtest/gtest.h>

#include <HYPRE.h>
#include <_hypre_parcsr_ls.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <memory>
#include <sstream>
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

/// The steps of every run: cold, a relight (another irradiance), a paint
/// stroke across the 2 and 3 ranks' slab boundaries (values-only, the
/// changed rows), a second relight.
struct Step
{
  std::string What;
  int Irradiance = 0; ///< seed offset of the irradiance
  bool Paint = false;
};

std::vector<Step> Steps()
{
  return { { "cold", 0, false }, { "relight", 1, false }, { "paint", 1, true },
    { "relight after the paint", 2, false } };
}

/// mu_a x 3 in every channel of the tets near (2.5, 2.5, 4.2): across
/// x = 2.5 (2 ranks) and near the top face.
void PaintStroke(const Scene& s, OpticalProperties& m)
{
  for (const int t : TetsNear(s.Whole, { 2.5, 2.5, 4.2 }, 0.9))
    for (int c = 0; c < 3; ++c)
      m.AbsorptionCoefficient[3 * static_cast<std::size_t>(t) + c] *= 3.0;
}

/// The whole mesh's fluence (3 per point of Whole) from every rank's piece
/// (a shared point has the same value on every rank that holds it).
std::vector<double> WholeFluence(const Scene& s, const std::vector<double>& fluence, MPI_Comm comm)
{
  const std::size_t n = static_cast<std::size_t>(s.Whole.GetNumberOfPoints());
  std::vector<double> sum(3 * n, 0.0), count(n, 0.0);
  for (std::size_t i = 0; i < s.Points.size(); ++i)
  {
    const std::size_t p = static_cast<std::size_t>(s.Points[i]);
    for (int c = 0; c < 3; ++c)
      sum[3 * p + c] += fluence[3 * i + c];
    count[p] += 1.0;
  }
  MPI_Allreduce(MPI_IN_PLACE, sum.data(), static_cast<int>(sum.size()), MPI_DOUBLE, MPI_SUM, comm);
  MPI_Allreduce(MPI_IN_PLACE, count.data(), static_cast<int>(count.size()), MPI_DOUBLE, MPI_SUM, comm);
  for (std::size_t p = 0; p < n; ++p)
    for (int c = 0; c < 3; ++c)
      sum[3 * p + c] = count[p] > 0.0 ? sum[3 * p + c] / count[p] : 0.0;
  return sum;
}

/// The interactive rule's measure: per channel, the relative RMS of a - b
/// over the whole mesh's boundary points; the worst channel.
double BoundaryRms(const TetMesh& whole, const std::vector<double>& a, const std::vector<double>& b)
{
  double worst = 0.0;
  for (int c = 0; c < 3; ++c)
  {
    double dd = 0.0, bb = 0.0;
    for (const int p : whole.GetBoundaryPoints())
    {
      const std::size_t k = 3 * static_cast<std::size_t>(p) + c;
      dd += (a[k] - b[k]) * (a[k] - b[k]);
      bb += b[k] * b[k];
    }
    worst = std::max(worst, std::sqrt(dd / bb));
  }
  return worst;
}

std::string Iterations(const SolverReport& r)
{
  std::ostringstream os;
  for (int c = 0; c < 3; ++c)
    os << (c ? "/" : "") << r.Iterations[c] << (r.StoppedByChange[c] ? "c" : "");
  return os.str();
}

/// One solver's run of Steps() on the partition of `scene`; the fluence of
/// each step in `fluences`, the reports in `reports`.
struct StepsRun
{
  std::vector<std::vector<double>> Fluences;
  std::vector<SolverReport> Reports;
};

StepsRun RunSteps(const Scene& s, DistributedVertexSolver& solver)
{
  StepsRun run;
  OpticalProperties whole = s.Material;
  for (const Step& step : Steps())
  {
    if (step.Paint)
      PaintStroke(s, whole);
    const OpticalProperties material = PieceMaterial(s, whole);
    const std::vector<double> q =
      PiecePoints(s, translucency::testing::RandomIrradiance(s.Whole, 41 + step.Irradiance));
    DiffusionProblem problem;
    problem.Mesh = s.Piece.get();
    problem.Material = &material;
    problem.Irradiance = &q;
    problem.PointKeys = &s.Keys;
    std::vector<double> fluence;
    SolverReport report;
    EXPECT_TRUE(solver.Solve(problem, fluence, report));
    run.Fluences.push_back(fluence);
    run.Reports.push_back(report);
  }
  return run;
}

void Configure(DistributedVertexSolver& solver, const Communicator& comm, double relTol,
  double changeTol, const std::string& linear)
{
  solver.SetCommunicator(comm);
  solver.SetRelTol(relTol);
  solver.SetChangeTol(changeTol);
  solver.SetMaxIter(500);
  if (!linear.empty())
    solver.SetLinearSolver(linear);
}

/// The new PCG at RelTol 1e-12 against hypre's per-channel PCG (the path it
/// replaced), every step, on the partition over `ranks` ranks.
void ExpectHyprePCG(int ranks, const std::string& discretization, const std::string& linear)
{
  SCOPED_TRACE(discretization + " " + (linear.empty() ? "cg/boomeramg" : linear) + ", " +
    std::to_string(ranks) + " ranks with tets of " + std::to_string(Size()));
  const Scene s = MakeScene(ranks);
  const Communicator world = MakeCommunicator(GetWorldCommunicator());
  DistributedVertexSolver channels(discretization), fused(discretization), hypre(discretization);
  Configure(channels, world, 1e-12, 0.0, linear);
  Configure(fused, world, 1e-12, 0.0, linear);
  Configure(hypre, world, 1e-12, 0.0, linear);
  EXPECT_TRUE(channels.GetThreeChannelPCG());
  EXPECT_FALSE(channels.GetFusedReductions());
  fused.SetFusedReductions(true);
  hypre.SetThreeChannelPCG(false);
  const StepsRun a = RunSteps(s, channels);
  const StepsRun f = RunSteps(s, fused);
  const StepsRun b = RunSteps(s, hypre);
  const std::vector<Step> steps = Steps();
  for (std::size_t k = 0; k < steps.size(); ++k)
  {
    SCOPED_TRACE(steps[k].What);
    const std::vector<double> x = WholeFluence(s, a.Fluences[k], MPI_COMM_WORLD);
    const std::vector<double> y = WholeFluence(s, b.Fluences[k], MPI_COMM_WORLD);
    const double difference = RelativeDifference(x, y);
    if (Rank() == 0)
    {
      std::cout << steps[k].What << ": iterations " << Iterations(a.Reports[k]) << " (hypre's PCG "
                << Iterations(b.Reports[k]) << "), set-up '" << a.Reports[k].LinearSetup
                << "', fluence difference " << difference << "\n";
    }
    EXPECT_LT(difference, 1e-10);
    // Fused reductions: the same iterates (sums of the same local terms).
    EXPECT_EQ(f.Fluences[k], a.Fluences[k]);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      EXPECT_EQ(f.Reports[k].Iterations[c], a.Reports[k].Iterations[c]) << "channel " << c;
      EXPECT_TRUE(a.Reports[k].Converged[c]) << "channel " << c;
      EXPECT_LE(a.Reports[k].Residual[c], 1e-12) << "channel " << c;
      EXPECT_FALSE(a.Reports[k].StoppedByChange[c]) << "channel " << c;
    }
    if (steps[k].Paint)
      EXPECT_EQ(a.Reports[k].LinearSetup.rfind("rows (", 0), 0u) << a.Reports[k].LinearSetup;
  }
}

/// The interactive rule (RelTol 1e-2 with the change rule, as Solve
/// Diffusion's default) against RelTol 1e-12 solves of every step: the
/// boundary fluence within 1 % RMS. Returns the interactive run's reports.
std::vector<SolverReport> ExpectInteractiveAccuracy(const Scene& s, const Communicator& comm,
  MPI_Comm mpi, const std::string& linear)
{
  DistributedVertexSolver interactive("divergence"), tight("divergence");
  Configure(interactive, comm, InteractiveRelTol, InteractiveChangeTol, linear);
  Configure(tight, comm, 1e-12, 0.0, linear);
  const StepsRun a = RunSteps(s, interactive);
  const StepsRun b = RunSteps(s, tight);
  const std::vector<Step> steps = Steps();
  int rank = 0;
  MPI_Comm_rank(mpi, &rank);
  for (std::size_t k = 0; k < steps.size(); ++k)
  {
    SCOPED_TRACE(steps[k].What);
    const std::vector<double> x = WholeFluence(s, a.Fluences[k], mpi);
    const std::vector<double> y = WholeFluence(s, b.Fluences[k], mpi);
    const double rms = BoundaryRms(s.Whole, x, y);
    if (rank == 0)
    {
      std::cout << steps[k].What << ": iterations " << Iterations(a.Reports[k])
                << " (c: stopped by change; RelTol 1e-12: " << Iterations(b.Reports[k])
                << "), boundary RMS error " << rms << "\n";
    }
    EXPECT_LT(rms, 1e-2);
    for (int c = 0; c < NumberOfChannels; ++c)
      EXPECT_TRUE(a.Reports[k].Converged[c]) << "channel " << c;
  }
  return a.Reports;
}

} // namespace

TEST(DistributedPCG, EqualsHyprePCG)
{
  for (const std::string discretization : { "divergence", "fem" })
    ExpectHyprePCG(Size(), discretization, "");
}

TEST(DistributedPCG, EqualsHyprePCGWithTheAggregationSolver)
{
  ExpectHyprePCG(Size(), "divergence", "cg/aggregation");
}

// The last rank's piece empty: no rows, in every reduction.
TEST(DistributedPCG, EqualsHyprePCGWithAnEmptyRank)
{
  if (Size() < 2)
  {
    GTEST_SKIP() << "needs 2 or more ranks";
  }
  ExpectHyprePCG(Size() - 1, "divergence", "");
}

// The interactive rule's accuracy on every rank count, and the iterations
// of the world's partition against one rank's (the whole mesh on
// MPI_COMM_SELF, on every rank).
TEST(DistributedPCG, ChangeRuleKeepsTheBoundaryFluenceWithinOnePercent)
{
  const Scene s = MakeScene(Size());
  SCOPED_TRACE(std::to_string(Size()) + " ranks");
  const std::vector<SolverReport> world =
    ExpectInteractiveAccuracy(s, MakeCommunicator(GetWorldCommunicator()), MPI_COMM_WORLD, "");
  if (Size() < 2)
    return;
  // One rank: the whole mesh on every rank, on its own.
  Scene one;
  {
    SCOPED_TRACE("one rank");
    one.Whole.SetGeometry(s.Whole.GetPoints(), s.Whole.GetTets());
    one.Material = s.Material;
    for (int t = 0; t < s.Whole.GetNumberOfTets(); ++t)
      one.Tets.push_back(t);
    for (int p = 0; p < s.Whole.GetNumberOfPoints(); ++p)
    {
      one.Points.push_back(p);
      one.Keys.push_back(PointKeyFromId(p));
    }
    one.Used.assign(one.Points.size(), 1);
    one.Piece = std::make_shared<TetMesh>();
    one.Piece->SetGeometry(s.Whole.GetPoints(), s.Whole.GetTets());
    const std::vector<SolverReport> self =
      ExpectInteractiveAccuracy(one, MakeCommunicator(GetSelfCommunicator()), MPI_COMM_SELF, "");
    const std::vector<Step> steps = Steps();
    for (std::size_t k = 0; k < steps.size(); ++k)
    {
      SCOPED_TRACE(steps[k].What);
      if (Rank() == 0)
      {
        std::cout << steps[k].What << ": iterations on 1 rank " << Iterations(self[k]) << ", on "
                  << Size() << " ranks " << Iterations(world[k]) << "\n";
      }
      // Not the same counts: BoomerAMG's coarsening (HMIS) depends on the
      // partition, so the preconditioners differ (RelTol 1e-12 on this box:
      // 14/14/14 iterations on 1 rank, 16/15/15 on 2), and a loose solve
      // stops an iteration apart (measured: at most 1).
      for (int c = 0; c < NumberOfChannels; ++c)
        EXPECT_LE(std::abs(self[k].Iterations[c] - world[k].Iterations[c]), 1) << "channel " << c;
    }
  }
}

// The change rule stops before RelTol: at RelTol 1e-12 with the interactive
// change tolerance every channel of every step stops by the change rule,
// with fewer iterations than the tight solve and within 1 % of it.
TEST(DistributedPCG, ChangeRuleStopsBeforeATightRelTol)
{
  const Scene s = MakeScene(Size());
  const Communicator world = MakeCommunicator(GetWorldCommunicator());
  DistributedVertexSolver changing("divergence"), tight("divergence");
  Configure(changing, world, 1e-12, InteractiveChangeTol, "");
  Configure(tight, world, 1e-12, 0.0, "");
  const StepsRun a = RunSteps(s, changing);
  const StepsRun b = RunSteps(s, tight);
  const std::vector<Step> steps = Steps();
  for (std::size_t k = 0; k < steps.size(); ++k)
  {
    SCOPED_TRACE(steps[k].What);
    const double rms = BoundaryRms(s.Whole, WholeFluence(s, a.Fluences[k], MPI_COMM_WORLD),
      WholeFluence(s, b.Fluences[k], MPI_COMM_WORLD));
    if (Rank() == 0)
    {
      std::cout << steps[k].What << ": iterations " << Iterations(a.Reports[k]) << " against "
                << Iterations(b.Reports[k]) << ", boundary RMS error " << rms << "\n";
    }
    EXPECT_LT(rms, 1e-2);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      EXPECT_TRUE(a.Reports[k].Converged[c]) << "channel " << c;
      EXPECT_TRUE(a.Reports[k].StoppedByChange[c]) << "channel " << c;
      EXPECT_GT(a.Reports[k].Residual[c], 1e-12) << "channel " << c;
      EXPECT_LT(a.Reports[k].Iterations[c], b.Reports[k].Iterations[c]) << "channel " << c;
      EXPECT_GE(a.Reports[k].Iterations[c], 3) << "channel " << c;
    }
  }
}

// The guard after a paint (LinearSolver::SetMinIter(1)): a stroke small
// enough that the warm start is within RelTol 1e-2 still iterates in every
// channel, and the fluence under the stroke moves.
TEST(DistributedPCG, PaintIteratesAtLeastOnce)
{
  const Scene s = MakeScene(Size());
  const Communicator world = MakeCommunicator(GetWorldCommunicator());
  DistributedVertexSolver solver("divergence");
  Configure(solver, world, 1e-2, InteractiveChangeTol, "");
  OpticalProperties whole = s.Material;
  const std::vector<double> q = PiecePoints(s, translucency::testing::RandomIrradiance(s.Whole, 41));
  const std::vector<int> stroke = TetsNear(s.Whole, { 2.5, 2.5, 4.6 }, 0.5);
  std::vector<std::vector<double>> fluences;
  for (int step = 0; step < 2; ++step)
  {
    if (step == 1)
      for (const int t : stroke)
        for (int c = 0; c < 3; ++c)
          whole.AbsorptionCoefficient[3 * static_cast<std::size_t>(t) + c] *= 1.5;
    const OpticalProperties material = PieceMaterial(s, whole);
    DiffusionProblem problem;
    problem.Mesh = s.Piece.get();
    problem.Material = &material;
    problem.Irradiance = &q;
    problem.PointKeys = &s.Keys;
    std::vector<double> fluence;
    SolverReport report;
    ASSERT_TRUE(solver.Solve(problem, fluence, report));
    fluences.push_back(WholeFluence(s, fluence, MPI_COMM_WORLD));
    if (Rank() == 0)
    {
      std::cout << (step ? "paint" : "cold") << ": iterations " << Iterations(report) << ", residuals "
                << report.Residual[0] << " " << report.Residual[1] << " " << report.Residual[2]
                << ", set-up '" << report.LinearSetup << "'\n";
    }
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      EXPECT_TRUE(report.Converged[c]) << "channel " << c;
      EXPECT_GE(report.Iterations[c], 1) << "channel " << c;
    }
    if (step == 1)
      EXPECT_EQ(report.LinearSetup.rfind("rows (", 0), 0u) << report.LinearSetup;
  }
  // The stroke's points: the fluence there moved (mu_a x 1.5 lowers it).
  std::vector<char> inStroke(static_cast<std::size_t>(s.Whole.GetNumberOfPoints()), 0);
  for (const int t : stroke)
    for (int k = 0; k < 4; ++k)
      inStroke[static_cast<std::size_t>(s.Whole.GetTet(t)[k])] = 1;
  for (int c = 0; c < 3; ++c)
  {
    double moved = 0.0, scale = 0.0;
    for (std::size_t p = 0; p < inStroke.size(); ++p)
    {
      if (!inStroke[p])
        continue;
      moved = std::max(moved, fluences[0][3 * p + c] - fluences[1][3 * p + c]);
      scale = std::max(scale, fluences[0][3 * p + c]);
    }
    if (Rank() == 0)
      std::cout << "channel " << c << ": the stroke's fluence moved by up to " << moved / scale << "\n";
    EXPECT_GT(moved, 1e-4 * scale) << "channel " << c;
  }
}

namespace
{
/// This rank's rows of the 3-D 7-point Laplacian of side^3 rows plus
/// `shift` I (split by rows over the ranks), with `absorber` added to the
/// diagonal of the rows in the bottom `absorberLayers` z-layers (a painted
/// absorber, ~1/3 of the rows).
struct LaplacianRows
{
  int Begin = 0, End = 0;
  std::vector<int> Offsets{ 0 }, Columns;
  std::vector<double> Values;
  std::vector<int> Painted; ///< local numbers of the absorber's rows
};

LaplacianRows MakeLaplacianRows(int side, double shift, double absorber, int absorberLayers)
{
  const int ranks = Size(), rank = Rank(), n = side * side * side;
  LaplacianRows m;
  m.Begin = static_cast<int>(static_cast<long long>(n) * rank / ranks);
  m.End = static_cast<int>(static_cast<long long>(n) * (rank + 1) / ranks);
  for (int i = m.Begin; i < m.End; ++i)
  {
    const int x = i % side, y = (i / side) % side, z = i / (side * side);
    std::vector<int> row{ i };
    const int steps[3] = { 1, side, side * side };
    const int at[3] = { x, y, z };
    for (int d = 0; d < 3; ++d)
    {
      if (at[d] > 0)
        row.push_back(i - steps[d]);
      if (at[d] + 1 < side)
        row.push_back(i + steps[d]);
    }
    std::sort(row.begin(), row.end());
    const bool painted = z < absorberLayers;
    if (painted)
      m.Painted.push_back(i - m.Begin);
    for (const int j : row)
    {
      m.Columns.push_back(j);
      m.Values.push_back(j == i ? 6.0 + shift + (painted ? absorber : 0.0) : -1.0);
    }
    m.Offsets.push_back(static_cast<int>(m.Columns.size()));
  }
  return m;
}

/// hypre's own l1 norms (hypre_ParCSRComputeL1Norms, option 4: what
/// BoomerAMG's set-up computes for the l1 Gauss-Seidel smoothers) of the
/// matrix of these rows, built here through hypre's IJ interface.
std::vector<double> HypreFineNorms(const LaplacianRows& m)
{
  HYPRE_IJMatrix ij = nullptr;
  HYPRE_IJMatrixCreate(MPI_COMM_WORLD, m.Begin, m.End - 1, m.Begin, m.End - 1, &ij);
  HYPRE_IJMatrixSetObjectType(ij, HYPRE_PARCSR);
  HYPRE_IJMatrixInitialize(ij);
  for (int r = 0; r < m.End - m.Begin; ++r)
  {
    HYPRE_Int count = m.Offsets[r + 1] - m.Offsets[r];
    HYPRE_BigInt row = m.Begin + r;
    std::vector<HYPRE_BigInt> columns(m.Columns.begin() + m.Offsets[r], m.Columns.begin() + m.Offsets[r + 1]);
    HYPRE_IJMatrixSetValues(ij, 1, &count, &row, columns.data(), m.Values.data() + m.Offsets[r]);
  }
  HYPRE_IJMatrixAssemble(ij);
  HYPRE_ParCSRMatrix a = nullptr;
  HYPRE_IJMatrixGetObject(ij, reinterpret_cast<void**>(&a));
  HYPRE_Real* norms = nullptr;
  hypre_ParCSRComputeL1Norms(reinterpret_cast<hypre_ParCSRMatrix*>(a), 4, nullptr, &norms);
  std::vector<double> result(norms, norms + (m.End - m.Begin));
  hypre_TFree(norms, HYPRE_MEMORY_HOST);
  HYPRE_IJMatrixDestroy(ij);
  return result;
}

double WorstRelative(const std::vector<double>& a, const std::vector<double>& b)
{
  double worst = a.size() == b.size() ? 0.0 : 1.0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i)
    worst = std::max(worst, std::abs(a[i] - b[i]) / std::abs(b[i]));
  MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return worst;
}
} // namespace

// Issue 32, session 34: a channel on another channel's BoomerAMG coarsening
// (HypreBoomerAMGPCG::SetupShared) has its own Galerkin levels, its own
// smoother norms and its own coarsest matrix for the Gaussian elimination,
// on every partition. The identity it is checked by: on a donor's
// coarsening the matrix 2.5 A has the levels 2.5 A_l, the norms 2.5 d_l and
// the coarsest matrix 2.5 A_L, so its V-cycle is the donor's divided by 2.5
// and PCG takes the donor's iterations to x / 2.5. A 3-D Laplacian (7-point,
// plus 0.1 I) of 14^3 rows split by rows over the ranks: several levels
// and a coarsest level eliminated (checked to fail without its own).
TEST(DistributedPCG, GalerkinSharerIsTheScaledDonorOnEveryPartition)
{
  const LaplacianRows m = MakeLaplacianRows(14, 0.1, 0.0, 0);
  const int begin = m.Begin, end = m.End;
  const std::vector<int>& offsets = m.Offsets;
  const std::vector<int>& columns = m.Columns;
  const std::vector<double>& values = m.Values;
  std::vector<double> scaled, b;
  for (const double v : values)
    scaled.push_back(2.5 * v);
  for (int i = begin; i < end; ++i)
    b.push_back(std::sin(0.37 * i) + 1.2);
  const MPI_Comm* world = GetWorldCommunicator();
  auto donor = CreateDistributedLinearSolver("cg/boomeramg", MakeCommunicator(world));
  auto sharer = CreateDistributedLinearSolver("cg/boomeramg", MakeCommunicator(world));
  donor->Setup(begin, end, offsets.data(), columns.data(), values.data());
  EXPECT_GE(donor->GetNumberOfLevels(), 3);
  ASSERT_TRUE(sharer->SetupShared(begin, end, offsets.data(), columns.data(), scaled.data(), *donor));
  EXPECT_EQ(sharer->GetNumberOfLevels(), donor->GetNumberOfLevels());
  std::vector<double> xd(b.size(), 0.0), xs(b.size(), 0.0);
  double rd = 1.0, rs = 1.0;
  const int itd = donor->Solve(b.data(), xd.data(), false, 1e-10, 200, rd);
  const int its = sharer->Solve(b.data(), xs.data(), false, 1e-10, 200, rs);
  EXPECT_GT(itd, 2);
  EXPECT_EQ(its, itd);
  EXPECT_LE(rs, 1e-10);
  double sums[2] = { 0.0, 0.0 };
  for (std::size_t i = 0; i < b.size(); ++i)
  {
    sums[0] += (2.5 * xs[i] - xd[i]) * (2.5 * xs[i] - xd[i]);
    sums[1] += xd[i] * xd[i];
  }
  MPI_Allreduce(MPI_IN_PLACE, sums, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_LE(std::sqrt(sums[0] / sums[1]), 1e-12);
}

// Issue 32, session 35: a values-only update of a kept BoomerAMG hierarchy
// (a paint) recomputes the fine level's smoother norms from the new values
// (UpdateValues every row, UpdateRows the changed rows), for a channel with
// its own hierarchy and for one on a shared coarsening. Checked against
// hypre's own l1 norms of the new matrix (hypre_ParCSRComputeL1Norms, built
// here), on every partition. An absorber painted into a third of the rows
// (diagonal 6.1 -> 46.1): with the set-up's norms the l1 Gauss-Seidel sweep
// divides those rows' residual by 6.1 and over-corrects 7.5-fold; with the
// refreshed ones the kept hierarchy converges (its coarse levels stale: 12
// -> 15 iterations on one rank, 14 -> 18 on three).
TEST(DistributedPCG, ValuesOnlyUpdateRefreshesTheFineSmoother)
{
  const int side = 14;
  const LaplacianRows before = MakeLaplacianRows(side, 0.1, 0.0, 0);
  const LaplacianRows after = MakeLaplacianRows(side, 0.1, 40.0, 5);
  const LaplacianRows otherBefore = MakeLaplacianRows(side, 1.3, 0.0, 0);
  const LaplacianRows otherAfter = MakeLaplacianRows(side, 1.3, 40.0, 5);
  long long painted = static_cast<long long>(after.Painted.size());
  MPI_Allreduce(MPI_IN_PLACE, &painted, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  ASSERT_EQ(painted, 5LL * side * side);
  const std::vector<double> expected = HypreFineNorms(after);
  const std::vector<double> expectedOther = HypreFineNorms(otherAfter);
  const std::vector<double> unpainted = HypreFineNorms(before);

  const MPI_Comm* world = GetWorldCommunicator();
  auto make = [world] {
    return std::make_unique<HypreBoomerAMGPCG>(*world, BoomerAMGOptions::Tuned());
  };
  const int* o = before.Offsets.data();
  const int* c = before.Columns.data();
  auto whole = make(), rows = make(), sharer = make(), fresh = make();
  whole->Setup(before.Begin, before.End, o, c, before.Values.data());
  EXPECT_GE(whole->GetNumberOfLevels(), 3);
  EXPECT_LE(WorstRelative(whole->GetFineSmootherNorms(), unpainted), 1e-14) << "the set-up's";
  rows->Setup(before.Begin, before.End, o, c, before.Values.data());
  ASSERT_TRUE(sharer->SetupShared(before.Begin, before.End, o, c, otherBefore.Values.data(), *whole));
  rows->PrepareUpdates(o, c);
  sharer->PrepareUpdates(o, c);

  whole->UpdateValues(o, c, after.Values.data());
  rows->UpdateRows(o, c, after.Values.data(), after.Painted.data(), static_cast<int>(after.Painted.size()));
  sharer->UpdateValues(o, c, otherAfter.Values.data());
  EXPECT_LE(WorstRelative(whole->GetFineSmootherNorms(), expected), 1e-14) << "UpdateValues";
  EXPECT_LE(WorstRelative(rows->GetFineSmootherNorms(), expected), 1e-14) << "UpdateRows";
  EXPECT_LE(WorstRelative(sharer->GetFineSmootherNorms(), expectedOther), 1e-14) << "a sharer";

  // The kept hierarchies against a fresh set-up of the painted matrix.
  fresh->Setup(after.Begin, after.End, o, c, after.Values.data());
  std::vector<double> b(after.Values.size() ? static_cast<std::size_t>(after.End - after.Begin) : 0);
  for (std::size_t i = 0; i < b.size(); ++i)
    b[i] = std::sin(0.37 * static_cast<double>(after.Begin + static_cast<int>(i))) + 1.2;
  auto solve = [&b](HypreBoomerAMGPCG& s, double& residual) {
    std::vector<double> x(b.size(), 0.0);
    return s.Solve(b.data(), x.data(), false, 1e-10, 100, residual);
  };
  double rFresh = 1.0, rWhole = 1.0, rRows = 1.0;
  const int itFresh = solve(*fresh, rFresh), itWhole = solve(*whole, rWhole), itRows = solve(*rows, rRows);
  if (Rank() == 0)
    std::cout << "iterations to 1e-10: fresh " << itFresh << ", kept (every row) " << itWhole
              << ", kept (changed rows) " << itRows << "\n";
  EXPECT_LE(rWhole, 1e-10);
  EXPECT_LE(rRows, 1e-10);
  EXPECT_EQ(itRows, itWhole);
  // Within the distributed solve's rule for an aged hierarchy (a values-only
  // solve taking more than twice the full set-up's iterations is rebuilt at
  // the next change: DistributedVertexSolver::SolveChannels). With the
  // set-up's norms it breaks down after 8-9 iterations at a relative
  // residual of 1.6-2.0 (1, 2 and 3 ranks).
  EXPECT_LE(itWhole, 2 * itFresh);
}
