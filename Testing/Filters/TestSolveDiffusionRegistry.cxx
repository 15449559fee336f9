// vtkSolveDiffusion's SOLVER_* constants are public API (scripts call
// SetSolver(int)) and indices into the diffusion solver registry: their
// order must be the registry's (the plugin XML's enumeration is compared
// with GetDiffusionSolverNames() by another test).
#include "DiffusionSolverFactory.h"
#include "vtkSolveDiffusion.h"

#include <vtkNew.h>

#include <gtest/gtest.h>

TEST(SolveDiffusionRegistry, EnumOrderIsTheRegistryOrder)
{
  const std::vector<std::string> names = translucency::GetDiffusionSolverNames();
  const std::pair<int, const char*> constants[] = {
    { vtkSolveDiffusion::SOLVER_DIVERGENCE, "divergence" },
    { vtkSolveDiffusion::SOLVER_FEM, "fem" },
    { vtkSolveDiffusion::SOLVER_QUADGRAPH, "quadgraph" },
    { vtkSolveDiffusion::SOLVER_GRID, "grid" },
    { vtkSolveDiffusion::SOLVER_MONTECARLO, "montecarlo" },
  };
  // One constant per solver, the last one the largest (SetSolver clamps to it).
  ASSERT_EQ(names.size(), std::size(constants));
  EXPECT_EQ(vtkSolveDiffusion::SOLVER_MONTECARLO + 1, static_cast<int>(names.size()));
  vtkNew<vtkSolveDiffusion> solve;
  for (const auto& constant : constants)
  {
    SCOPED_TRACE(constant.second);
    ASSERT_LT(constant.first, static_cast<int>(names.size()));
    EXPECT_EQ(names[constant.first], constant.second);
    solve->SetSolver(constant.first);
    EXPECT_STREQ(solve->GetSolverName(), constant.second);
    solve->SetSolver(vtkSolveDiffusion::SOLVER_DIVERGENCE);
    EXPECT_TRUE(solve->SetSolverByName(translucency::ToLower(constant.second).c_str()));
    EXPECT_EQ(solve->GetSolver(), constant.first);
  }
}

TEST(SolveDiffusionRegistry, UnknownNameIsRefusedWithTheRegistryNames)
{
  vtkNew<vtkSolveDiffusion> solve;
  solve->SetSolver(vtkSolveDiffusion::SOLVER_GRID);
  solve->GlobalWarningDisplayOff();
  EXPECT_FALSE(solve->SetSolverByName("voxels"));
  EXPECT_FALSE(solve->SetSolverByName(nullptr));
  EXPECT_EQ(solve->GetSolver(), vtkSolveDiffusion::SOLVER_GRID); // unchanged
}
