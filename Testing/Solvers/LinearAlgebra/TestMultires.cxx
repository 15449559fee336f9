// The TransCut multiresolution hierarchy (Sec. 4.1-4.2) and the two linear
// solvers built on it ("transcut-multires", "multigrid-cg"): hierarchy
// invariants checked against their definitions, coarse operators against
// Eigen sparse products, solutions against sparse Cholesky.

#include "DiffusionSolverFactory.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "FiniteElement.h"
#include "LinearSolver.h"
#include "MultiresHierarchy.h"
#include "MultiresSolvers.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TestRandomProblems.h"
#include "TetMesh.h"
#include "VertexDiffusionSolver.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <omp.h>

#include <cmath>
#include <random>
#include <set>

namespace
{

using namespace translucency;
using translucency::testing::CubeMesh;
using translucency::testing::MeshData;
using translucency::testing::MakeProblem;
using translucency::testing::Uniform01;
using translucency::testing::RandomIrradiance;
using translucency::testing::RandomMaterial;
using translucency::testing::TwoPieces;

bool Adjacent(const CsrPattern& g, int i, int j)
{
  return std::binary_search(
    g.Columns.begin() + g.Offsets[i], g.Columns.begin() + g.Offsets[i + 1], j);
}

using translucency::testing::Cholesky;

/// Eq. 16 as an Eigen matrix.
Eigen::SparseMatrix<double, Eigen::RowMajor> Interpolation(
  const MultiresHierarchy& h, int l)
{
  const auto& level = h.GetLevel(l);
  const int n = level.Graph.Size, nc = h.GetLevel(l + 1).Graph.Size;
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i)
  {
    for (int p = level.InterpolationOffsets[i]; p < level.InterpolationOffsets[i + 1]; ++p)
    {
      t.emplace_back(i, level.InterpolationColumns[p], level.InterpolationWeights[p]);
    }
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> p(n, nc);
  p.setFromTriplets(t.begin(), t.end());
  return p;
}

/// Checks the Sec. 4.1 invariants of every level against their definitions.
void CheckInvariants(const MultiresHierarchy& h, const std::vector<double>& points)
{
  for (int l = 0; l + 1 < h.GetNumberOfLevels(); ++l)
  {
    SCOPED_TRACE("level " + std::to_string(l));
    const auto& level = h.GetLevel(l);
    const CsrPattern& g = level.Graph;
    const int n = g.Size;
    ASSERT_EQ(static_cast<int>(level.CoarseIds.size()), n);
    ASSERT_EQ(static_cast<int>(level.FirstPicks.size()), n);
    auto kept = [&](int i) { return level.CoarseIds[i] >= 0; };
    int retained = 0;
    for (int i = 0; i < n; ++i)
    {
      retained += kept(i) ? 1 : 0;
      // First picks are retained and never adjacent (Sec. 4.1.1).
      if (level.FirstPicks[i])
      {
        EXPECT_TRUE(kept(i));
        for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
        {
          const int j = g.Columns[k];
          if (j != i)
          {
            EXPECT_FALSE(level.FirstPicks[j]) << "picks " << i << " and " << j << " adjacent";
          }
        }
      }
      if (!kept(i))
      {
        // Every dropped vertex has a retained neighbour (eq. 16 defined), and
        // its interpolation weights are 1/|x_i - x_j| normalised.
        double lambda = 0.0;
        std::vector<std::pair<int, double>> expected;
        for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
        {
          const int j = g.Columns[k];
          if (kept(j))
          {
            const int mi = level.MeshIds[i], mj = level.MeshIds[j];
            const double d = std::sqrt(std::pow(points[3 * mi] - points[3 * mj], 2) +
              std::pow(points[3 * mi + 1] - points[3 * mj + 1], 2) +
              std::pow(points[3 * mi + 2] - points[3 * mj + 2], 2));
            expected.emplace_back(level.CoarseIds[j], 1.0 / d);
            lambda += 1.0 / d;
          }
        }
        ASSERT_FALSE(expected.empty()) << "dropped vertex " << i << " has no retained neighbour";
        const int begin = level.InterpolationOffsets[i];
        ASSERT_EQ(level.InterpolationOffsets[i + 1] - begin, static_cast<int>(expected.size()));
        for (std::size_t e = 0; e < expected.size(); ++e)
        {
          EXPECT_EQ(level.InterpolationColumns[begin + e], expected[e].first);
          EXPECT_NEAR(level.InterpolationWeights[begin + e], expected[e].second / lambda, 1e-14);
        }
        // Enhancement (Sec. 4.1.3): no edge between two dropped vertices
        // loses its connection.
        for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
        {
          const int j = g.Columns[k];
          if (j == i || kept(j))
          {
            continue;
          }
          bool shared = false;
          for (int m = g.Offsets[i]; m < g.Offsets[i + 1] && !shared; ++m)
          {
            const int c = g.Columns[m];
            shared = kept(c) && Adjacent(g, j, c);
          }
          EXPECT_TRUE(shared) << "edge " << i << "-" << j << " lost at level " << l + 1;
        }
      }
    }
    // The coarse edge set (Sec. 4.1.2-4.1.3), built here by its definition:
    // pairs of retained one-ring neighbours of each dropped vertex, and the
    // level-l edges between retained vertices.
    std::set<std::pair<int, int>> edges;
    for (int i = 0; i < n; ++i)
    {
      for (int a = g.Offsets[i]; a < g.Offsets[i + 1]; ++a)
      {
        const int ja = g.Columns[a];
        if (!kept(ja))
        {
          continue;
        }
        if (kept(i) && ja != i)
        {
          edges.emplace(level.CoarseIds[i], level.CoarseIds[ja]);
        }
        if (!kept(i))
        {
          for (int b = g.Offsets[i]; b < g.Offsets[i + 1]; ++b)
          {
            const int jb = g.Columns[b];
            if (kept(jb) && jb != ja)
            {
              edges.emplace(level.CoarseIds[ja], level.CoarseIds[jb]);
            }
          }
        }
      }
    }
    const CsrPattern& cg = h.GetLevel(l + 1).Graph;
    ASSERT_EQ(cg.Size, retained);
    std::set<std::pair<int, int>> got;
    for (int a = 0; a < cg.Size; ++a)
    {
      EXPECT_TRUE(Adjacent(cg, a, a)) << "coarse row " << a << " lacks its diagonal";
      for (int k = cg.Offsets[a]; k < cg.Offsets[a + 1]; ++k)
      {
        if (k > cg.Offsets[a])
        {
          EXPECT_LT(cg.Columns[k - 1], cg.Columns[k]) << "coarse row " << a << " not sorted/unique";
        }
        if (cg.Columns[k] != a)
        {
          got.emplace(a, cg.Columns[k]);
        }
      }
    }
    EXPECT_TRUE(got == edges) << "coarse edge set differs from its definition";
  }
}

TEST(MultiresHierarchy, InvariantsOnRandomMeshes)
{
  for (std::uint64_t seed : { 1u, 2u, 3u })
  {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const auto data = CubeMesh(9, 4.0, 0.3, seed);
    TetMesh mesh;
    mesh.SetGeometry(data.Points, data.Tets);
    MultiresHierarchy h;
    h.SetCoarsestSize(20);
    h.Build(mesh);
    ASSERT_GE(h.GetNumberOfLevels(), 3);
    EXPECT_LE(h.GetLevel(h.GetNumberOfLevels() - 1).Graph.Size, 20);
    CheckInvariants(h, mesh.GetPoints());
    for (int l = 0; l + 1 < h.GetNumberOfLevels(); ++l)
    {
      EXPECT_LT(h.GetLevel(l + 1).Graph.Size, h.GetLevel(l).Graph.Size);
    }
  }
}

TEST(MultiresHierarchy, UserSetLevels)
{
  const auto data = CubeMesh(8, 4.0, 0.3, 4);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  MultiresHierarchy h;
  h.SetMaxLevels(2);
  h.Build(mesh);
  EXPECT_EQ(h.GetNumberOfLevels(), 2);
  CheckInvariants(h, mesh.GetPoints());
}

TEST(MultiresHierarchy, ParallelBuildEqualsSerial)
{
  const auto data = CubeMesh(14, 4.0, 0.3, 8);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  MultiresHierarchy serial, parallel;
  serial.SetNumberOfThreads(1);
  serial.SetCoarsestSize(30);
  parallel.SetNumberOfThreads(std::max(2, omp_get_max_threads()));
  parallel.SetCoarsestSize(30);
  serial.Build(mesh);
  parallel.Build(mesh);
  ASSERT_EQ(serial.GetNumberOfLevels(), parallel.GetNumberOfLevels());
  for (int l = 0; l < serial.GetNumberOfLevels(); ++l)
  {
    const auto& a = serial.GetLevel(l);
    const auto& b = parallel.GetLevel(l);
    EXPECT_EQ(a.Graph.Offsets, b.Graph.Offsets);
    EXPECT_EQ(a.Graph.Columns, b.Graph.Columns);
    EXPECT_EQ(a.CoarseIds, b.CoarseIds);
    EXPECT_EQ(a.FirstPicks, b.FirstPicks);
    EXPECT_EQ(a.InterpolationColumns, b.InterpolationColumns);
    EXPECT_EQ(a.InterpolationWeights, b.InterpolationWeights);
  }
  // And the coarse operators' values (Galerkin, three channels).
  const MaterialPreset& marble = FindMaterialPreset("marble");
  const auto material = RandomMaterial(mesh.GetNumberOfTets(), 3);
  DiffusionSystem system;
  DiscreteDivergence().Assemble(mesh, material, RandomIrradiance(mesh, 4), system);
  (void)marble;
  MultigridConjugateGradient s1, s2;
  s1.SetNumberOfThreads(1);
  s2.SetNumberOfThreads(2);
  s1.Setup(system, &mesh, true);
  s2.Setup(system, &mesh, true);
  for (int l = 1; l < s1.GetHierarchy().GetNumberOfLevels(); ++l)
  {
    for (int c = 0; c < 3; ++c)
    {
      const auto a = s1.GetCoarseMatrix(l, c), b = s2.GetCoarseMatrix(l, c);
      ASSERT_EQ(a.nonZeros(), b.nonZeros());
      EXPECT_TRUE(std::equal(a.valuePtr(), a.valuePtr() + a.nonZeros(), b.valuePtr()));
    }
  }
}

TEST(MultiresHierarchy, IndependentSetIsMaximalAndIndependent)
{
  const auto data = CubeMesh(7, 3.0, 0.3, 9);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  CsrPattern g;
  g.Size = mesh.GetNumberOfPoints();
  g.Offsets = mesh.GetRowOffsets();
  g.Columns = mesh.GetColumnIndices();
  // Candidate set: every other vertex.
  std::vector<char> inQ(g.Size, 0);
  for (int i = 0; i < g.Size; i += 2)
  {
    inQ[i] = 1;
  }
  std::vector<char> picked;
  MultiresHierarchy::IndependentSet(g, inQ, 0, picked, 2);
  for (int i = 0; i < g.Size; ++i)
  {
    if (!inQ[i])
    {
      EXPECT_FALSE(picked[i]);
      continue;
    }
    bool pickedNeighbour = false;
    for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
    {
      const int j = g.Columns[k];
      if (j != i && picked[j])
      {
        pickedNeighbour = true;
        EXPECT_FALSE(picked[i]) << i << " and " << j;
      }
    }
    EXPECT_TRUE(picked[i] || pickedNeighbour) << "candidate " << i << " neither picked nor covered";
  }
  // Codes: random high bits, index low bits, unique.
  EXPECT_EQ(MultiresHierarchy::Code(12345, 0) & 0xffffffffu, 12345u);
  EXPECT_NE(MultiresHierarchy::Code(1, 0) >> 32, MultiresHierarchy::Code(1, 1) >> 32);
}

TEST(MultiresHierarchy, TinyAndDisconnectedGraphs)
{
  // One vertex: a single level.
  {
    MultiresHierarchy h;
    h.SetMaxLevels(4);
    h.Build({ 0.0, 0.0, 0.0 }, { 0, 0 }, {});
    EXPECT_EQ(h.GetNumberOfLevels(), 1);
  }
  // Two connected vertices: the one with the smaller code is kept.
  {
    MultiresHierarchy h;
    h.SetMaxLevels(4);
    h.Build({ 0.0, 0.0, 0.0, 1.0, 0.0, 0.0 }, { 0, 1, 2 }, { 1, 0 });
    ASSERT_EQ(h.GetNumberOfLevels(), 2);
    EXPECT_EQ(h.GetLevel(1).Graph.Size, 1);
    const int kept = MultiresHierarchy::Code(0, 0) < MultiresHierarchy::Code(1, 0) ? 0 : 1;
    EXPECT_EQ(h.GetLevel(0).CoarseIds[kept], 0);
    EXPECT_EQ(h.GetLevel(0).CoarseIds[1 - kept], -1);
    EXPECT_EQ(h.GetLevel(0).InterpolationWeights[1 - kept], 1.0);
  }
  // Ten vertices on a path.
  {
    std::vector<double> points;
    std::vector<int> offsets{ 0 }, columns;
    for (int i = 0; i < 10; ++i)
    {
      points.insert(points.end(), { 0.5 * i, 0.0, 0.0 });
      if (i > 0)
      {
        columns.push_back(i - 1);
      }
      if (i < 9)
      {
        columns.push_back(i + 1);
      }
      offsets.push_back(static_cast<int>(columns.size()));
    }
    MultiresHierarchy h;
    h.SetMaxLevels(5);
    h.Build(points, offsets, columns);
    EXPECT_GE(h.GetNumberOfLevels(), 2);
    CheckInvariants(h, points);
  }
  // Bad graphs fail with a message naming the problem.
  {
    MultiresHierarchy h;
    h.SetMaxLevels(3); // coarsen even these tiny graphs
    EXPECT_TRUE(translucency::testing::Contains(
      translucency::testing::ErrorMessage([&] { h.Build({ 0, 0, 0, 1, 0, 0 }, { 0, 1, 1 }, { 1 }); }),
      "not symmetric"));
    EXPECT_TRUE(translucency::testing::Contains(
      translucency::testing::ErrorMessage([&] { h.Build({ 0, 0, 0, 0, 0, 0 }, { 0, 1, 2 }, { 1, 0 }); }),
      "same position"));
    EXPECT_TRUE(translucency::testing::Contains(
      translucency::testing::ErrorMessage([&] { h.Build({ 0, 0, 0 }, { 0, 1 }, { 3 }); }), "out of range"));
  }
  // Two pieces: the hierarchy keeps them apart and stays valid.
  {
    const auto data = TwoPieces(5);
    TetMesh mesh;
    mesh.SetGeometry(data.Points, data.Tets);
    MultiresHierarchy h;
    h.SetCoarsestSize(10);
    h.Build(mesh);
    CheckInvariants(h, mesh.GetPoints());
    const int half = data.NumberOfPoints() / 2;
    for (int l = 1; l < h.GetNumberOfLevels(); ++l)
    {
      const auto& level = h.GetLevel(l);
      for (int a = 0; a < level.Graph.Size; ++a)
      {
        for (int k = level.Graph.Offsets[a]; k < level.Graph.Offsets[a + 1]; ++k)
        {
          EXPECT_EQ(level.MeshIds[a] < half, level.MeshIds[level.Graph.Columns[k]] < half);
        }
      }
    }
  }
}

using Problem = translucency::testing::RandomProblem;

double RelativeError(const Eigen::VectorXd& x, const Eigen::VectorXd& reference)
{
  return (x - reference).norm() / reference.norm();
}

TEST(MultiresSolvers, CoarseOperatorsMatchSparseProducts)
{
  Problem p(CubeMesh(8, 4.0, 0.3, 11), 12);
  MultigridConjugateGradient mg, sparse;
  TransCutMultiresSolver tc;
  mg.SetCoarsestSize(20);
  mg.SetExactGalerkinLevels(-1); // every level exact P^T A P
  tc.SetCoarsestSize(20);
  sparse.SetCoarsestSize(20);
  sparse.SetSparseGalerkin(true);
  mg.Setup(p.System, &p.Mesh, true);
  tc.Setup(p.System, &p.Mesh, true);
  sparse.Setup(p.System, &p.Mesh, true);
  const auto& h = mg.GetHierarchy();
  ASSERT_GE(h.GetNumberOfLevels(), 3);
  for (int c = 0; c < 3; ++c)
  {
    Eigen::SparseMatrix<double, Eigen::RowMajor> galerkin = p.System.Matrix(c);
    Eigen::SparseMatrix<double, Eigen::RowMajor> injected = p.System.Matrix(c);
    Eigen::MatrixXd lumped = Eigen::MatrixXd(p.System.Matrix(c));
    for (int l = 0; l + 1 < h.GetNumberOfLevels(); ++l)
    {
      const auto P = Interpolation(h, l);
      // Galerkin P^T A P: symmetric positive definite.
      galerkin = Eigen::SparseMatrix<double, Eigen::RowMajor>(P.transpose() * galerkin * P);
      const auto mine = mg.GetCoarseMatrix(l + 1, c);
      EXPECT_LT((Eigen::MatrixXd(mine) - Eigen::MatrixXd(galerkin)).norm(),
        1e-12 * Eigen::MatrixXd(galerkin).norm());
      EXPECT_LT((Eigen::MatrixXd(mine) - Eigen::MatrixXd(mine).transpose()).norm(),
        1e-13 * Eigen::MatrixXd(mine).norm());
      const Eigen::MatrixXd dense = mine;
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(dense);
      EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0) << "P^T A P not positive definite, level "
                                                   << l + 1;
      // Sparse Galerkin: P^T A P on the coarse graph, the rest lumped as |a_ab|.
      {
        const Eigen::MatrixXd Pd = Eigen::MatrixXd(P);
        Eigen::MatrixXd full = Pd.transpose() * lumped * Pd;
        const CsrPattern& g = h.GetLevel(l + 1).Graph;
        for (int a = 0; a < g.Size; ++a)
        {
          for (int b = 0; b < g.Size; ++b)
          {
            if (!Adjacent(g, a, b))
            {
              full(a, a) += std::abs(full(a, b));
              full(a, b) = 0.0;
            }
          }
        }
        lumped = full;
        const Eigen::MatrixXd got = sparse.GetCoarseMatrix(l + 1, c);
        EXPECT_LT((got - lumped).norm(), 1e-12 * lumped.norm()) << "sparse Galerkin, level " << l + 1;
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigSparse(got);
        EXPECT_GT(eigSparse.eigenvalues().minCoeff(), 0.0);
      }
      // Eq. 17: rows of the retained vertices of A P.
      const auto& ids = h.GetLevel(l).CoarseIds;
      std::vector<Eigen::Triplet<double>> s;
      for (std::size_t i = 0; i < ids.size(); ++i)
      {
        if (ids[i] >= 0)
        {
          s.emplace_back(ids[i], static_cast<int>(i), 1.0);
        }
      }
      Eigen::SparseMatrix<double, Eigen::RowMajor> S(P.cols(), P.rows());
      S.setFromTriplets(s.begin(), s.end());
      injected = Eigen::SparseMatrix<double, Eigen::RowMajor>(S * injected * P);
      const auto paper = tc.GetCoarseMatrix(l + 1, c);
      EXPECT_LT((Eigen::MatrixXd(paper) - Eigen::MatrixXd(injected)).norm(),
        1e-12 * Eigen::MatrixXd(injected).norm());
      // Its pattern is the hierarchy's coarse graph (Sec. 4.1.2).
      const CsrPattern& g = h.GetLevel(l + 1).Graph;
      EXPECT_EQ(paper.nonZeros(), g.GetNumberOfNonZeros());
    }
  }
}

class SolverNames : public ::testing::TestWithParam<const char*>
{
};

TEST_P(SolverNames, MatchCholeskyOnRandomMeshesAndMaterials)
{
  struct Case
  {
    MeshData Data;
    std::uint64_t Seed;
    bool Fem;
  };
  std::vector<Case> cases{ { CubeMesh(10, 5.0, 0.3, 21), 22, false },
    { translucency::testing::BoxMesh(14, 6, 5, 8.0, 3.0, 2.5, 0.25, 23), 24, false },
    { CubeMesh(8, 2.0, 0.2, 25), 26, true }, { TwoPieces(6), 27, false } };
  for (const auto& test : cases)
  {
    Problem p(test.Data, test.Seed, test.Fem);
    const auto reference = Cholesky(p.System);
    auto solver = CreateLinearSolver(GetParam());
    EXPECT_EQ(solver->GetName(), GetParam());
    solver->SetRelTol(1e-10);
    if (auto* mg = dynamic_cast<MultigridConjugateGradient*>(solver.get()))
    {
      // Also the options: sparse Galerkin on every coarse level (fem case)
      // or below the first one (two pieces).
      if (test.Fem)
      {
        mg->SetSparseGalerkin(true);
      }
      else if (test.Seed == 27)
      {
        mg->SetExactGalerkinLevels(1);
      }
    }
    if (auto* m = dynamic_cast<MultiresLinearSolverBase*>(solver.get()))
    {
      m->SetCoarsestSize(40); // several levels even on these small meshes
    }
    solver->Setup(p.System, &p.Mesh, true);
    std::array<Eigen::VectorXd, 3> x;
    std::array<LinearSolveStats, 3> stats;
    ASSERT_TRUE(solver->Solve(p.System, x, false, stats));
    for (int c = 0; c < 3; ++c)
    {
      EXPECT_TRUE(stats[c].Converged);
      EXPECT_LE(stats[c].RelativeResidual, 1e-10);
      // True residual, not only the recurrence.
      const Eigen::VectorXd r = p.System.RightHandSide[c] - p.System.Matrix(c) * x[c];
      EXPECT_LE(r.norm() / p.System.RightHandSide[c].norm(), 1e-9);
      EXPECT_LT(RelativeError(x[c], reference[c]), 1e-7) << GetParam() << " channel " << c;
      EXPECT_GT(stats[c].SpMVEquivalents, stats[c].Iterations);
    }
  }
}

TEST_P(SolverNames, WarmStartNeedsFewerIterations)
{
  Problem p(CubeMesh(12, 5.0, 0.3, 31), 32);
  auto solver = CreateLinearSolver(GetParam());
  solver->SetRelTol(1e-8);
  solver->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> x;
  std::array<LinearSolveStats, 3> cold, warm;
  ASSERT_TRUE(solver->Solve(p.System, x, false, cold));
  // A small light change: 2 % more light on the boundary, slightly tilted.
  for (int c = 0; c < 3; ++c)
  {
    for (int i = 0; i < p.System.NumberOfUnknowns; ++i)
    {
      p.System.RightHandSide[c][i] *= 1.0 + 0.02 * p.Mesh.GetPoint(i)[0] / 5.0;
    }
  }
  std::array<Eigen::VectorXd, 3> xCold;
  std::array<LinearSolveStats, 3> coldAgain;
  ASSERT_TRUE(solver->Solve(p.System, xCold, false, coldAgain));
  ASSERT_TRUE(solver->Solve(p.System, x, true, warm)); // no Setup: only b changed
  const auto reference = Cholesky(p.System);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(warm[c].Converged);
    EXPECT_LT(warm[c].Iterations, coldAgain[c].Iterations) << GetParam() << " channel " << c;
    EXPECT_LT(RelativeError(x[c], reference[c]), 1e-5);
  }
}

TEST_P(SolverNames, ValuesOnlySetupEqualsFreshSetup)
{
  Problem p(CubeMesh(10, 5.0, 0.3, 41), 42);
  auto kept = CreateLinearSolver(GetParam());
  kept->Setup(p.System, &p.Mesh, true);
  std::array<Eigen::VectorXd, 3> x1, x2;
  std::array<LinearSolveStats, 3> s1, s2;
  ASSERT_TRUE(kept->Solve(p.System, x1, false, s1));
  // Paint: new material on the same mesh.
  const auto painted = RandomMaterial(p.Mesh.GetNumberOfTets(), 43);
  DiscreteDivergence().Assemble(p.Mesh, painted, RandomIrradiance(p.Mesh, 42), p.System);
  kept->Setup(p.System, &p.Mesh, false);
  auto fresh = CreateLinearSolver(GetParam());
  fresh->Setup(p.System, &p.Mesh, true);
  ASSERT_TRUE(kept->Solve(p.System, x1, false, s1));
  ASSERT_TRUE(fresh->Solve(p.System, x2, false, s2));
  auto* m = dynamic_cast<MultiresLinearSolverBase*>(kept.get());
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->GetNumberOfHierarchyBuilds(), 1);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(s1[c].Iterations, s2[c].Iterations);
    EXPECT_EQ((x1[c] - x2[c]).norm(), 0.0) << "channel " << c;
  }
}

TEST_P(SolverNames, TinyMeshesAndBadInput)
{
  // One tet (4 vertices) and two separate tets: everything on the coarsest
  // level or one coarsening step.
  const std::vector<double> points{ 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 5, 0, 0, 6, 0, 0, 5, 1, 0,
    5, 0, 1 };
  for (int tets : { 1, 2 })
  {
    TetMesh mesh;
    std::vector<int> ids{ 0, 1, 2, 3, 4, 5, 6, 7 };
    ids.resize(4 * tets);
    mesh.SetGeometry(std::vector<double>(points.begin(), points.begin() + 12 * tets), ids);
    const auto material = RandomMaterial(tets, 50);
    DiffusionSystem system;
    DiscreteDivergence().Assemble(mesh, material, RandomIrradiance(mesh, 51), system);
    const auto reference = Cholesky(system);
    for (int levels : { 0, 3 })
    {
      auto solver = CreateLinearSolver(GetParam());
      dynamic_cast<MultiresLinearSolverBase&>(*solver).SetMaxLevels(levels);
      solver->SetRelTol(1e-12);
      solver->Setup(system, &mesh, true);
      std::array<Eigen::VectorXd, 3> x;
      std::array<LinearSolveStats, 3> stats;
      ASSERT_TRUE(solver->Solve(system, x, false, stats));
      for (int c = 0; c < 3; ++c)
      {
        EXPECT_LT(RelativeError(x[c], reference[c]), 1e-9);
      }
    }
  }
  Problem p(CubeMesh(3, 1.0), 60);
  auto solver = CreateLinearSolver(GetParam());
  EXPECT_TRUE(translucency::testing::Contains(
    translucency::testing::ErrorMessage([&] { solver->Setup(p.System, nullptr, true); }), "needs the mesh"));
  std::array<Eigen::VectorXd, 3> x;
  std::array<LinearSolveStats, 3> stats;
  EXPECT_TRUE(translucency::testing::Contains(
    translucency::testing::ErrorMessage([&] { solver->Solve(p.System, x, false, stats); }), "before Setup"));
  solver->Setup(p.System, &p.Mesh, true);
  DiffusionSystem other = p.System;
  other.RightHandSide[1].resize(3);
  EXPECT_TRUE(translucency::testing::Contains(
    translucency::testing::ErrorMessage([&] { solver->Solve(other, x, false, stats); }), "does not match"));
  // Zero right-hand side: zero solution, no iterations.
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

INSTANTIATE_TEST_SUITE_P(Multires, SolverNames,
  ::testing::Values("transcut-multires", "multigrid-cg"));

TEST(MultiresSolvers, VertexSolverKeepsTheHierarchy)
{
  // VertexDiffusionSolver: no Setup for a relight, a values-only Setup for a
  // paint, a new hierarchy for a new mesh; the result always equals Cholesky.
  const auto data = CubeMesh(12, 4.0, 0.3, 81); // > 1000 points: several levels
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  auto material = RandomMaterial(mesh.GetNumberOfTets(), 82);
  auto q = RandomIrradiance(mesh, 83);
  auto solver = CreateDiffusionSolver("divergence");
  EXPECT_EQ(solver->GetLinearSolver(), "");
  solver->SetLinearSolver("Multigrid-CG");
  solver->SetRelTol(1e-10);
  DiffusionProblem problem = MakeProblem(mesh, material, q);
  std::vector<double> fluence;
  SolverReport report;
  auto check = [&](const TetMesh& m)
  {
    DiffusionSystem system;
    DiscreteDivergence().Assemble(m, *problem.Material, *problem.Irradiance, system);
    const auto reference = Cholesky(system);
    for (int i = 0; i < m.GetNumberOfPoints(); ++i)
    {
      for (int c = 0; c < 3; ++c)
      {
        EXPECT_NEAR(fluence[3 * i + c], reference[c][i], 1e-7 * reference[c].cwiseAbs().maxCoeff());
      }
    }
  };
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_EQ(report.LinearSolver, "multigrid-cg");
  auto& vertex = dynamic_cast<VertexDiffusionSolver&>(*solver);
  auto* mg = dynamic_cast<MultigridConjugateGradient*>(vertex.GetLinearSolverObject());
  ASSERT_NE(mg, nullptr);
  EXPECT_EQ(mg->GetNumberOfHierarchyBuilds(), 1);
  EXPECT_EQ(mg->GetNumberOfSetups(), 1);
  check(mesh);
  const int coldIterations = report.Iterations[0];
  // Relight: no Setup, warm start.
  q = RandomIrradiance(mesh, 84, 1.02);
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_EQ(mg->GetNumberOfSetups(), 1);
  check(mesh);
  // Relight with a tiny change: warm start needs fewer iterations.
  for (double& v : q)
  {
    v *= 1.001;
  }
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_LT(report.Iterations[0], coldIterations);
  // Paint: values-only Setup, same hierarchy.
  material.AbsorptionCoefficient[0] *= 3.0;
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_EQ(mg->GetNumberOfSetups(), 2);
  EXPECT_EQ(mg->GetNumberOfHierarchyBuilds(), 1);
  check(mesh);
  // Another mesh: a new hierarchy.
  const auto data2 = CubeMesh(7, 4.0, 0.3, 85);
  TetMesh mesh2;
  mesh2.SetGeometry(data2.Points, data2.Tets);
  auto material2 = RandomMaterial(mesh2.GetNumberOfTets(), 86);
  auto q2 = RandomIrradiance(mesh2, 87);
  problem.Mesh = &mesh2;
  problem.Material = &material2;
  problem.Irradiance = &q2;
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_EQ(mg->GetNumberOfHierarchyBuilds(), 2);
  check(mesh2);
  // Another name: another solver object; an unknown name lists the known.
  solver->SetLinearSolver("transcut-multires");
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_EQ(report.LinearSolver, "transcut-multires");
  check(mesh2);
  solver->SetLinearSolver("");
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_EQ(report.LinearSolver, VertexDiffusionSolver::GetDefaultLinearSolverName());
  solver->SetLinearSolver("amg");
  EXPECT_TRUE(translucency::testing::Contains(
    translucency::testing::ErrorMessage([&] { solver->Solve(problem, fluence, report); }),
    "multigrid-cg"));
}

TEST(MultiresSolvers, FactoryNames)
{
  const auto names = GetLinearSolverNames();
  EXPECT_EQ(names.front(), "cg-jacobi");
  EXPECT_NE(std::find(names.begin(), names.end(), "transcut-multires"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "multigrid-cg"), names.end());
  EXPECT_EQ(CreateLinearSolver("MultiGrid-CG")->GetName(), "multigrid-cg");
  EXPECT_TRUE(translucency::testing::Contains(
    translucency::testing::ErrorMessage([] { CreateLinearSolver("multigrid"); }), "multigrid-cg"));
}

TEST(MultiresSolvers, MultigridPreconditionerIsSymmetricPositive)
{
  // The V-cycle B must be SPD for CG: check B symmetric (u.Bv = v.Bu) and
  // positive (v.Bv > 0) on random vectors.
  Problem p(CubeMesh(9, 4.0, 0.3, 71), 72);
  MultigridConjugateGradient mg;
  mg.SetCoarsestSize(30);
  mg.Setup(p.System, &p.Mesh, true);
  ASSERT_GE(mg.GetHierarchy().GetNumberOfLevels(), 3);
  std::mt19937_64 rng(73);
  const int n = 3 * p.System.NumberOfUnknowns;
  for (int trial = 0; trial < 3; ++trial)
  {
    Eigen::VectorXd u(n), v(n), bu, bv;
    for (int i = 0; i < n; ++i)
    {
      u[i] = Uniform01(rng) - 0.5;
      v[i] = Uniform01(rng) - 0.5;
    }
    mg.ApplyPreconditioner(u, bu);
    mg.ApplyPreconditioner(v, bv);
    for (int c = 0; c < 3; ++c)
    {
      double ubv = 0, vbu = 0, vbv = 0;
      for (int i = c; i < n; i += 3)
      {
        ubv += u[i] * bv[i];
        vbu += v[i] * bu[i];
        vbv += v[i] * bv[i];
      }
      // The V-cycle holds single-precision matrix values: coarse entries
      // (a, b) and (b, a), summed in different orders, may round to floats
      // one ulp (6e-8) apart, so symmetry holds to about that.
      EXPECT_NEAR(ubv, vbu, 1e-6 * u.norm() * bv.norm());
      EXPECT_GT(vbv, 0.0);
    }
  }
}

} // namespace
