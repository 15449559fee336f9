// vtkSolveDiffusion's SOLVER_* constants are public API (scripts call
// SetSolver(int)) and indices into the diffusion solver registry: their
// order must be the registry's (the plugin XML's enumeration is compared
// with GetDiffusionSolverNames() by another test).
#include "DiffusionSolverFactory.h"
#include "LinearSolver.h"
#include "VertexDiffusionSolver.h"
#include "vtkSolveDiffusion.h"

#include <vtkNew.h>
#include <vtkStringArray.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

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
    { vtkSolveDiffusion::SOLVER_SP3, "sp3" },
  };
  // One constant per solver, the last one the largest (SetSolver clamps to it).
  ASSERT_EQ(names.size(), std::size(constants));
  EXPECT_EQ(vtkSolveDiffusion::SOLVER_SP3 + 1, static_cast<int>(names.size()));
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

// The plugin's Linear Solver drop-down is fed by GetAvailableLinearSolvers():
// "default", then every linear solver of the registry that this build has,
// each once, the symmetric ones (divergence, fem) first in registry order.
TEST(SolveDiffusionRegistry, AvailableLinearSolversAreTheBuiltRegistryEntries)
{
  vtkNew<vtkSolveDiffusion> solve;
  vtkStringArray* names = solve->GetAvailableLinearSolvers();
  ASSERT_NE(names, nullptr);
  std::vector<std::string> listed;
  for (vtkIdType i = 0; i < names->GetNumberOfValues(); ++i)
  {
    listed.push_back(names->GetValue(i));
  }
  std::vector<std::string> expected{ "default" };
  std::vector<std::string> nonSymmetric;
  for (const auto& entry : translucency::GetLinearSolverRegistry().GetEntries())
  {
    if (entry.Properties.Built)
    {
      (entry.Properties.NeedsSymmetricPositiveDefinite ? expected : nonSymmetric)
        .push_back(entry.Name);
    }
  }
  expected.insert(expected.end(), nonSymmetric.begin(), nonSymmetric.end());
  EXPECT_EQ(listed, expected);
  EXPECT_EQ(listed.at(1), translucency::VertexDiffusionSolver::GetDefaultLinearSolverName());
  EXPECT_NE(std::find(listed.begin(), listed.end(), "bicgstab"), listed.end());
  // Asked again (ParaView asks on every information update): the same list.
  EXPECT_EQ(solve->GetAvailableLinearSolvers()->GetNumberOfValues(),
    static_cast<vtkIdType>(expected.size()));
}

// The plugin's Linear Solver drop-down follows the chosen Solver through
// GetLinearSolverTable(): pairs (solver, linear solver), exactly each registry
// entry's accepted list in order, every name one of GetAvailableLinearSolvers().
TEST(SolveDiffusionRegistry, LinearSolverTableIsEachSolversAcceptedList)
{
  vtkNew<vtkSolveDiffusion> solve;
  vtkStringArray* table = solve->GetLinearSolverTable();
  ASSERT_NE(table, nullptr);
  ASSERT_EQ(table->GetNumberOfValues() % 2, 0);
  std::map<std::string, std::vector<std::string>> listed;
  for (vtkIdType i = 0; i < table->GetNumberOfValues(); i += 2)
  {
    listed[table->GetValue(i)].push_back(table->GetValue(i + 1));
  }
  vtkStringArray* available = solve->GetAvailableLinearSolvers();
  std::vector<std::string> names;
  for (vtkIdType i = 0; i < available->GetNumberOfValues(); ++i)
  {
    names.push_back(available->GetValue(i));
  }
  for (const auto& entry : translucency::GetDiffusionSolverRegistry().GetEntries())
  {
    SCOPED_TRACE(entry.Name);
    EXPECT_EQ(listed[entry.Name], entry.Properties.LinearSolvers);
    for (const std::string& name : entry.Properties.LinearSolvers)
    {
      EXPECT_NE(std::find(names.begin(), names.end(), name), names.end());
    }
  }
  EXPECT_TRUE(listed["montecarlo"].empty());
  EXPECT_EQ(listed["sp3"], (std::vector<std::string>{ "bicgstab", "multigrid-agg" }));
  EXPECT_EQ(listed["grid"], (std::vector<std::string>{ "bicgstab", "relaxation" }));
  // Asked again (ParaView asks on every information update): the same table.
  EXPECT_EQ(solve->GetLinearSolverTable()->GetNumberOfValues(), table->GetNumberOfValues());
}
