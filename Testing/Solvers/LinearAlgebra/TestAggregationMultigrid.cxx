// "multigrid-agg" (Solvers/AggregationMultigrid): the aggregation hierarchy
// built on TransCut's independent sets (Sec. 4.1.1) and eq. 16 weights,
// checked against independent references: brute-force nearest retained
// neighbours, Galerkin operators against Eigen sparse products P^T A P,
// solutions against a sparse / dense Cholesky factorisation.
// (TestLinearSolvers also covers it: every solver of GetLinearSolverNames().)

#include "AggregationMultigrid.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "FiniteElement.h"
#include "LinearSolver.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TestRandomProblems.h"
#include "TetMesh.h"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace
{

using namespace translucency;
using translucency::testing::CubeMesh;
using translucency::testing::MeshData;
using translucency::testing::Uniform01;
using translucency::testing::RandomIrradiance;
using translucency::testing::RandomMaterial;
using translucency::testing::TwoPieces;
namespace tt = translucency::testing;

using Problem = translucency::testing::RandomProblem;

using translucency::testing::Cholesky;

double RelativeError(const Eigen::VectorXd& x, const Eigen::VectorXd& reference)
{
  return (x - reference).norm() / reference.norm();
}

bool Adjacent(const CsrPattern& g, int i, int j)
{
  return std::binary_search(
    g.Columns.begin() + g.Offsets[i], g.Columns.begin() + g.Offsets[i + 1], j);
}

std::unique_ptr<AggregationMultigridSolver> MakeSolver(int coarsest = 40)
{
  auto solver = std::make_unique<AggregationMultigridSolver>();
  solver->SetCoarsestSize(coarsest); // several levels even on small meshes
  return solver;
}

// Hierarchy invariants on every level: each aggregate has exactly one
// retained vertex (its root, the coarse vertex) and the roots are pairwise
// non-adjacent (Sec. 4.1.1 independent set); every dropped vertex is a
// neighbour of its root and no other retained neighbour is nearer (eq. 16's
// largest weight 1/|x_i - x_j|), checked by brute force.
TEST(AggregationMultigrid, HierarchyInvariants)
{
  for (std::uint64_t seed : { 1u, 2u, 3u })
  {
    Problem p(CubeMesh(9, 4.0, 0.3, seed), seed + 10);
    auto solver = MakeSolver(20);
    solver->Setup(p.System, &p.Mesh, true);
    ASSERT_GE(solver->GetNumberOfLevels(), 3);
    const auto& x = p.Mesh.GetPoints();
    auto dist2 = [&](int a, int b)
    {
      double d = 0.0;
      for (int k = 0; k < 3; ++k)
      {
        d += (x[3 * a + k] - x[3 * b + k]) * (x[3 * a + k] - x[3 * b + k]);
      }
      return d;
    };
    for (int l = 0; l + 1 < solver->GetNumberOfLevels(); ++l)
    {
      const CsrPattern& g = solver->GetPattern(l);
      const auto& agg = solver->GetAggregates(l);
      const auto& ids = solver->GetMeshIds(l);
      const auto& coarseIds = solver->GetMeshIds(l + 1);
      const int n = g.Size, nc = solver->GetLevelSize(l + 1);
      ASSERT_EQ(static_cast<int>(agg.size()), n);
      EXPECT_LT(nc, n);
      std::vector<char> retained(n, 0);
      std::vector<int> roots(nc, 0);
      for (int i = 0; i < n; ++i)
      {
        ASSERT_GE(agg[i], 0);
        ASSERT_LT(agg[i], nc);
        if (coarseIds[agg[i]] == ids[i])
        {
          retained[i] = 1;
          ++roots[agg[i]];
        }
      }
      for (int a = 0; a < nc; ++a)
      {
        EXPECT_EQ(roots[a], 1) << "level " << l << " aggregate " << a;
      }
      for (int i = 0; i < n; ++i)
      {
        bool hasRetainedNeighbour = retained[i] != 0;
        double nearest = 1e300;
        for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
        {
          const int j = g.Columns[k];
          if (j != i && retained[j])
          {
            EXPECT_FALSE(retained[i]) << "adjacent roots " << i << ", " << j << " at level " << l;
            hasRetainedNeighbour = true;
            nearest = std::min(nearest, dist2(ids[i], ids[j]));
          }
        }
        EXPECT_TRUE(hasRetainedNeighbour) << "vertex " << i << " of level " << l;
        if (!retained[i])
        {
          // The root is a neighbour at this level and a nearest one.
          int root = -1;
          for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
          {
            if (retained[g.Columns[k]] && agg[g.Columns[k]] == agg[i])
            {
              root = g.Columns[k];
            }
          }
          ASSERT_GE(root, 0) << "vertex " << i << " of level " << l;
          EXPECT_EQ(dist2(ids[i], ids[root]), nearest);
        }
      }
    }
  }
}

// The coarse operators are exactly P^T A P with the piecewise-constant P of
// the aggregates (Eigen sparse products as the reference), per channel.
TEST(AggregationMultigrid, CoarseOperatorsAreGalerkinProducts)
{
  Problem p(CubeMesh(8, 4.0, 0.3, 7), 8);
  auto solver = MakeSolver(10);
  solver->Setup(p.System, &p.Mesh, true);
  ASSERT_GE(solver->GetNumberOfLevels(), 3);
  for (int c = 0; c < 3; ++c)
  {
    Eigen::SparseMatrix<double, Eigen::RowMajor> a = p.System.Matrix(c);
    for (int l = 0; l + 1 < solver->GetNumberOfLevels(); ++l)
    {
      const auto& agg = solver->GetAggregates(l);
      std::vector<Eigen::Triplet<double>> t;
      for (std::size_t i = 0; i < agg.size(); ++i)
      {
        t.emplace_back(static_cast<int>(i), agg[i], 1.0);
      }
      Eigen::SparseMatrix<double, Eigen::RowMajor> P(agg.size(), solver->GetLevelSize(l + 1));
      P.setFromTriplets(t.begin(), t.end());
      a = Eigen::SparseMatrix<double, Eigen::RowMajor>(P.transpose() * a * P);
      const auto ours = solver->GetCoarseMatrix(l + 1, c);
      const Eigen::MatrixXd dense = Eigen::MatrixXd(a);
      EXPECT_LT((Eigen::MatrixXd(ours) - dense).norm(), 1e-12 * dense.norm())
        << "level " << l + 1 << " channel " << c;
      // Symmetric (A is) up to the rounding of the summation order.
      const Eigen::MatrixXd o = Eigen::MatrixXd(ours);
      EXPECT_LE((o - o.transpose()).norm(), 1e-14 * o.norm());
    }
  }
  EXPECT_GT(solver->GetOperatorComplexity(), 1.0);
  EXPECT_LT(solver->GetOperatorComplexity(), 2.0);
}

// Solutions equal the sparse Cholesky ones on random meshes and materials
// (discrete divergence and FEM, two separate pieces), with the defaults and
// with other smoother / correction options.
TEST(AggregationMultigrid, MatchesCholeskyOnRandomMeshesAndMaterials)
{
  struct Case
  {
    MeshData Data;
    std::uint64_t Seed;
    bool Fem;
    int Degree;
    double Scale;
    int Cycle;
  };
  std::vector<Case> cases{ { CubeMesh(10, 5.0, 0.3, 21), 22, false, 1, 1.5, 2 },
    { tt::BoxMesh(14, 6, 5, 8.0, 3.0, 2.5, 0.25, 23), 24, false, 2, 1.0, 1 },
    { CubeMesh(8, 2.0, 0.2, 25), 26, true, 3, 1.8, 3 }, { TwoPieces(6), 27, false, 1, 1.5, 1 } };
  for (const auto& test : cases)
  {
    Problem p(test.Data, test.Seed, test.Fem);
    const auto reference = Cholesky(p.System);
    auto solver = MakeSolver();
    solver->SetSmootherDegree(test.Degree);
    solver->SetCoarseCorrectionScale(test.Scale);
    solver->SetCycleIndex(test.Cycle);
    solver->SetRelTol(1e-10);
    solver->Setup(p.System, &p.Mesh, true);
    EXPECT_GE(solver->GetNumberOfLevels(), 2);
    std::array<Eigen::VectorXd, 3> x;
    std::array<LinearSolveStats, 3> stats;
    ASSERT_TRUE(solver->Solve(p.System, x, false, stats));
    for (int c = 0; c < 3; ++c)
    {
      EXPECT_TRUE(stats[c].Converged);
      const Eigen::VectorXd r = p.System.RightHandSide[c] - p.System.Matrix(c) * x[c];
      EXPECT_LE(r.norm() / p.System.RightHandSide[c].norm(), 1e-9);
      EXPECT_LT(RelativeError(x[c], reference[c]), 1e-7) << "seed " << test.Seed << " channel " << c;
      EXPECT_GT(stats[c].SpMVEquivalents, stats[c].Iterations);
    }
  }
}

// Loose tolerances use the single-precision copy of the level-0 matrix for
// CG's own products: the solver then solves the rounded system A_f x = b. The
// true residual b - A x (double matrix, computed here with Eigen) must still
// meet the tolerance up to the rounding of A_f (|A - A_f| <= 2^-24 |A| per
// entry, so |(A - A_f) x| <= 6e-8 |A| |x|, far below the tolerances where the
// copy is used); tight tolerances keep the double product.
TEST(AggregationMultigrid, SinglePrecisionProductMeetsTheTrueResidual)
{
  Problem p(CubeMesh(12, 5.0, 0.3, 51), 52);
  const auto reference = Cholesky(p.System);
  for (double tol : { 0.1, 0.03, 1e-3, 1e-4 })
  {
    auto solver = MakeSolver();
    solver->SetRelTol(tol);
    solver->Setup(p.System, &p.Mesh, true);
    ASSERT_GE(solver->GetNumberOfLevels(), 2);
    EXPECT_TRUE(solver->UsesSinglePrecisionProduct()) << tol;
    std::array<Eigen::VectorXd, 3> x;
    std::array<LinearSolveStats, 3> stats;
    ASSERT_TRUE(solver->Solve(p.System, x, false, stats));
    for (int c = 0; c < 3; ++c)
    {
      ASSERT_TRUE(stats[c].Converged);
      const Eigen::SparseMatrix<double, Eigen::RowMajor> a = p.System.Matrix(c);
      const Eigen::VectorXd& b = p.System.RightHandSide[c];
      const double trueResidual = (b - a * x[c]).norm() / b.norm();
      // |A| |x| / |b| bounds how much the rounding of A can move the residual.
      Eigen::SparseMatrix<double, Eigen::RowMajor> absA = a.cwiseAbs();
      const double rounding = 6e-8 * (absA * x[c].cwiseAbs()).norm() / b.norm();
      EXPECT_LE(trueResidual, tol + rounding) << "tol " << tol << " channel " << c;
      EXPECT_NEAR(trueResidual, stats[c].RelativeResidual, rounding) << "tol " << tol;
      // The solution error is bounded by the condition number times the
      // residual; on this mesh it is well below the residual tolerance.
      EXPECT_LT(RelativeError(x[c], reference[c]), 10.0 * tol) << "tol " << tol;
    }
  }
  auto tight = MakeSolver();
  tight->SetRelTol(1e-8);
  tight->Setup(p.System, &p.Mesh, true);
  EXPECT_FALSE(tight->UsesSinglePrecisionProduct());
  tight->SetSinglePrecisionProductTolerance(0.0); // always single
  EXPECT_TRUE(tight->UsesSinglePrecisionProduct());
}

// The V-cycle is a symmetric positive definite operator (needed by CG):
// u.B v = v.B u and v.B v > 0 for random vectors, per channel.
TEST(AggregationMultigrid, PreconditionerIsSymmetricPositive)
{
  Problem p(CubeMesh(8, 4.0, 0.3, 31), 32);
  for (int degree : { 1, 2 })
  {
    auto solver = MakeSolver(20);
    solver->SetSmootherDegree(degree);
    solver->SetCycleIndex(degree == 1 ? 2 : 1); // W- and V-cycle
    solver->Setup(p.System, &p.Mesh, true);
    const int n = p.System.NumberOfUnknowns;
    std::mt19937_64 rng(5);
    Eigen::VectorXd u(3 * n), v(3 * n), bu, bv;
    for (int k = 0; k < 3 * n; ++k)
    {
      u[k] = Uniform01(rng) - 0.5;
      v[k] = Uniform01(rng) - 0.5;
    }
    solver->ApplyPreconditioner(u, bu);
    solver->ApplyPreconditioner(v, bv);
    for (int c = 0; c < 3; ++c)
    {
      double ubv = 0, vbu = 0, vbv = 0, scale = 0;
      for (int i = 0; i < n; ++i)
      {
        ubv += u[3 * i + c] * bv[3 * i + c];
        vbu += v[3 * i + c] * bu[3 * i + c];
        vbv += v[3 * i + c] * bv[3 * i + c];
        scale += std::abs(u[3 * i + c] * bv[3 * i + c]);
      }
      // Single-precision smoother values: symmetric to float rounding.
      EXPECT_NEAR(ubv, vbu, 1e-5 * scale) << "degree " << degree << " channel " << c;
      EXPECT_GT(vbv, 0.0);
    }
  }
}

// Warm start after a small change of the right-hand side needs fewer
// iterations than a cold start; values-only Setup after a paint equals a
// fresh Setup bit for bit and keeps the hierarchy.
TEST(AggregationMultigrid, WarmStartAndValuesOnlySetup)
{
  Problem p(CubeMesh(12, 5.0, 0.3, 41), 42);
  auto solver = MakeSolver();
  solver->SetRelTol(1e-8);
  solver->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> x, xCold;
  std::array<LinearSolveStats, 3> s, cold, warm;
  ASSERT_TRUE(solver->Solve(p.System, x, false, s));
  for (int c = 0; c < 3; ++c)
  {
    for (int i = 0; i < p.System.NumberOfUnknowns; ++i)
    {
      p.System.RightHandSide[c][i] *= 1.0 + 0.01 * p.Mesh.GetPoint(i)[0] / 5.0;
    }
  }
  ASSERT_TRUE(solver->Solve(p.System, xCold, false, cold));
  ASSERT_TRUE(solver->Solve(p.System, x, true, warm));
  const auto reference = Cholesky(p.System);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(warm[c].Converged);
    EXPECT_GT(cold[c].Iterations, 2);
    EXPECT_LT(warm[c].Iterations, cold[c].Iterations) << "channel " << c;
    EXPECT_LT(RelativeError(x[c], reference[c]), 1e-5);
  }

  // Paint: new material on the same mesh, values-only Setup.
  const auto painted = RandomMaterial(p.Mesh.GetNumberOfTets(), 43);
  DiscreteDivergence().Assemble(p.Mesh, painted, RandomIrradiance(p.Mesh, 44), p.System);
  solver->Setup(p.System, &p.Mesh, false);
  EXPECT_EQ(solver->GetNumberOfHierarchyBuilds(), 1);
  EXPECT_EQ(solver->GetNumberOfSetups(), 2);
  auto fresh = MakeSolver();
  fresh->SetRelTol(1e-8);
  fresh->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> x1, x2;
  std::array<LinearSolveStats, 3> s1, s2;
  ASSERT_TRUE(solver->Solve(p.System, x1, false, s1));
  ASSERT_TRUE(fresh->Solve(p.System, x2, false, s2));
  const auto paintedReference = Cholesky(p.System);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(s1[c].Iterations, s2[c].Iterations);
    EXPECT_EQ((x1[c] - x2[c]).norm(), 0.0) << "channel " << c;
    EXPECT_LT(RelativeError(x1[c], paintedReference[c]), 1e-5);
  }
}

// SetupSharedHierarchy: a second system on the donor's mesh and pattern
// with other values (another random material, as SP3's A22 beside A11)
// set up on the donor's hierarchy equals a fresh Setup of that system: the
// same hierarchy level by level (the aggregation reads only the pattern and
// the points), the same CG iterations and bits, its residual recomputed
// here from the matrix entries within RelTol, its solution the Cholesky
// one's. The donor's own solve is unchanged, no hierarchy is built, and a
// values-only Setup of the shared solver keeps the copy.
TEST(AggregationMultigrid, SharedHierarchyEqualsAFreshSetup)
{
  Problem p(CubeMesh(12, 5.0, 0.3, 71), 72);
  auto donor = MakeSolver();
  donor->SetRelTol(1e-8);
  donor->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> xDonor, xDonorAfter;
  std::array<LinearSolveStats, 3> sDonor, sDonorAfter;
  ASSERT_TRUE(donor->Solve(p.System, xDonor, false, sDonor));

  DiffusionSystem second;
  DiscreteDivergence().Assemble(p.Mesh, RandomMaterial(p.Mesh.GetNumberOfTets(), 73),
    RandomIrradiance(p.Mesh, 74), second);
  ASSERT_EQ(second.ColumnIndices, p.System.ColumnIndices);
  ASSERT_NE(second.Values[0], p.System.Values[0]);
  auto shared = MakeSolver();
  shared->SetRelTol(1e-8);
  shared->SetupSharedHierarchy(*donor, second, &p.Mesh);
  EXPECT_TRUE(shared->HasPreconditioner());
  EXPECT_EQ(shared->GetNumberOfHierarchyBuilds(), 0);
  EXPECT_EQ(shared->GetNumberOfSharedHierarchySetups(), 1);
  EXPECT_EQ(shared->GetNumberOfSetups(), 1);
  auto fresh = MakeSolver();
  fresh->SetRelTol(1e-8);
  fresh->Setup(second, &p.Mesh, true);
  ASSERT_GE(fresh->GetNumberOfLevels(), 3);
  ASSERT_EQ(shared->GetNumberOfLevels(), fresh->GetNumberOfLevels());
  for (int l = 0; l < fresh->GetNumberOfLevels(); ++l)
  {
    EXPECT_EQ(shared->GetAggregates(l), fresh->GetAggregates(l)) << "level " << l;
    EXPECT_EQ(shared->GetMeshIds(l), fresh->GetMeshIds(l)) << "level " << l;
    EXPECT_EQ(shared->GetPattern(l).Offsets, fresh->GetPattern(l).Offsets) << "level " << l;
    EXPECT_EQ(shared->GetPattern(l).Columns, fresh->GetPattern(l).Columns) << "level " << l;
  }

  std::array<Eigen::VectorXd, 3> xShared, xFresh;
  std::array<LinearSolveStats, 3> sShared, sFresh;
  ASSERT_TRUE(shared->Solve(second, xShared, false, sShared));
  ASSERT_TRUE(fresh->Solve(second, xFresh, false, sFresh));
  const auto reference = Cholesky(second);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(sShared[c].Converged) << "channel " << c;
    EXPECT_GT(sShared[c].Iterations, 2) << "channel " << c;
    EXPECT_EQ(sShared[c].Iterations, sFresh[c].Iterations) << "channel " << c;
    EXPECT_EQ((xShared[c] - xFresh[c]).norm(), 0.0) << "channel " << c;
    // b - A x from the CSR entries (not the solver's product).
    double rr = 0.0, bb = 0.0;
    for (int i = 0; i < second.NumberOfUnknowns; ++i)
    {
      double r = second.RightHandSide[c][i];
      for (int k = second.RowOffsets[i]; k < second.RowOffsets[i + 1]; ++k)
      {
        r -= second.Values[c][k] * xShared[c][second.ColumnIndices[k]];
      }
      rr += r * r;
      bb += second.RightHandSide[c][i] * second.RightHandSide[c][i];
    }
    EXPECT_LE(std::sqrt(rr / bb), 1e-8) << "channel " << c;
    EXPECT_LT(RelativeError(xShared[c], reference[c]), 1e-6) << "channel " << c;
  }
  ASSERT_TRUE(donor->Solve(p.System, xDonorAfter, false, sDonorAfter));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ((xDonorAfter[c] - xDonor[c]).norm(), 0.0) << "channel " << c;
  }

  // New values on the shared solver: values only, still no build.
  DiscreteDivergence().Assemble(p.Mesh, RandomMaterial(p.Mesh.GetNumberOfTets(), 75),
    RandomIrradiance(p.Mesh, 76), second);
  shared->Setup(second, &p.Mesh, false);
  fresh->Setup(second, &p.Mesh, true);
  EXPECT_EQ(shared->GetNumberOfHierarchyBuilds(), 0);
  EXPECT_EQ(shared->GetNumberOfSetups(), 2);
  ASSERT_TRUE(shared->Solve(second, xShared, false, sShared));
  ASSERT_TRUE(fresh->Solve(second, xFresh, false, sFresh));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ((xShared[c] - xFresh[c]).norm(), 0.0) << "channel " << c;
  }

  // Refused: a donor without a Setup, the solver itself, another pattern.
  auto unset = MakeSolver();
  auto other = MakeSolver();
  std::string message =
    tt::ErrorMessage([&] { other->SetupSharedHierarchy(*unset, second, &p.Mesh); });
  EXPECT_TRUE(tt::Contains(message, "no successful Setup")) << message;
  EXPECT_FALSE(other->HasPreconditioner());
  message = tt::ErrorMessage([&] { shared->SetupSharedHierarchy(*shared, second, &p.Mesh); });
  EXPECT_TRUE(tt::Contains(message, "another solver")) << message;
  EXPECT_FALSE(shared->HasPreconditioner());
  Problem small(CubeMesh(4, 1.0), 77);
  message = tt::ErrorMessage([&] { other->SetupSharedHierarchy(*donor, small.System, &small.Mesh); });
  EXPECT_TRUE(tt::Contains(message, "not the donor's")) << message;
  EXPECT_FALSE(other->HasPreconditioner());
}

// A paint stroke: SetupChangedRows refreshes the level-0 single-precision
// values and l1 diagonal of the painted rows and keeps the coarse levels (the
// unpainted Galerkin values); the preconditioner stays symmetric positive,
// CG reaches the painted system's solution in a few more iterations at most,
// and CG's own single-precision products use the painted values (else the
// true residual would stall). Past the refresh fraction a row update
// recomputes every level; bad rows are named.
TEST(AggregationMultigrid, RowUpdateAfterPaint)
{
  Problem p(CubeMesh(12, 5.0, 0.3, 61), 62);
  const auto q = RandomIrradiance(p.Mesh, 63);
  DiscreteDivergence disc;
  disc.Assemble(p.Mesh, p.Material, q, p.System);
  const int n = p.System.NumberOfUnknowns;
  auto solver = MakeSolver();
  solver->Setup(p.System, &p.Mesh, true);
  ASSERT_GE(solver->GetNumberOfLevels(), 3);
  const Eigen::MatrixXd coarseBefore = Eigen::MatrixXd(solver->GetCoarseMatrix(1, 0));
  // Paint a corner: 20x absorption, 0.3x scattering.
  const std::vector<int>& tets = p.Mesh.GetTets();
  OpticalProperties painted = p.Material;
  std::vector<int> changed, rows;
  std::vector<char> isRow(n, 0);
  for (int t = 0; t < p.Mesh.GetNumberOfTets(); ++t)
  {
    const double* x0 = p.Mesh.GetPoint(tets[4 * t]);
    if (x0[0] * x0[0] + x0[1] * x0[1] + x0[2] * x0[2] < 1.6 * 1.6)
    {
      changed.push_back(t);
      for (int c = 0; c < 3; ++c)
      {
        painted.AbsorptionCoefficient[3 * t + c] *= 20.0;
        painted.ReducedScatteringCoefficient[3 * t + c] *= 0.3;
      }
      for (int v = 0; v < 4; ++v)
      {
        rows.push_back(tets[4 * t + v]);
        isRow[tets[4 * t + v]] = 1;
      }
    }
  }
  const int distinct = static_cast<int>(std::count(isRow.begin(), isRow.end(), 1));
  ASSERT_GT(distinct, n / 100);
  ASSERT_LT(distinct, n / 10);
  disc.UpdateTets(p.Mesh, painted, q, changed, p.System);
  solver->SetupChangedRows(p.System, &p.Mesh, rows);
  EXPECT_EQ(solver->GetNumberOfRowSetups(), 1);
  EXPECT_EQ(solver->GetNumberOfSetups(), 1);
  EXPECT_EQ(solver->GetNumberOfStaleRows(), distinct);
  EXPECT_EQ((Eigen::MatrixXd(solver->GetCoarseMatrix(1, 0)) - coarseBefore).norm(), 0.0);

  // Symmetric positive preconditioner.
  std::mt19937_64 rng(7);
  Eigen::VectorXd u(3 * n), v(3 * n), bu, bv;
  for (int k = 0; k < 3 * n; ++k)
  {
    u[k] = Uniform01(rng) - 0.5;
    v[k] = Uniform01(rng) - 0.5;
  }
  solver->ApplyPreconditioner(u, bu);
  solver->ApplyPreconditioner(v, bv);
  EXPECT_NEAR(u.dot(bv), v.dot(bu), 1e-5 * (u.cwiseAbs().dot(bv.cwiseAbs())));
  EXPECT_GT(v.dot(bv), 0.0);

  // Against a fresh set-up of the painted system, at a tolerance with
  // single-precision products (1e-4) and a tight one (1e-9).
  auto fresh = MakeSolver();
  fresh->Setup(p.System, &p.Mesh, true);
  const auto reference = Cholesky(p.System);
  for (const double tol : { 1e-4, 1e-9 })
  {
    solver->SetRelTol(tol);
    fresh->SetRelTol(tol);
    EXPECT_EQ(solver->UsesSinglePrecisionProduct(), tol >= 1e-5);
    std::array<Eigen::VectorXd, 3> x, xf;
    std::array<LinearSolveStats, 3> s, sf;
    ASSERT_TRUE(solver->Solve(p.System, x, false, s));
    ASSERT_TRUE(fresh->Solve(p.System, xf, false, sf));
    for (int c = 0; c < 3; ++c)
    {
      EXPECT_TRUE(s[c].Converged) << "tol " << tol << " channel " << c;
      EXPECT_LE(s[c].Iterations, sf[c].Iterations + 3) << "tol " << tol << " channel " << c;
      const double trueResidual =
        (p.System.RightHandSide[c] - p.System.Matrix(c) * x[c]).norm() /
        p.System.RightHandSide[c].norm();
      EXPECT_LT(trueResidual, 10 * tol) << "tol " << tol << " channel " << c;
      EXPECT_LT(RelativeError(x[c], reference[c]), tol < 1e-8 ? 1e-6 : 1e-2)
        << "tol " << tol << " channel " << c;
    }
  }

  // The same rows again do not add stale rows; past the fraction (0 here)
  // every level is recomputed and equals a fresh set-up's.
  solver->SetupChangedRows(p.System, &p.Mesh, rows);
  EXPECT_EQ(solver->GetNumberOfRowSetups(), 2);
  EXPECT_EQ(solver->GetNumberOfStaleRows(), distinct);
  solver->SetCoarseRefreshFraction(0.0);
  solver->SetupChangedRows(p.System, &p.Mesh, { rows[0] });
  EXPECT_EQ(solver->GetNumberOfRowSetups(), 2);
  EXPECT_EQ(solver->GetNumberOfSetups(), 2);
  EXPECT_EQ(solver->GetNumberOfStaleRows(), 0);
  EXPECT_EQ((Eigen::MatrixXd(solver->GetCoarseMatrix(1, 0)) -
              Eigen::MatrixXd(fresh->GetCoarseMatrix(1, 0)))
              .norm(),
    0.0);

  // Bad rows: out of range, a NaN in a changed row (then the solver is not
  // ready and the next row update is a full set-up).
  solver->SetCoarseRefreshFraction(0.1);
  std::string message =
    tt::ErrorMessage([&] { solver->SetupChangedRows(p.System, &p.Mesh, { 3, n + 2 }); });
  EXPECT_TRUE(tt::Contains(message, "changed row " + std::to_string(n + 2))) << message;
  EXPECT_TRUE(tt::Contains(message, "out of range")) << message;
  DiffusionSystem bad = p.System;
  bad.Values[1][bad.RowOffsets[rows[0]]] = std::nan("");
  message = tt::ErrorMessage([&] { solver->SetupChangedRows(bad, &p.Mesh, { rows[0] }); });
  EXPECT_TRUE(tt::Contains(message, "row " + std::to_string(rows[0]) + " (level 0)")) << message;
  EXPECT_TRUE(tt::Contains(message, "not SPD")) << message;
  std::array<Eigen::VectorXd, 3> x;
  std::array<LinearSolveStats, 3> s;
  EXPECT_TRUE(tt::Contains(
    tt::ErrorMessage([&] { solver->Solve(p.System, x, false, s); }), "before Setup"));
  solver->SetupChangedRows(p.System, &p.Mesh, { rows[0] });
  EXPECT_EQ(solver->GetNumberOfHierarchyBuilds(), 2);
  EXPECT_EQ(solver->GetNumberOfRowSetups(), 2);
}

// Recycled solutions (a light being dragged): right-hand sides b(t) =
// cos t b_a + sin t b_b, solved for t = 0, 0.1, 0.2 with 3 solutions kept;
// the warm solve at t = 0.3 starts from their A-norm-best combination (the
// exact solution lies in their span) and needs fewer iterations than a
// solver without them on the same sequence, with the same accuracy. A
// Setup forgets them; tight tolerances (double products) do not use them.
TEST(AggregationMultigrid, RecycledSolutionsOnALightSweep)
{
  Problem p(CubeMesh(12, 5.0, 0.3, 71), 72);
  DiffusionSystem other;
  DiscreteDivergence().Assemble(p.Mesh, p.Material, RandomIrradiance(p.Mesh, 73), other);
  const auto ba = p.System.RightHandSide;
  const auto bb = other.RightHandSide;
  auto sweep = [&](AggregationMultigridSolver& solver, double tol, std::array<Eigen::VectorXd, 3>& x,
                 std::array<LinearSolveStats, 3>& last)
  {
    solver.SetRelTol(tol);
    for (int f = 0; f < 4; ++f)
    {
      for (int c = 0; c < 3; ++c)
      {
        p.System.RightHandSide[c] = std::cos(0.1 * f) * ba[c] + std::sin(0.1 * f) * bb[c];
      }
      ASSERT_TRUE(solver.Solve(p.System, x, f > 0, last));
    }
  };
  auto recycling = MakeSolver();
  recycling->SetRecycledSolutions(3);
  EXPECT_EQ(recycling->GetRecycledSolutions(), 3);
  recycling->Setup(p.System, &p.Mesh, true);
  auto plain = MakeSolver();
  plain->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> x, y;
  std::array<LinearSolveStats, 3> s, t;
  sweep(*recycling, 1e-4, x, s);
  sweep(*plain, 1e-4, y, t);
  const auto reference = Cholesky(p.System);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(s[c].Converged);
    EXPECT_LT(s[c].Iterations, t[c].Iterations) << "channel " << c;
    const double trueResidual = (p.System.RightHandSide[c] - p.System.Matrix(c) * x[c]).norm() /
      p.System.RightHandSide[c].norm();
    EXPECT_LT(trueResidual, 1e-3) << "channel " << c;
    EXPECT_LT(RelativeError(x[c], reference[c]), 1e-2) << "channel " << c;
  }
  // After a Setup the kept solutions are gone: the same warm solve as
  // without them, iteration for iteration.
  recycling->Setup(p.System, &p.Mesh, false);
  plain->Setup(p.System, &p.Mesh, false);
  std::array<Eigen::VectorXd, 3> x1 = y, y1 = y;
  ASSERT_TRUE(recycling->Solve(p.System, x1, true, s));
  ASSERT_TRUE(plain->Solve(p.System, y1, true, t));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(s[c].Iterations, t[c].Iterations) << "channel " << c;
  }
  // Double-precision products (tolerance 1e-9): not used.
  sweep(*recycling, 1e-9, x, s);
  sweep(*plain, 1e-9, y, t);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(s[c].Iterations, t[c].Iterations) << "channel " << c;
    EXPECT_LT(RelativeError(x[c], Cholesky(p.System)[c]), 1e-6) << "channel " << c;
  }
}

// Recycled solutions kept in double precision (SetRecycleInDoublePrecision,
// the time stepper's setting): used at a tight tolerance too (double
// products, where the single-precision ones are not), with fewer iterations
// on the same light sweep and the accuracy of the plain solver.
TEST(AggregationMultigrid, DoublePrecisionRecyclingAtTightTolerance)
{
  Problem p(CubeMesh(12, 5.0, 0.3, 71), 72);
  DiffusionSystem other;
  DiscreteDivergence().Assemble(p.Mesh, p.Material, RandomIrradiance(p.Mesh, 73), other);
  const auto ba = p.System.RightHandSide;
  const auto bb = other.RightHandSide;
  auto sweep = [&](AggregationMultigridSolver& solver, std::array<Eigen::VectorXd, 3>& x,
                 std::array<LinearSolveStats, 3>& last)
  {
    solver.SetRelTol(1e-9);
    for (int f = 0; f < 4; ++f)
    {
      for (int c = 0; c < 3; ++c)
      {
        p.System.RightHandSide[c] = std::cos(0.1 * f) * ba[c] + std::sin(0.1 * f) * bb[c];
      }
      ASSERT_TRUE(solver.Solve(p.System, x, f > 0, last));
    }
  };
  auto recycling = MakeSolver();
  EXPECT_FALSE(recycling->GetRecycleInDoublePrecision());
  recycling->SetRecycledSolutions(3);
  recycling->SetRecycleInDoublePrecision(true);
  EXPECT_TRUE(recycling->GetRecycleInDoublePrecision());
  recycling->Setup(p.System, &p.Mesh, true);
  EXPECT_FALSE(recycling->UsesSinglePrecisionProduct());
  auto plain = MakeSolver();
  plain->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> x, y;
  std::array<LinearSolveStats, 3> s, t;
  sweep(*recycling, x, s);
  sweep(*plain, y, t);
  const auto reference = Cholesky(p.System);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(s[c].Converged);
    EXPECT_LT(s[c].Iterations, t[c].Iterations) << "channel " << c;
    const double trueResidual = (p.System.RightHandSide[c] - p.System.Matrix(c) * x[c]).norm() /
      p.System.RightHandSide[c].norm();
    EXPECT_LT(trueResidual, 1e-8) << "channel " << c;
    EXPECT_LT(RelativeError(x[c], reference[c]), 1e-6) << "channel " << c;
  }
}

// The build and the solve give bit-identical results on 1 and 2 threads.
TEST(AggregationMultigrid, OneAndTwoThreadsIdentical)
{
  Problem p(CubeMesh(12, 5.0, 0.3, 51), 52);
  std::array<std::array<Eigen::VectorXd, 3>, 2> x;
  std::array<std::array<LinearSolveStats, 3>, 2> s;
  std::array<std::vector<int>, 2> aggregates;
  const int before = omp_get_max_threads();
  for (int t : { 0, 1 })
  {
    omp_set_num_threads(t + 1);
    auto solver = MakeSolver();
    solver->SetRelTol(1e-9);
    solver->Setup(p.System, &p.Mesh, true);
    aggregates[t] = solver->GetAggregates(0);
    ASSERT_TRUE(solver->Solve(p.System, x[t], false, s[t]));
  }
  omp_set_num_threads(before);
  EXPECT_EQ(aggregates[0], aggregates[1]);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(s[0][c].Iterations, s[1][c].Iterations);
    EXPECT_EQ((x[0][c] - x[1][c]).norm(), 0.0) << "channel " << c;
  }
}

/// A hand-made SPD system on a path of n vertices along x (1 mm apart),
/// optionally cut into two pieces between vertices n/2 - 1 and n/2:
/// kappa-weighted graph Laplacian plus absorption, per channel.
void PathSystem(int n, bool twoPieces, DiffusionSystem& s, TetMesh& mesh)
{
  std::vector<double> points;
  for (int i = 0; i < n; ++i)
  {
    points.insert(points.end(), { static_cast<double>(i), 0.0, 0.0 });
  }
  mesh.SetGeometry(points, {});
  s.NumberOfUnknowns = n;
  s.RowOffsets.assign(1, 0);
  s.ColumnIndices.clear();
  auto linked = [&](int i, int j)
  { return j >= 0 && j < n && !(twoPieces && std::min(i, j) == n / 2 - 1 && std::max(i, j) == n / 2); };
  for (int i = 0; i < n; ++i)
  {
    for (int j : { i - 1, i, i + 1 })
    {
      if (j == i || linked(i, j))
      {
        s.ColumnIndices.push_back(j);
      }
    }
    s.RowOffsets.push_back(static_cast<int>(s.ColumnIndices.size()));
  }
  for (int c = 0; c < 3; ++c)
  {
    const double kappa = 0.3 + 0.2 * c, absorption = 0.01 * (c + 1);
    s.Values[c].clear();
    s.RightHandSide[c].resize(n);
    for (int i = 0; i < n; ++i)
    {
      double diagonal = absorption * (1.0 + 0.1 * i);
      for (int k = s.RowOffsets[i]; k < s.RowOffsets[i + 1]; ++k)
      {
        if (s.ColumnIndices[k] != i)
        {
          diagonal += kappa;
        }
      }
      for (int k = s.RowOffsets[i]; k < s.RowOffsets[i + 1]; ++k)
      {
        s.Values[c].push_back(s.ColumnIndices[k] == i ? diagonal : -kappa);
      }
      s.RightHandSide[c][i] = 1.0 + std::sin(1.0 + i + c);
    }
  }
}

// Meshes of 1, 2 and 10 vertices and a disconnected one (two paths), with the
// automatic hierarchy and with forced coarsening (several levels): the
// solution equals a dense LDL^T one.
TEST(AggregationMultigrid, TinyAndDisconnectedSystems)
{
  struct Case
  {
    int N;
    bool TwoPieces;
  };
  for (const Case test : { Case{ 1, false }, Case{ 2, false }, Case{ 10, false }, Case{ 10, true },
         Case{ 40, true } })
  {
    DiffusionSystem s;
    TetMesh mesh;
    PathSystem(test.N, test.TwoPieces, s, mesh);
    for (int levels : { 0, 4 })
    {
      auto solver = MakeSolver(1);
      solver->SetMaxLevels(levels);
      solver->SetRelTol(1e-12);
      solver->Setup(s, &mesh, true);
      if (test.N >= 10)
      {
        EXPECT_GE(solver->GetNumberOfLevels(), 2) << test.N << " vertices";
      }
      std::array<Eigen::VectorXd, 3> x;
      std::array<LinearSolveStats, 3> stats;
      ASSERT_TRUE(solver->Solve(s, x, false, stats));
      for (int c = 0; c < 3; ++c)
      {
        const Eigen::MatrixXd a = Eigen::MatrixXd(s.Matrix(c));
        const Eigen::VectorXd exact = a.ldlt().solve(s.RightHandSide[c]);
        EXPECT_LT(RelativeError(x[c], exact), 1e-10)
          << test.N << " vertices, two pieces " << test.TwoPieces << ", levels " << levels;
      }
    }
  }
}

TEST(AggregationMultigrid, BadInput)
{
  Problem p(CubeMesh(4, 1.0), 60);
  auto solver = MakeSolver();
  EXPECT_TRUE(tt::Contains(tt::ErrorMessage([&] { solver->Setup(p.System, nullptr, true); }),
    "needs the mesh"));
  std::array<Eigen::VectorXd, 3> x;
  std::array<LinearSolveStats, 3> stats;
  EXPECT_TRUE(tt::Contains(
    tt::ErrorMessage([&] { solver->Solve(p.System, x, false, stats); }), "before Setup"));
  solver->Setup(p.System, &p.Mesh, true);
  DiffusionSystem other = p.System;
  other.RightHandSide[1].resize(3);
  EXPECT_TRUE(tt::Contains(
    tt::ErrorMessage([&] { solver->Solve(other, x, false, stats); }), "does not match"));
  // A non-positive diagonal entry (row 5, channel 2) is named.
  other = p.System;
  for (int k = other.RowOffsets[5]; k < other.RowOffsets[6]; ++k)
  {
    if (other.ColumnIndices[k] == 5)
    {
      other.Values[2][k] = -1.0;
    }
  }
  std::string message = tt::ErrorMessage([&] { solver->Setup(other, &p.Mesh, false); });
  EXPECT_TRUE(tt::Contains(message, "row 5")) << message;
  EXPECT_TRUE(tt::Contains(message, "not SPD")) << message;
  // A NaN value.
  other = p.System;
  other.Values[0][other.RowOffsets[7]] = std::nan("");
  message = tt::ErrorMessage([&] { solver->Setup(other, &p.Mesh, true); });
  EXPECT_TRUE(tt::Contains(message, "row 7")) << message;
  // A column index out of range (row 9) when the pattern is new.
  other = p.System;
  other.ColumnIndices[other.RowOffsets[9]] = p.System.NumberOfUnknowns + 5;
  message = tt::ErrorMessage([&] { solver->Setup(other, &p.Mesh, true); });
  EXPECT_TRUE(tt::Contains(message, "row 9")) << message;
  EXPECT_TRUE(tt::Contains(message, "out of range")) << message;
  // A mesh that does not match the system.
  Problem small(CubeMesh(2, 1.0), 61);
  message = tt::ErrorMessage([&] { solver->Setup(p.System, &small.Mesh, true); });
  EXPECT_TRUE(tt::Contains(message, "does not match the mesh")) << message;
  // Zero right-hand side: zero solution, no iterations.
  solver->Setup(p.System, &p.Mesh, true);
  for (auto& b : p.System.RightHandSide)
  {
    b.setZero();
  }
  ASSERT_TRUE(solver->Solve(p.System, x, false, stats));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(x[c].norm(), 0.0);
    EXPECT_EQ(stats[c].Iterations, 0);
  }
}

} // namespace
