/**
 * @file TestReferenceAssembly.h
 * @brief Pieces of the independent reference assemblies of the vertex
 * discretisation tests (written from the P1 FEM definitions, not from the
 * code under test): per-tet P1 gradients and a tight CG solve.
 */
#pragma once

#include "ConjugateGradient.h"
#include "DiffusionSystem.h"
#include "TetMesh.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <array>
#include <cmath>

namespace translucency
{
namespace testing
{

/// Volume and P1 basis gradients of one tet.
struct P1Tet
{
  double Volume = 0.0;   ///< mm^3
  Eigen::Vector3d Grad[4]; ///< grad beta_a (1/mm)
};

/// Barycentric coordinates lambda = edges^{-1} (x - p0): the gradients are
/// the rows of the inverse edge matrix, grad beta_0 = -(the sum of the others).
inline P1Tet P1TetOf(const TetMesh& mesh, int t)
{
  const int* tv = mesh.GetTet(t);
  Eigen::Vector3d p[4];
  for (int a = 0; a < 4; ++a)
  {
    p[a] = Eigen::Vector3d(mesh.GetPoint(tv[a]));
  }
  Eigen::Matrix3d edges;
  edges.col(0) = p[1] - p[0];
  edges.col(1) = p[2] - p[0];
  edges.col(2) = p[3] - p[0];
  P1Tet tet;
  tet.Volume = std::abs(edges.determinant()) / 6.0;
  const Eigen::Matrix3d inverse = edges.inverse();
  for (int a = 1; a < 4; ++a)
  {
    tet.Grad[a] = inverse.row(a - 1).transpose();
  }
  tet.Grad[0] = -(tet.Grad[1] + tet.Grad[2] + tet.Grad[3]);
  return tet;
}

/// Solve the three channels with a tight tolerance; checks convergence.
inline std::array<Eigen::VectorXd, 3> Solve(const DiffusionSystem& system, double tol = 1e-12)
{
  ConjugateGradient cg;
  cg.SetRelTol(tol);
  cg.SetMaxIter(20000);
  std::array<Eigen::VectorXd, 3> x;
  EXPECT_TRUE(cg.Solve(system, x));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(cg.GetConverged(c)) << "channel " << c << ": " << cg.GetFinalNorm(c);
  }
  return x;
}

} // namespace testing
} // namespace translucency
