// ConjugateGradient against a sparse Cholesky solution of the same systems.

#include "ConjugateGradient.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "TestMeshes.h"
#include "TetMesh.h"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <omp.h>

#include <random>

namespace
{

using namespace translucency;
using translucency::testing::CubeMesh;
using translucency::testing::Uniform01;

/// A skin1 cube lit by random boundary irradiance, assembled once.
class ConjugateGradientTest : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    const auto data = CubeMesh(12, 6.0, 0.25, 21);
    Mesh = new TetMesh;
    Mesh->SetGeometry(data.Points, data.Tets);
    const MaterialPreset& skin = FindMaterialPreset("skin1");
    const OpticalProperties material = OpticalProperties::Uniform(
      Mesh->GetNumberOfTets(), skin.Absorption, skin.ReducedScattering, skin.RefractiveIndex);
    std::mt19937_64 rng(22);
    std::vector<double> q(3 * Mesh->GetNumberOfPoints(), 0.0);
    for (int i : Mesh->GetBoundaryPoints())
    {
      for (int c = 0; c < 3; ++c)
      {
        q[3 * i + c] = Uniform01(rng);
      }
    }
    System = new DiffusionSystem;
    DiscreteDivergence().Assemble(*Mesh, material, q, *System);
    for (int c = 0; c < 3; ++c)
    {
      Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(
        Eigen::SparseMatrix<double>(System->Matrix(c)));
      ASSERT_EQ(llt.info(), Eigen::Success);
      Direct[c] = llt.solve(System->RightHandSide[c]);
    }
  }
  static void TearDownTestSuite()
  {
    delete System;
    delete Mesh;
  }

  static TetMesh* Mesh;
  static DiffusionSystem* System;
  static std::array<Eigen::VectorXd, 3> Direct;
};

TetMesh* ConjugateGradientTest::Mesh = nullptr;
DiffusionSystem* ConjugateGradientTest::System = nullptr;
std::array<Eigen::VectorXd, 3> ConjugateGradientTest::Direct;

TEST_F(ConjugateGradientTest, MatchesCholesky)
{
  ConjugateGradient cg;
  EXPECT_EQ(cg.GetRelTol(), 1e-6);
  EXPECT_EQ(cg.GetMaxIter(), 2000);
  const double tol = 1e-10;
  cg.SetRelTol(tol);
  std::array<Eigen::VectorXd, 3> x;
  ASSERT_TRUE(cg.Solve(*System, x));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(cg.GetConverged(c));
    EXPECT_GT(cg.GetNumIterations(c), 1);
    EXPECT_LE(cg.GetFinalNorm(c), tol);
    // True residual: the CG recurrence residual may drift from it slightly.
    const Eigen::VectorXd r = System->RightHandSide[c] - System->Matrix(c) * x[c];
    EXPECT_LE(r.norm(), 10.0 * tol * System->RightHandSide[c].norm()) << "channel " << c;
    // Error <= cond(M) * relative residual; cond(M) < 1e4 on this mesh.
    EXPECT_LE((x[c] - Direct[c]).norm(), 1e-6 * Direct[c].norm()) << "channel " << c;
  }
}

TEST_F(ConjugateGradientTest, WarmStartFromSolutionNeedsAtMostOneIteration)
{
  ConjugateGradient cg;
  cg.SetRelTol(1e-8);
  std::array<Eigen::VectorXd, 3> x = Direct;
  ASSERT_TRUE(cg.Solve(*System, x, true));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(cg.GetConverged(c));
    EXPECT_LE(cg.GetNumIterations(c), 1) << "channel " << c;
    EXPECT_LE((x[c] - Direct[c]).norm(), 1e-8 * Direct[c].norm());
  }
  // Without warmStart the guess is ignored: a full solve.
  x = Direct;
  ASSERT_TRUE(cg.Solve(*System, x, false));
  EXPECT_GT(cg.GetNumIterations(0), 5);
  // A guess of the wrong size is ignored too.
  x[0].resize(3);
  ASSERT_TRUE(cg.Solve(*System, x, true));
  EXPECT_EQ(x[0].size(), System->NumberOfUnknowns);
  EXPECT_GT(cg.GetNumIterations(0), 5);
}

TEST_F(ConjugateGradientTest, ZeroRightHandSide)
{
  DiffusionSystem zero = *System;
  for (int c = 0; c < 3; ++c)
  {
    zero.RightHandSide[c].setZero();
  }
  ConjugateGradient cg;
  std::array<Eigen::VectorXd, 3> x = Direct; // a non-zero guess
  ASSERT_TRUE(cg.Solve(zero, x, true));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(cg.GetConverged(c));
    EXPECT_EQ(cg.GetNumIterations(c), 0);
    EXPECT_EQ(x[c].size(), zero.NumberOfUnknowns);
    EXPECT_EQ(x[c].lpNorm<Eigen::Infinity>(), 0.0);
  }
}

TEST_F(ConjugateGradientTest, IterationLimitIsNotAnError)
{
  ConjugateGradient cg;
  cg.SetRelTol(1e-14);
  cg.SetMaxIter(3);
  std::array<Eigen::VectorXd, 3> x;
  ASSERT_TRUE(cg.Solve(*System, x));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_FALSE(cg.GetConverged(c));
    EXPECT_EQ(cg.GetNumIterations(c), 3);
    EXPECT_GT(cg.GetFinalNorm(c), 1e-14);
  }
}

TEST_F(ConjugateGradientTest, ProgressCallbackCanAbort)
{
  ConjugateGradient cg;
  std::vector<double> fractions;
  cg.SetProgressCallback(
    [&](double f)
    {
      fractions.push_back(f);
      return f < 0.3; // abort before the second channel
    });
  std::array<Eigen::VectorXd, 3> x;
  EXPECT_FALSE(cg.Solve(*System, x));
  ASSERT_EQ(fractions.size(), 2u);
  EXPECT_EQ(fractions[0], 0.0);
  EXPECT_NEAR(fractions[1], 1.0 / 3.0, 1e-15);
  EXPECT_TRUE(cg.GetConverged(0));
  EXPECT_FALSE(cg.GetConverged(1));
  EXPECT_FALSE(cg.GetConverged(2));

  fractions.clear();
  cg.SetProgressCallback(
    [&](double f)
    {
      fractions.push_back(f);
      return true;
    });
  EXPECT_TRUE(cg.Solve(*System, x));
  EXPECT_EQ(fractions.back(), 1.0);
}

TEST_F(ConjugateGradientTest, ParallelEqualsSerial)
{
  // Eigen's OpenMP product splits rows between threads; every row is still
  // summed by one thread in order, and the vector reductions are serial.
  ASSERT_GT(System->ColumnIndices.size(), 20000u); // Eigen's threshold to go parallel
  ConjugateGradient cg;
  cg.SetRelTol(1e-10);
  std::array<Eigen::VectorXd, 3> serial, parallel;
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  ASSERT_TRUE(cg.Solve(*System, serial));
  omp_set_num_threads(2);
  ASSERT_TRUE(cg.Solve(*System, parallel));
  omp_set_num_threads(saved);
  for (int c = 0; c < 3; ++c)
  {
    for (Eigen::Index i = 0; i < serial[c].size(); ++i)
    {
      ASSERT_EQ(serial[c][i], parallel[c][i]) << "channel " << c << " unknown " << i;
    }
  }
}

TEST_F(ConjugateGradientTest, InconsistentSystemThrows)
{
  DiffusionSystem broken = *System;
  broken.RightHandSide[1].resize(4);
  ConjugateGradient cg;
  std::array<Eigen::VectorXd, 3> x;
  EXPECT_THROW(cg.Solve(broken, x), Error);
}

} // namespace
