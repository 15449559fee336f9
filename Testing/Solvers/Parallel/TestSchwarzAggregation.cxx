// The distributed variant of multigrid-agg, "cg/aggregation" (issue 32):
// hypre's PCG on the whole matrix preconditioned by additive Schwarz (one
// aggregation cycle on each rank's owned block). These tests run on
// MPI_COMM_WORLD: on one rank as discovered by ctest (an MPI singleton), and
// on 2 and 3 ranks through mpiexec (Testing/Solvers/CMakeLists.txt,
// Solvers.SchwarzAggregation2/3). Every rank runs the same tests in the same
// order (the solver's calls are collective), and checks its expectations
// with EXPECT (no early return before a collective).
//
// The system: the 7-point Laplacian plus a mass term on an M^3 grid (rows
// split in contiguous ranges over the ranks), SPD. The independent checks:
// the residual b - A x recomputed here from the stencil (not from the CSR
// arrays the solver got) on the gathered solution, and cg/boomeramg's
// solution of the same system.
#include "DistributedLinearSolver.h"
#include "HypreSolver.h"
#include "SchwarzAggregation.h"
#include "TestProblems.h"

#include <gtest/gtest.h>

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <numeric>

using namespace translucency;
using translucency::testing::Contains;
using translucency::testing::ErrorMessage;

namespace
{

Communicator World()
{
  return MakeCommunicator(GetWorldCommunicator());
}

constexpr int M = 16; // 4,096 unknowns: 2-3 levels on each rank's block

/// The grid system: a(i, i) = 6 + mass, a(i, j) = -1 for grid neighbours.
struct Grid
{
  int N = M * M * M;
  int Begin = 0, End = 0; ///< this rank's rows
  std::vector<int> Offsets, Columns;
  std::vector<double> Values;
  std::vector<double> Xyz; ///< positions of this rank's rows (grid spacing 1)
  double Mass = 0.1;

  Grid(int rank, int size, double mass)
    : Mass(mass)
  {
    Begin = static_cast<int>(static_cast<long long>(N) * rank / size);
    End = static_cast<int>(static_cast<long long>(N) * (rank + 1) / size);
    Offsets.push_back(0);
    for (int row = Begin; row < End; ++row)
    {
      const int x = row % M, y = (row / M) % M, z = row / (M * M);
      for (int j : Neighbours(row))
      {
        Columns.push_back(j);
        Values.push_back(j == row ? 6.0 + mass : -1.0);
      }
      Offsets.push_back(static_cast<int>(Columns.size()));
      Xyz.insert(Xyz.end(), { double(x), double(y), double(z) });
    }
  }

  /// Row `row`'s columns, ascending, the diagonal included.
  static std::vector<int> Neighbours(int row)
  {
    const int x = row % M, y = (row / M) % M, z = row / (M * M);
    std::vector<int> n;
    if (z > 0) n.push_back(row - M * M);
    if (y > 0) n.push_back(row - M);
    if (x > 0) n.push_back(row - 1);
    n.push_back(row);
    if (x < M - 1) n.push_back(row + 1);
    if (y < M - 1) n.push_back(row + M);
    if (z < M - 1) n.push_back(row + M * M);
    return n;
  }

  /// The global right-hand side's entry `row` (smooth plus a kink).
  static double Rhs(int row) { return 1.0 + std::sin(0.37 * row) + (row % 17 == 0 ? 5.0 : 0.0); }

  std::vector<double> LocalRhs() const
  {
    std::vector<double> b;
    for (int row = Begin; row < End; ++row)
      b.push_back(Rhs(row));
    return b;
  }

  /// ||b - A x|| / ||b|| over the whole grid, from the stencil (x: all N
  /// values), with diagonal 6 + mass.
  static double Residual(const std::vector<double>& x, double mass)
  {
    double r2 = 0.0, b2 = 0.0;
    for (int row = 0; row < M * M * M; ++row)
    {
      double ax = 0.0;
      for (int j : Neighbours(row))
        ax += (j == row ? 6.0 + mass : -1.0) * x[j];
      const double r = Rhs(row) - ax;
      r2 += r * r;
      b2 += Rhs(row) * Rhs(row);
    }
    return std::sqrt(r2 / b2);
  }
};

/// Every rank's part of x, in row order (collective).
std::vector<double> Gather(const std::vector<double>& local, int n)
{
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::vector<int> counts(size), displs(size);
  const int mine = static_cast<int>(local.size());
  MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  std::partial_sum(counts.begin(), counts.end() - 1, displs.begin() + 1);
  std::vector<double> all(n);
  MPI_Allgatherv(local.data(), mine, MPI_DOUBLE, all.data(), counts.data(), displs.data(),
    MPI_DOUBLE, MPI_COMM_WORLD);
  return all;
}

double MaxRelativeDifference(const std::vector<double>& a, const std::vector<double>& b)
{
  double diff = 0.0, scale = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k)
  {
    diff = std::max(diff, std::abs(a[k] - b[k]));
    scale = std::max(scale, std::abs(b[k]));
  }
  return diff / scale;
}

int Rank()
{
  EnsureHypreInitialized(); // MPI too, when a test runs alone
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int Size()
{
  EnsureHypreInitialized();
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

} // namespace

// The registry: "cg/aggregation" and its alias "multigrid-agg" name the
// distributed Schwarz solver; an unknown name and an invalid option are
// clear errors; options of other solvers are left unused.
TEST(SchwarzAggregation, RegistryNamesAndOptions)
{
  auto solver = CreateDistributedLinearSolver("cg/aggregation", World());
  EXPECT_EQ(solver->GetName(), "cg/aggregation");
  EXPECT_NE(dynamic_cast<SchwarzAggregationPCG*>(solver.get()), nullptr);
  EXPECT_EQ(CreateDistributedLinearSolver("Multigrid-Agg", World())->GetName(), "cg/aggregation");
  EXPECT_EQ(ErrorMessage([] { CreateDistributedLinearSolver("cg/schwarz", World()); }),
    "linear solver 'cg/schwarz' has no distributed variant (those with one: cg/aggregation, "
    "cg/boomeramg)");
  for (const auto& bad : { std::make_pair("agg-coarse-scale", 2.0),
         std::make_pair("agg-coarse-scale", 0.0), std::make_pair("agg-cycle-index", 3.0),
         std::make_pair("agg-cycle-index", 0.0), std::make_pair("agg-coarsest-size", 0.5),
         std::make_pair("agg-threads", -1.0) })
  {
    SolverOptions options;
    options.Set(bad.first, bad.second);
    const std::string message = ErrorMessage([&] { solver->SetOptions(options); });
    EXPECT_TRUE(Contains(message, std::string("cg/aggregation: option ") + bad.first))
      << bad.first << " = " << bad.second << ": " << message;
    EXPECT_TRUE(Contains(message, "is invalid")) << message;
  }
  SolverOptions mixed = BoomerAMGOptions::Tuned().ToOptions();
  mixed.Set("agg-cycle-index", 1).Set("agg-typo", 1);
  solver->SetOptions(mixed);
  const std::vector<std::string> unused = mixed.GetUnused();
  EXPECT_NE(std::find(unused.begin(), unused.end(), "agg-typo"), unused.end());
  EXPECT_NE(std::find(unused.begin(), unused.end(), "amg-pmax"), unused.end());
  EXPECT_EQ(std::find(unused.begin(), unused.end(), "agg-cycle-index"), unused.end());
  // Solve before Setup is an error, not a crash.
  double residual = 0.0;
  EXPECT_TRUE(Contains(ErrorMessage([&] { solver->Solve(nullptr, nullptr, false, 1e-8, 10, residual); }),
    "before Setup"));
}

// The solve meets RelTol on the residual recomputed here, equals
// cg/boomeramg's solution, and after UpdateValues (a large change of every
// diagonal: mass 0.1 -> 2) meets RelTol on the new matrix.
TEST(SchwarzAggregation, SolvesToTolAndMatchesBoomerAMG)
{
  const Grid g(Rank(), Size(), 0.1);
  const std::vector<double> b = g.LocalRhs();
  const int rows = g.End - g.Begin;
  auto schwarz = CreateDistributedLinearSolver("cg/aggregation", World());
  schwarz->SetCoordinates(g.Xyz.data(), rows);
  schwarz->Setup(g.Begin, g.End, g.Offsets.data(), g.Columns.data(), g.Values.data());
  EXPECT_GE(schwarz->GetNumberOfLevels(), 2);
  EXPECT_EQ(schwarz->GetNumberOfNonZeros(), static_cast<long long>(7 * g.N - 6 * M * M));
  EXPECT_GT(schwarz->GetMemoryBytes(), 0u);
  const double tol = 1e-8;
  std::vector<double> x(rows, 0.0);
  double residual = 1.0;
  const int iterations = schwarz->Solve(b.data(), x.data(), false, tol, 500, residual);
  EXPECT_GT(iterations, 0);
  EXPECT_LE(residual, tol);
  const std::vector<double> all = Gather(x, g.N);
  // hypre's PCG stops on its recursive residual; the true one agrees to
  // round-off (the Laplacian + mass is well conditioned: kappa < 150).
  EXPECT_LE(Grid::Residual(all, 0.1), 1.01 * tol);
  if (Rank() == 0)
    std::printf("[schwarz] %d ranks: %d iterations to %g, %d levels on rank 0\n", Size(),
      iterations, tol, schwarz->GetNumberOfLevels());

  // cg/boomeramg on the same system to the same tolerance: the two errors
  // are below kappa * tol ~ 1e-6 of the solution, so the two agree to that.
  auto amg = CreateDistributedLinearSolver("cg/boomeramg", World());
  amg->Setup(g.Begin, g.End, g.Offsets.data(), g.Columns.data(), g.Values.data());
  std::vector<double> y(rows, 0.0);
  amg->Solve(b.data(), y.data(), false, tol, 500, residual);
  EXPECT_LE(residual, tol);
  EXPECT_LE(MaxRelativeDifference(all, Gather(y, g.N)), 1e-6);

  // Values-only update: mass 0.1 -> 2 everywhere (the aggregation kept,
  // the block values set up again).
  const Grid heavy(Rank(), Size(), 2.0);
  schwarz->UpdateValues(heavy.Offsets.data(), heavy.Columns.data(), heavy.Values.data());
  std::vector<double> z(x);
  schwarz->Solve(b.data(), z.data(), true, tol, 500, residual);
  EXPECT_LE(residual, tol);
  const std::vector<double> allZ = Gather(z, g.N);
  EXPECT_LE(Grid::Residual(allZ, 2.0), 1.01 * tol);
  EXPECT_GT(Grid::Residual(allZ, 0.1), 1e-2); // the new matrix, not the old one
  // A changed pattern is refused (on every rank: the same change).
  std::vector<int> moved(heavy.Columns);
  std::swap(moved[0], moved[1]);
  EXPECT_TRUE(Contains(ErrorMessage([&] {
    schwarz->UpdateValues(heavy.Offsets.data(), moved.data(), heavy.Values.data());
  }),
    "changed pattern"));
}

// SetupShared: a second channel's matrix on the donor's aggregation, with
// its own values (solves its own matrix to RelTol); a donor of another kind
// or without a set-up is refused.
TEST(SchwarzAggregation, SharedAggregationSolvesItsOwnMatrix)
{
  const Grid g(Rank(), Size(), 0.1), other(Rank(), Size(), 0.7);
  const int rows = g.End - g.Begin;
  auto donor = CreateDistributedLinearSolver("cg/aggregation", World());
  auto sharer = CreateDistributedLinearSolver("cg/aggregation", World());
  auto unset = CreateDistributedLinearSolver("cg/aggregation", World());
  auto amg = CreateDistributedLinearSolver("cg/boomeramg", World());
  EXPECT_FALSE(sharer->SetupShared(
    g.Begin, g.End, other.Offsets.data(), other.Columns.data(), other.Values.data(), *unset));
  donor->SetCoordinates(g.Xyz.data(), rows);
  donor->Setup(g.Begin, g.End, g.Offsets.data(), g.Columns.data(), g.Values.data());
  amg->Setup(g.Begin, g.End, g.Offsets.data(), g.Columns.data(), g.Values.data());
  EXPECT_FALSE(sharer->SetupShared(
    g.Begin, g.End, other.Offsets.data(), other.Columns.data(), other.Values.data(), *amg));
  ASSERT_TRUE(sharer->SetupShared(
    g.Begin, g.End, other.Offsets.data(), other.Columns.data(), other.Values.data(), *donor));
  EXPECT_EQ(sharer->GetNumberOfLevels(), donor->GetNumberOfLevels());
  EXPECT_LT(sharer->GetMemoryBytes(), donor->GetMemoryBytes()); // the aggregation not its own
  const std::vector<double> b = g.LocalRhs();
  std::vector<double> x(rows, 0.0);
  double residual = 1.0;
  EXPECT_GT(sharer->Solve(b.data(), x.data(), false, 1e-8, 500, residual), 0);
  EXPECT_LE(residual, 1e-8);
  const std::vector<double> all = Gather(x, g.N);
  EXPECT_LE(Grid::Residual(all, 0.7), 1.01e-8);
  EXPECT_GT(Grid::Residual(all, 0.1), 1e-2);
}

// Convergence honesty: a solve stopped by maxIter reports its residual
// above RelTol (not an error: the caller decides), and a matrix that is not
// SPD (a negative diagonal on every rank's block) is a clear error.
TEST(SchwarzAggregation, NotConvergedAndNotSpd)
{
  const Grid g(Rank(), Size(), 0.1);
  const int rows = g.End - g.Begin;
  auto solver = CreateDistributedLinearSolver("cg/aggregation", World());
  solver->Setup(g.Begin, g.End, g.Offsets.data(), g.Columns.data(), g.Values.data());
  const std::vector<double> b = g.LocalRhs();
  std::vector<double> x(rows, 0.0);
  double residual = 0.0;
  EXPECT_EQ(solver->Solve(b.data(), x.data(), false, 1e-12, 2, residual), 2);
  EXPECT_GT(residual, 1e-12);
  std::vector<double> bad(g.Values);
  for (int k = g.Offsets[0]; k < g.Offsets[1]; ++k)
    if (g.Columns[k] == g.Begin)
      bad[static_cast<std::size_t>(k)] = -1.0; // the first row's diagonal
  EXPECT_TRUE(Contains(ErrorMessage([&] {
    solver->Setup(g.Begin, g.End, g.Offsets.data(), g.Columns.data(), bad.data());
  }),
    "not SPD"));
}
