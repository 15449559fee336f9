// Issue 21: an iterative solver never reports convergence on a NaN or
// infinite residual (a light power of 1e300 overflows the right-hand side).

#include "ConjugateGradient.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "LinearSolver.h"
#include "TestMeshes.h"
#include "TetMesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace
{
using namespace translucency;

/// A small cube with an overflowing right-hand side in channel 1 (inf) and
/// a NaN in channel 2; channel 0 is a normal system.
DiffusionSystem OverflowingSystem(TetMesh& mesh)
{
  const auto data = translucency::testing::CubeMesh(5, 6.0, 0.25, 3);
  mesh.SetGeometry(data.Points, data.Tets);
  const MaterialPreset& skin = FindMaterialPreset("skin1");
  const OpticalProperties material = OpticalProperties::Uniform(
    mesh.GetNumberOfTets(), skin.Absorption, skin.ReducedScattering, skin.RefractiveIndex);
  std::vector<double> q(3 * mesh.GetNumberOfPoints(), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    q[3 * i] = 1.0;
    q[3 * i + 1] = 1e308;
    q[3 * i + 2] = 1.0;
  }
  DiffusionSystem system;
  DiscreteDivergence().Assemble(mesh, material, q, system);
  system.RightHandSide[1] *= 1e10; // overflows to inf
  system.RightHandSide[2][0] = std::numeric_limits<double>::quiet_NaN();
  return system;
}

TEST(NonFiniteResidual, ConjugateGradientDoesNotConverge)
{
  TetMesh mesh;
  const DiffusionSystem system = OverflowingSystem(mesh);
  ConjugateGradient cg;
  cg.SetMaxIter(50);
  std::array<Eigen::VectorXd, 3> x;
  ASSERT_TRUE(cg.Solve(system, x, false));
  EXPECT_TRUE(cg.GetConverged(0));
  EXPECT_FALSE(cg.GetConverged(1));
  EXPECT_FALSE(cg.GetConverged(2));
}

TEST(NonFiniteResidual, NoRegisteredSolverConverges)
{
  TetMesh mesh;
  const DiffusionSystem system = OverflowingSystem(mesh);
  for (const std::string& name : GetLinearSolverNames())
  {
    SCOPED_TRACE(name);
    std::unique_ptr<LinearSolver> solver;
    try
    {
      solver = CreateLinearSolver(name);
    }
    catch (const Error&)
    {
      continue; // a peer library not built in
    }
    solver->SetMaxIter(50);
    std::array<Eigen::VectorXd, 3> x;
    std::array<LinearSolveStats, 3> stats;
    try
    {
      solver->Setup(system, &mesh, true);
      solver->Solve(system, x, false, stats);
    }
    catch (const Error&)
    {
      continue; // refusing the system is fine too
    }
    // channel 0 is a normal system (a relaxation may need more than 50 sweeps)
    EXPECT_FALSE(stats[1].Converged);
    EXPECT_FALSE(stats[2].Converged);
  }
}

} // namespace
