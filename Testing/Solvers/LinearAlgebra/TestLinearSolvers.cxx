// Every linear solver of this build (GetLinearSolverNames(), so solvers added
// later are covered too) against an independent direct solution: CHOLMOD when
// the build has it, otherwise (and for CHOLMOD itself) Eigen's
// SimplicialLDLT. Systems are the discrete-divergence systems (TransCut
// eq. 10-14, DiscreteDivergence::Assemble) of random jittered box meshes with
// heterogeneous random materials.

#include "AggregationMultigrid.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "LightSources.h"
#include "LinearSolver.h"
#include "Radiance.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TetMesh.h"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <string>

namespace
{

using namespace translucency;
namespace tt = translucency::testing;

struct Problem
{
  TetMesh Mesh;
  OpticalProperties Material;
  DiffusionSystem System;
};

/// Per-tet material drawn between marble and skin1 per channel (log-uniform
/// mu_a, uniform sigma_s'), refractive index in [1.3, 1.5]: coefficients vary
/// by an order of magnitude from tet to tet.
OpticalProperties RandomMaterial(int numTets, std::uint64_t seed)
{
  const MaterialPreset& marble = FindMaterialPreset("marble");
  const MaterialPreset& skin = FindMaterialPreset("skin1");
  std::mt19937_64 rng(seed);
  OpticalProperties m = OpticalProperties::Uniform(numTets, marble.Absorption,
    marble.ReducedScattering, marble.RefractiveIndex);
  for (int t = 0; t < numTets; ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double lo = std::log(std::min(marble.Absorption[c], skin.Absorption[c]));
      const double hi = std::log(std::max(marble.Absorption[c], skin.Absorption[c]));
      m.AbsorptionCoefficient[3 * t + c] = std::exp(lo + (hi - lo) * tt::Uniform01(rng));
      m.ReducedScatteringCoefficient[3 * t + c] = marble.ReducedScattering[c] +
        (skin.ReducedScattering[c] - marble.ReducedScattering[c]) * tt::Uniform01(rng);
    }
    m.RefractiveIndex[t] = 1.3 + 0.2 * tt::Uniform01(rng);
  }
  return m;
}

/// Irradiance of a directional light travelling along (sin a, -cos a, 0)
/// (a in degrees) on the box (convex: no shadows needed).
std::vector<double> LightAt(const Problem& p, double degrees)
{
  const double a = degrees * M_PI / 180.0;
  LightSource light;
  light.Direction = { std::sin(a), -std::cos(a), 0.0 };
  light.Power = { 1.0, 0.8, 0.6 };
  std::vector<double> q;
  ComputeBoundaryIrradiance(p.Mesh, PointRefractiveIndex(p.Mesh, p.Material.RefractiveIndex),
    { light }, 0.0, 0, false, q);
  return q;
}

/// A jittered nx x ny x nz box (mm: 2 mm cells) with a random material, lit
/// by LightAt(degrees) and assembled.
void MakeProblem(Problem& p, int nx, int ny, int nz, std::uint64_t seed, double degrees = 20.0)
{
  const tt::MeshData box = tt::BoxMesh(nx, ny, nz, 2.0 * nx, 2.0 * ny, 2.0 * nz, 0.25, seed);
  p.Mesh.SetGeometry(box.Points, box.Tets);
  p.Material = RandomMaterial(p.Mesh.GetNumberOfTets(), seed + 11);
  DiscreteDivergence().Assemble(p.Mesh, p.Material, LightAt(p, degrees), p.System);
}

double RelativeDifference(const Eigen::VectorXd& x, const Eigen::VectorXd& reference)
{
  return (x - reference).norm() / reference.norm();
}

bool Has(const std::string& name)
{
  const auto names = GetLinearSolverNames();
  return std::find(names.begin(), names.end(), name) != names.end();
}

/// The reference solution of channel c: CHOLMOD (unless testing CHOLMOD
/// itself or the build lacks it), else Eigen's SimplicialLDLT.
std::array<Eigen::VectorXd, 3> ReferenceSolution(const DiffusionSystem& s, const std::string& tested)
{
  std::array<Eigen::VectorXd, 3> x;
  if (tested != "cholmod" && Has("cholmod"))
  {
    auto direct = CreateLinearSolver("cholmod");
    direct->Setup(s, nullptr, true);
    std::array<LinearSolveStats, 3> stats;
    direct->Solve(s, x, false, stats);
    return x;
  }
  for (int c = 0; c < 3; ++c)
  {
    const Eigen::SparseMatrix<double> m = s.Matrix(c);
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(m);
    EXPECT_EQ(ldlt.info(), Eigen::Success);
    x[c] = ldlt.solve(s.RightHandSide[c]);
  }
  return x;
}

class LinearSolverTest : public ::testing::TestWithParam<std::string>
{
};

// The solution to a relative residual of 1e-10 matches the direct one to the
// accuracy that residual implies (||dx|| / ||x|| <= cond(M) * 1e-10; on these
// meshes cond(M) is 10-40 for uniform marble or skin1, from the dense
// eigenvalues, so 1e-6 leaves a wide margin while any wrong solve, e.g. with
// the wrong channel's matrix, is off by > 1e-2).
TEST_P(LinearSolverTest, ReachesTheDirectSolutionOnRandomMeshesAndMaterials)
{
  for (std::uint64_t seed : { 1u, 2u })
  {
    Problem p;
    MakeProblem(p, 7 + seed, 6, 5 + 2 * seed, seed);
    const auto reference = ReferenceSolution(p.System, GetParam());
    auto solver = CreateLinearSolver(GetParam());
    solver->SetRelTol(1e-10);
    solver->SetMaxIter(5000);
    solver->Setup(p.System, &p.Mesh, true);
    std::array<Eigen::VectorXd, 3> x;
    std::array<LinearSolveStats, 3> stats;
    ASSERT_TRUE(solver->Solve(p.System, x, false, stats));
    for (int c = 0; c < 3; ++c)
    {
      const Eigen::VectorXd& b = p.System.RightHandSide[c];
      const double trueResidual = (b - p.System.Matrix(c) * x[c]).norm() / b.norm();
      EXPECT_TRUE(stats[c].Converged) << GetParam() << " seed " << seed << " channel " << c;
      // Iterative solvers track the residual by a recurrence that drifts
      // from the true one by rounding (~1e-13 here): far below 1e-9.
      EXPECT_LE(trueResidual, 1e-9) << GetParam() << " seed " << seed << " channel " << c;
      EXPECT_LE(RelativeDifference(x[c], reference[c]), 1e-6)
        << GetParam() << " seed " << seed << " channel " << c;
      EXPECT_GT(stats[c].SpMVEquivalents, 0.0);
    }
    // The reference itself is a solution (guards against a broken reference).
    for (int c = 0; c < 3; ++c)
    {
      const Eigen::VectorXd& b = p.System.RightHandSide[c];
      EXPECT_LE((b - p.System.Matrix(c) * reference[c]).norm() / b.norm(), 1e-12);
    }
  }
}

// Relighting: after a 0.5-degree light rotation (one frame of dragging a
// light), starting from the previous solution needs fewer iterations than
// starting from zero (iterative solvers; a direct solve has no iterations and
// is skipped). The change is this small because AMG-PCG cuts the residual
// ~100-fold per iteration: a guess saves one of its iterations only when its
// residual is below ~1 % of ||b|| (a 5-degree rotation leaves ~5 %).
TEST_P(LinearSolverTest, WarmStartAfterASmallLightChangeNeedsFewerIterations)
{
  Problem p;
  MakeProblem(p, 10, 8, 8, 3, 20.0);
  auto solver = CreateLinearSolver(GetParam());
  solver->SetRelTol(1e-8);
  solver->SetMaxIter(5000);
  solver->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> previous, cold, warm;
  std::array<LinearSolveStats, 3> stats, coldStats, warmStats;
  ASSERT_TRUE(solver->Solve(p.System, previous, false, stats));
  if (stats[0].Iterations == 0)
  {
    GTEST_SKIP() << GetParam() << " is a direct solver";
  }
  if (stats[0].Iterations == 1)
  {
    // multigrid-cg on a mesh below its coarsest-level size is one exact
    // (LDLT) application: nothing for a guess to save. TestMultires checks
    // its warm start on a mesh with a real hierarchy.
    GTEST_SKIP() << GetParam() << " solves this small problem exactly in one iteration";
  }
  // Same matrix, new light: only the right-hand sides change.
  DiffusionSystem rotated;
  DiscreteDivergence().Assemble(p.Mesh, p.Material, LightAt(p, 20.5), rotated);
  for (int c = 0; c < 3; ++c)
  {
    ASSERT_EQ(rotated.Values[c], p.System.Values[c]);
    p.System.RightHandSide[c] = rotated.RightHandSide[c];
  }
  ASSERT_TRUE(solver->Solve(p.System, cold, false, coldStats));
  warm = previous;
  ASSERT_TRUE(solver->Solve(p.System, warm, true, warmStats));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(coldStats[c].Converged && warmStats[c].Converged) << GetParam() << " channel " << c;
    EXPECT_LT(warmStats[c].Iterations, coldStats[c].Iterations) << GetParam() << " channel " << c;
    // Both reach the same solution (each within its tolerance).
    EXPECT_LE(RelativeDifference(warm[c], cold[c]), 1e-5) << GetParam() << " channel " << c;
  }
}

// MinIter (the interactive rule's guard after a paint stroke): a warm start
// already within RelTol runs no iteration by default and exactly MinIter = 1
// with it, which lowers the error in the energy norm (a CG step minimises
// it along its direction; the error is taken against a solve of the same
// system to 1e-12). Honoured by the CG solvers (LinearSolver::SetMinIter);
// the others are skipped.
TEST_P(LinearSolverTest, MinIterIteratesAWarmStartAlreadyWithinTolerance)
{
  const std::string name = GetParam();
  if (name != "cg-jacobi" && name != "multigrid-agg" && name != "multigrid-cg")
  {
    GTEST_SKIP() << name << " does not honour MinIter";
  }
  Problem p;
  MakeProblem(p, 10, 8, 8, 7, 20.0);
  auto solver = CreateLinearSolver(name);
  solver->SetMaxIter(5000);
  solver->SetRelTol(1e-12);
  solver->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> reference, x, guess;
  std::array<LinearSolveStats, 3> stats;
  ASSERT_TRUE(solver->Solve(p.System, reference, false, stats));
  // A guess within the loose RelTol 0.05: a cold solve to 0.03.
  solver->SetRelTol(0.03);
  ASSERT_TRUE(solver->Solve(p.System, guess, false, stats));
  if ((guess[0] - reference[0]).norm() == 0.0)
  {
    // multigrid-cg below its coarsest-level size: one exact application.
    GTEST_SKIP() << name << " solves this small problem exactly in one iteration";
  }
  solver->SetRelTol(0.05);
  x = guess;
  ASSERT_TRUE(solver->Solve(p.System, x, true, stats));
  for (int c = 0; c < 3; ++c)
  {
    ASSERT_EQ(stats[c].Iterations, 0) << name << ": the guess must start within RelTol";
  }
  solver->SetMinIter(1);
  EXPECT_EQ(solver->GetMinIter(), 1);
  x = guess;
  ASSERT_TRUE(solver->Solve(p.System, x, true, stats));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(stats[c].Iterations, 1) << name << " channel " << c;
    EXPECT_TRUE(stats[c].Converged) << name << " channel " << c;
    const Eigen::VectorXd before = guess[c] - reference[c], after = x[c] - reference[c];
    const auto a = p.System.Matrix(c);
    EXPECT_LT(after.dot(a * after), before.dot(a * before)) << name << " channel " << c;
  }
}

// Setup(patternChanged = false) after only the values changed gives the same
// solve as a fresh solver set up from scratch on the new values: same
// iterations and the same solution up to rounding (1e-12, while a stale
// preconditioner or factor would be off by the 1e-8 tolerance or worse: the
// new material differs by a factor of up to 3).
TEST_P(LinearSolverTest, ValuesOnlySetupEqualsAFreshSetup)
{
  Problem p;
  MakeProblem(p, 9, 7, 6, 4);
  auto reused = CreateLinearSolver(GetParam());
  reused->SetRelTol(1e-8);
  reused->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> x0, x1, x2;
  std::array<LinearSolveStats, 3> s0, s1, s2;
  ASSERT_TRUE(reused->Solve(p.System, x0, false, s0));

  // New material on the same mesh: same pattern, new values.
  OpticalProperties other = RandomMaterial(p.Mesh.GetNumberOfTets(), 99);
  for (double& v : other.ReducedScatteringCoefficient)
    v *= 3.0;
  DiffusionSystem changed;
  DiscreteDivergence().Assemble(p.Mesh, other, LightAt(p, 20.0), changed);
  ASSERT_EQ(changed.ColumnIndices, p.System.ColumnIndices);
  ASSERT_NE(changed.Values[0], p.System.Values[0]);
  p.System = changed;
  reused->Setup(p.System, &p.Mesh, false);
  ASSERT_TRUE(reused->Solve(p.System, x1, false, s1));

  auto fresh = CreateLinearSolver(GetParam());
  fresh->SetRelTol(1e-8);
  fresh->Setup(p.System, &p.Mesh, true);
  ASSERT_TRUE(fresh->Solve(p.System, x2, false, s2));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(s1[c].Iterations, s2[c].Iterations) << GetParam() << " channel " << c;
    EXPECT_LE(RelativeDifference(x1[c], x2[c]), 1e-12) << GetParam() << " channel " << c;
    // ...and it is the new system's solution, not the old one's.
    EXPECT_GT(RelativeDifference(x0[c], x2[c]), 1e-2) << GetParam() << " channel " << c;
  }
}

// A zero right-hand side gives exactly x = 0 (M is SPD), whatever the guess.
TEST_P(LinearSolverTest, ZeroRightHandSideGivesZeroSolution)
{
  Problem p;
  MakeProblem(p, 5, 4, 4, 5);
  for (auto& b : p.System.RightHandSide)
    b.setZero();
  auto solver = CreateLinearSolver(GetParam());
  solver->Setup(p.System, &p.Mesh, true);
  for (bool warm : { false, true })
  {
    std::array<Eigen::VectorXd, 3> x;
    for (auto& v : x)
      v = Eigen::VectorXd::Ones(p.System.NumberOfUnknowns);
    std::array<LinearSolveStats, 3> stats;
    ASSERT_TRUE(solver->Solve(p.System, x, warm, stats));
    for (int c = 0; c < 3; ++c)
    {
      ASSERT_EQ(x[c].size(), p.System.NumberOfUnknowns);
      EXPECT_EQ(x[c].norm(), 0.0) << GetParam() << " channel " << c << (warm ? " warm" : " cold");
      EXPECT_TRUE(stats[c].Converged);
    }
  }
}

// Names are case-insensitive and round-trip through GetName().
TEST_P(LinearSolverTest, NameRoundTrips)
{
  std::string upper = GetParam();
  std::transform(upper.begin(), upper.end(), upper.begin(), ::toupper);
  EXPECT_EQ(CreateLinearSolver(upper)->GetName(), GetParam());
}

std::string TestName(const ::testing::TestParamInfo<std::string>& info)
{
  std::string s = info.param;
  std::replace(s.begin(), s.end(), '-', '_');
  return s;
}

INSTANTIATE_TEST_SUITE_P(
  AllLinearSolvers, LinearSolverTest, ::testing::ValuesIn(GetLinearSolverNames()), TestName);

TEST(LinearSolverFactory, UnknownNameListsTheKnownOnes)
{
  const std::string message = tt::ErrorMessage([] { CreateLinearSolver("gauss-seidel-magic"); });
  EXPECT_TRUE(tt::Contains(message, "gauss-seidel-magic")) << message;
  for (const std::string& name : GetLinearSolverNames())
  {
    EXPECT_TRUE(tt::Contains(message, name)) << message;
  }
}

TEST(LinearSolverFactory, HasTheJacobiDefaultAndThePeers)
{
  const auto names = GetLinearSolverNames();
  EXPECT_TRUE(Has("cg-jacobi"));
  EXPECT_TRUE(Has("cg-ichol"));
  // Names are unique.
  auto sorted = names;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end());
}

// Solving without a Setup() for the system is a clear error, not a crash.
TEST(LinearSolverFactory, DirectSolversNeedSetup)
{
  Problem p;
  MakeProblem(p, 4, 4, 4, 6);
  for (const std::string name : { "cg-ichol", "cholmod", "hypre-amg" })
  {
    if (!Has(name))
      continue;
    auto solver = CreateLinearSolver(name);
    std::array<Eigen::VectorXd, 3> x;
    std::array<LinearSolveStats, 3> stats;
    const std::string message = tt::ErrorMessage([&] { solver->Solve(p.System, x, false, stats); });
    EXPECT_TRUE(tt::Contains(message, "Setup")) << name << ": " << message;
  }
}

// The registry (LinearSolver.h): every entry names its Krylov method and
// preconditioner and has a line of help; the two views split it by symmetry.
TEST(LinearSolverRegistry, TraitsAndViews)
{
  const LinearSolverRegistry& registry = GetLinearSolverRegistry();
  std::vector<std::string> symmetric, nonSymmetric;
  for (const auto& entry : registry.GetEntries())
  {
    EXPECT_FALSE(entry.Properties.Krylov.empty()) << entry.Name;
    EXPECT_FALSE(entry.Properties.Preconditioner.empty()) << entry.Name;
    EXPECT_FALSE(entry.Help.empty()) << entry.Name;
    EXPECT_EQ(entry.Properties.Built, entry.Properties.Library.empty() || Has(entry.Name) ||
        !entry.Properties.NeedsSymmetricPositiveDefinite)
      << entry.Name;
    if (entry.Properties.Built)
    {
      EXPECT_EQ(entry.Create()->GetName(), entry.Name);
      (entry.Properties.NeedsSymmetricPositiveDefinite ? symmetric : nonSymmetric)
        .push_back(entry.Name);
    }
  }
  EXPECT_EQ(registry.GetNames().front(), "cg-jacobi");
  EXPECT_EQ(symmetric, GetLinearSolverNames());
  EXPECT_EQ(nonSymmetric, (std::vector<std::string>{ "bicgstab", "relaxation" }));
  EXPECT_EQ(nonSymmetric, GetNonSymmetricLinearSolverNames());
  EXPECT_EQ(registry.Get("bicgstab").Properties.Krylov, "bicgstab");
  EXPECT_EQ(registry.Get("bicgstab").Properties.Preconditioner, "jacobi");
  EXPECT_EQ(registry.Get("multigrid-agg").Properties.Krylov, "cg");
  EXPECT_TRUE(registry.Get("multigrid-agg").Properties.NeedsMesh);
}

TEST(LinearSolverRegistry, EachFamilyRejectsTheOthersNames)
{
  EXPECT_EQ(CreateNonSymmetricLinearSolver("", "grid")->GetName(), "bicgstab");
  EXPECT_EQ(CreateNonSymmetricLinearSolver("Relaxation", "grid")->GetName(), "relaxation");
  std::string message =
    tt::ErrorMessage([] { CreateNonSymmetricLinearSolver("multigrid-cg", "quadgraph"); });
  EXPECT_TRUE(tt::Contains(message, "quadgraph: linear solver 'multigrid-cg'")) << message;
  EXPECT_TRUE(tt::Contains(message, "symmetric positive definite")) << message;
  EXPECT_TRUE(tt::Contains(message, "(known: bicgstab, relaxation)")) << message;
  message = tt::ErrorMessage([] { CreateNonSymmetricLinearSolver("gmres", "grid"); });
  EXPECT_EQ(message, "grid: unknown linear solver 'gmres' (known: bicgstab, relaxation)");
  message = tt::ErrorMessage([] { CreateLinearSolver("bicgstab"); });
  EXPECT_TRUE(tt::Contains(message, "unknown linear solver 'bicgstab'")) << message;
  EXPECT_TRUE(tt::Contains(message, "cg-jacobi")) << message;
}

// Every entry is a Krylov method x preconditioner composition (LinearSolver.h):
// "KRYLOV/PRECONDITIONER" names it, one entry per composition, and its
// registered name is an alias of it for both factories.
TEST(LinearSolverRegistry, EveryNameIsAnAliasOfItsComposition)
{
  std::set<std::string> compositions;
  for (const auto& entry : GetLinearSolverRegistry().GetEntries())
  {
    const std::string composition = GetLinearSolverComposition(entry.Name);
    EXPECT_EQ(composition, entry.Properties.Krylov + "/" + entry.Properties.Preconditioner);
    EXPECT_TRUE(compositions.insert(composition).second) << composition << " twice";
    EXPECT_EQ(GetLinearSolverComposition(composition), composition);
    EXPECT_EQ(ResolveLinearSolverName(composition), entry.Name);
    std::string upper = composition;
    std::transform(upper.begin(), upper.end(), upper.begin(), ::toupper);
    EXPECT_EQ(ResolveLinearSolverName(upper), entry.Name);
    if (!entry.Properties.Built)
    {
      const std::string message = tt::ErrorMessage([&] { CreateLinearSolver(composition); });
      EXPECT_TRUE(tt::Contains(message, "is not in this build")) << message;
      continue;
    }
    EXPECT_EQ(FindLinearSolver(entry.Properties.Krylov, entry.Properties.Preconditioner).Name,
      entry.Name);
    if (entry.Properties.NeedsSymmetricPositiveDefinite)
    {
      EXPECT_EQ(CreateLinearSolver(composition)->GetName(), entry.Name);
    }
    else
    {
      EXPECT_EQ(CreateNonSymmetricLinearSolver(composition, "test")->GetName(), entry.Name);
    }
  }
  EXPECT_EQ(GetLinearSolverComposition("cg-jacobi"), "cg/jacobi");
  EXPECT_EQ(GetLinearSolverComposition("Multigrid-Agg"), "cg/aggregation");
  EXPECT_EQ(ResolveLinearSolverName("cg/bogus"), "cg/bogus");
  std::string message = tt::ErrorMessage([] { CreateLinearSolver("cg/bogus"); });
  EXPECT_TRUE(tt::Contains(message, "unknown linear solver 'cg/bogus'")) << message;
  message = tt::ErrorMessage([] { CreateLinearSolver("bicgstab/jacobi"); });
  EXPECT_TRUE(tt::Contains(message, "unknown linear solver 'bicgstab/jacobi'")) << message;
  message = tt::ErrorMessage([] { FindLinearSolver("cg", "bogus"); });
  EXPECT_TRUE(tt::Contains(message, "no linear solver cg/bogus")) << message;
  message = tt::ErrorMessage([] { GetLinearSolverComposition("gmres"); });
  EXPECT_TRUE(tt::Contains(message, "gmres")) << message;
}

// An alias and its composition create the same solver: the same iterates,
// bit for bit, and the same iteration counts on the same system.
TEST(LinearSolverRegistry, AliasAndCompositionGiveTheSameIterates)
{
  Problem p;
  MakeProblem(p, 3, 3, 3, 41);
  const auto solve = [&p](std::unique_ptr<LinearSolver> solver,
                       std::array<Eigen::VectorXd, 3>& x, std::array<LinearSolveStats, 3>& stats) {
    solver->SetRelTol(1e-8);
    solver->SetMaxIter(100000);
    solver->Setup(p.System, &p.Mesh, true);
    return solver->Solve(p.System, x, false, stats);
  };
  for (const auto& entry : GetLinearSolverRegistry().GetEntries())
  {
    if (!entry.Properties.Built)
    {
      continue;
    }
    const std::string composition = GetLinearSolverComposition(entry.Name);
    const bool symmetric = entry.Properties.NeedsSymmetricPositiveDefinite;
    const auto create = [symmetric](const std::string& name) -> std::unique_ptr<LinearSolver> {
      if (symmetric)
      {
        return CreateLinearSolver(name);
      }
      return CreateNonSymmetricLinearSolver(name, "test");
    };
    std::array<Eigen::VectorXd, 3> byName, byComposition;
    std::array<LinearSolveStats, 3> nameStats, compositionStats;
    ASSERT_TRUE(solve(create(entry.Name), byName, nameStats)) << entry.Name;
    ASSERT_TRUE(solve(create(composition), byComposition, compositionStats)) << composition;
    for (int c = 0; c < 3; ++c)
    {
      EXPECT_TRUE(nameStats[c].Converged) << entry.Name << " channel " << c;
      EXPECT_EQ(nameStats[c].Iterations, compositionStats[c].Iterations) << composition;
      ASSERT_EQ(byName[c].size(), byComposition[c].size()) << composition;
      EXPECT_EQ((byName[c] - byComposition[c]).cwiseAbs().maxCoeff(), 0.0)
        << entry.Name << " and " << composition << " differ in channel " << c;
    }
  }
}

// BiCGSTAB and the relaxation also solve the symmetric systems; the two
// give the direct solution (the relaxation of QuadGraph is Jacobi).
TEST(LinearSolverRegistry, NonSymmetricSolversReachTheDirectSolution)
{
  Problem p;
  MakeProblem(p, 3, 3, 3, 21);
  const auto reference = ReferenceSolution(p.System, "");
  for (const std::string name : GetNonSymmetricLinearSolverNames())
  {
    auto solver = CreateNonSymmetricLinearSolver(name, "test");
    solver->SetRelTol(1e-10);
    solver->SetMaxIter(100000);
    std::array<Eigen::VectorXd, 3> x;
    std::array<LinearSolveStats, 3> stats;
    solver->Setup(p.System, nullptr, true);
    ASSERT_TRUE(solver->Solve(p.System, x, false, stats)) << name;
    for (int c = 0; c < 3; ++c)
    {
      EXPECT_TRUE(stats[c].Converged) << name << " channel " << c;
      EXPECT_LE(stats[c].RelativeResidual, 1e-10) << name;
      EXPECT_LT(RelativeDifference(x[c], reference[c]), 1e-6) << name << " channel " << c;
    }
  }
}

// LinearSolver::Setup decides once for every solver: rebuild on the first
// call, when the pattern changed or the size differs, else values only.
TEST(LinearSolverSetup, RebuildsOnlyWhenThePatternOrTheSizeChanged)
{
  Problem a, b;
  MakeProblem(a, 3, 3, 3, 31);
  MakeProblem(b, 4, 3, 3, 32);
  AggregationMultigridSolver solver;
  solver.Setup(a.System, &a.Mesh, false); // first call: rebuild
  EXPECT_EQ(solver.GetNumberOfHierarchyBuilds(), 1);
  solver.Setup(a.System, &a.Mesh, false); // values only
  EXPECT_EQ(solver.GetNumberOfHierarchyBuilds(), 1);
  solver.Setup(a.System, &a.Mesh, true); // pattern changed
  EXPECT_EQ(solver.GetNumberOfHierarchyBuilds(), 2);
  solver.Setup(b.System, &b.Mesh, false); // another size despite the flag
  EXPECT_EQ(solver.GetNumberOfHierarchyBuilds(), 3);
  EXPECT_EQ(solver.GetNumberOfSetups(), 4);
  // A system the checks reject leaves the last set-up as it was.
  EXPECT_THROW(solver.Setup(b.System, &a.Mesh, false), Error); // the wrong mesh
  std::array<Eigen::VectorXd, 3> x;
  std::array<LinearSolveStats, 3> stats;
  EXPECT_TRUE(solver.Solve(b.System, x, false, stats));
  solver.Setup(b.System, &b.Mesh, false);
  EXPECT_EQ(solver.GetNumberOfHierarchyBuilds(), 3);
  // Solving another system than the set-up one is an error naming Setup.
  EXPECT_TRUE(tt::Contains(
    tt::ErrorMessage([&] { solver.Solve(a.System, x, false, stats); }), "Setup"));
}

// The change rule (LinearSolver::SetChangeRule: the interactive accuracy
// rule of Documentation/Solvers.md). A relight (new right-hand side, warm
// start from the converged solution of the old light) with RelTol out of
// reach stops by the rule alone, after at least 3 iterations, with its
// estimated boundary error within tol; checked: the actual boundary error
// against a direct solve of the new system (the independent reference) is
// within tol too; off (tol 0) it never stops by change and iterates on to
// RelTol; a row out of range is refused.
TEST(LinearSolverChangeRule, StopsARelightWhenTheBoundaryStopsChanging)
{
  Problem p;
  MakeProblem(p, 24, 20, 18, 5, 0.0);
  auto solver = CreateLinearSolver("multigrid-agg");
  solver->SetRelTol(1e-14);
  solver->SetMaxIter(500);
  solver->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> previous;
  std::array<LinearSolveStats, 3> stats;
  ASSERT_TRUE(solver->Solve(p.System, previous, false, stats));
  DiffusionSystem rotated;
  DiscreteDivergence().Assemble(p.Mesh, p.Material, LightAt(p, 15.0), rotated);
  for (int c = 0; c < 3; ++c)
  {
    p.System.RightHandSide[c] = rotated.RightHandSide[c];
  }
  const auto reference = ReferenceSolution(p.System, "multigrid-agg");
  const std::vector<int>& rows = p.Mesh.GetBoundaryPoints();
  auto boundaryError = [&](const Eigen::VectorXd& x, int c) {
    double num = 0.0, den = 0.0;
    for (int i : rows)
    {
      num += (x[i] - reference[c][i]) * (x[i] - reference[c][i]);
      den += reference[c][i] * reference[c][i];
    }
    return std::sqrt(num / den);
  };

  const double tol = 3e-3;
  solver->SetChangeRule(tol, rows);
  EXPECT_EQ(solver->GetChangeTol(), tol);
  std::array<Eigen::VectorXd, 3> x = previous;
  ASSERT_TRUE(solver->Solve(p.System, x, true, stats));
  std::array<int, 3> byChange{};
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(stats[c].Converged && stats[c].StoppedByChange) << "channel " << c;
    EXPECT_GE(stats[c].Iterations, 3) << "channel " << c;
    EXPECT_LE(boundaryError(x[c], c), tol) << "channel " << c << ", " << stats[c].Iterations << " iterations";
    byChange[c] = stats[c].Iterations;
  }

  // Off: the residual rule alone, to RelTol 1e-14, iterates longer.
  solver->SetChangeRule(0.0, rows);
  x = previous;
  ASSERT_TRUE(solver->Solve(p.System, x, true, stats));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_FALSE(stats[c].StoppedByChange) << "channel " << c;
    EXPECT_GT(stats[c].Iterations, byChange[c]) << "channel " << c;
  }

  solver->SetChangeRule(tol, { 0, p.System.NumberOfUnknowns });
  x = previous;
  EXPECT_TRUE(tt::Contains(
    tt::ErrorMessage([&] { solver->Solve(p.System, x, true, stats); }), "change rule row"));
}

} // namespace
