// The table of the diffusion solvers (DiffusionSolverFactory.h) and the
// options hook (DiffusionSolver::SetOptions, Common/SolverOptions.h).
#include "DiffusionSolverFactory.h"
#include "Error.h"
#include "GridSolver.h"
#include "LinearSolver.h"
#include "MonteCarlo.h"
#include "QuadGraph.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TetMesh.h"
#include "VertexDiffusionSolver.h"

#include <gtest/gtest.h>

#include <algorithm>

using namespace translucency;
using translucency::testing::Contains;
using translucency::testing::ErrorMessage;

TEST(DiffusionRegistry, ServesTheFactoryInListingOrder)
{
  const DiffusionSolverRegistry& registry = GetDiffusionSolverRegistry();
  EXPECT_EQ(GetDiffusionSolverNames(),
    (std::vector<std::string>{ "divergence", "fem", "quadgraph", "grid", "montecarlo", "sp3" }));
  EXPECT_EQ(registry.GetNames(), GetDiffusionSolverNames());
  for (const auto& entry : registry.GetEntries())
  {
    SCOPED_TRACE(entry.Name);
    // Each name creates the solver of that name (case-insensitively).
    const std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver(ToLower(entry.Name));
    EXPECT_EQ(solver->GetName(), entry.Name);
    EXPECT_EQ(CreateDiffusionSolver(entry.Name)->GetName(), entry.Name);
    // The traits describe the object.
    EXPECT_EQ(entry.Properties.UnknownsAtVertices,
      dynamic_cast<VertexDiffusionSolver*>(solver.get()) != nullptr);
    EXPECT_EQ(entry.Properties.IsStochastic,
      dynamic_cast<MonteCarloSolver*>(solver.get()) != nullptr);
    EXPECT_EQ(entry.Properties.HasLinearSolverChoice, !entry.Properties.IsStochastic);
    EXPECT_FALSE(entry.Help.empty());
    // Help: one line per solver, in order.
    EXPECT_NE(GetDiffusionSolverHelp().find("  " + entry.Name + " "), std::string::npos);
  }
  const std::string help = GetDiffusionSolverHelp();
  EXPECT_EQ(std::count(help.begin(), help.end(), '\n'),
    static_cast<long>(registry.GetEntries().size()));
  const std::string message = ErrorMessage([] { CreateDiffusionSolver("voxels"); });
  EXPECT_EQ(message,
    "unknown solver 'voxels' (known solvers: divergence, fem, quadgraph, grid, montecarlo, sp3)");
}

// The options each entry lists are exactly those its solver reads.
TEST(DiffusionRegistry, OptionTraitsAreWhatEachSolverReads)
{
  SolverOptions all;
  for (const std::string& name : GetDiffusionSolverOptionNames())
  {
    all.Set(name, 1.0); // valid for every option
  }
  EXPECT_EQ(GetDiffusionSolverOptionNames(),
    (std::vector<std::string>{ "anisotropy", "grid-spacing", "multilevel", "photons", "seed",
      "time-step-recycled", "two-point-flux" }));
  for (const auto& entry : GetDiffusionSolverRegistry().GetEntries())
  {
    SCOPED_TRACE(entry.Name);
    all.ClearUsed();
    entry.Create()->SetOptions(all);
    std::vector<std::string> read = GetDiffusionSolverOptionNames(), unused = all.GetUnused();
    read.erase(std::remove_if(read.begin(), read.end(),
                 [&](const std::string& n) {
                   return std::find(unused.begin(), unused.end(), n) != unused.end();
                 }),
      read.end());
    std::vector<std::string> listed = entry.Properties.Options;
    std::sort(listed.begin(), listed.end());
    EXPECT_EQ(read, listed);
  }
}

TEST(DiffusionSolverOptions, GridSpacingReachesTheGridSolverThroughTheHook)
{
  const std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver("grid");
  SolverOptions options{ { "Grid-Spacing", 0.25 }, { DiffusionOption::MultiLevel, 1 },
    { DiffusionOption::Photons, 1000 } };
  solver->SetOptions(options);
  const auto& grid = dynamic_cast<const GridSolver&>(*solver);
  EXPECT_EQ(grid.GetGridSpacing(), 0.25);
  EXPECT_TRUE(grid.GetMultiLevel());
  // The photons do not apply to the grid solver: left unused, for the caller to report.
  EXPECT_EQ(options.GetUnused(), (std::vector<std::string>{ "photons" }));

  const std::unique_ptr<DiffusionSolver> quad = CreateDiffusionSolver("quadgraph");
  quad->SetOptions(SolverOptions{ { DiffusionOption::MultiLevel, 1 } });
  EXPECT_TRUE(dynamic_cast<const QuadGraphSolver&>(*quad).GetMultiLevel());

  const std::unique_ptr<DiffusionSolver> photons = CreateDiffusionSolver("montecarlo");
  photons->SetOptions(SolverOptions{ { DiffusionOption::Photons, 12345 }, { "seed", 7 } });
  const auto& mc = dynamic_cast<const MonteCarloSolver&>(*photons);
  EXPECT_EQ(mc.GetNumberOfPhotons(), 12345);
  EXPECT_EQ(mc.GetSeed(), 7u);

  // A solver that reads none leaves them all unused and is unchanged.
  SolverOptions forDivergence{ { DiffusionOption::GridSpacing, -1.0 } };
  CreateDiffusionSolver("divergence")->SetOptions(forDivergence);
  EXPECT_EQ(forDivergence.GetUnused(), (std::vector<std::string>{ "grid-spacing" }));
}

TEST(DiffusionSolverOptions, BadValueIsRefusedNamingIt)
{
  GridSolver grid;
  grid.SetGridSpacing(0.5);
  EXPECT_EQ(ErrorMessage([&] { grid.SetOptions(SolverOptions{ { "grid-spacing", -0.1 } }); }),
    "grid: option grid-spacing = -0.1 is invalid: the voxel spacing must be > 0 "
    "mm (or 0 for automatic)");
  EXPECT_EQ(grid.GetGridSpacing(), 0.5); // unchanged
  EXPECT_TRUE(Contains(
    ErrorMessage([&] { grid.SetOptions(SolverOptions{ { "multilevel", 2 } }); }),
    "grid: option multilevel = 2 is invalid: it is a flag"));

  MonteCarloSolver mc;
  EXPECT_TRUE(Contains(
    ErrorMessage([&] { mc.SetOptions(SolverOptions{ { "photons", 0 } }); }),
    "montecarlo: option photons = 0 is invalid"));
  EXPECT_TRUE(Contains(
    ErrorMessage([&] { mc.SetOptions(SolverOptions{ { "seed", 1.5 } }); }),
    "montecarlo: option seed = 1.5 is invalid"));
  EXPECT_EQ(mc.GetNumberOfPhotons(), 1000000); // unchanged default
  EXPECT_EQ(mc.GetSeed(), 1u);

  // A name no solver reads is a typo, refused with the known names.
  EXPECT_EQ(
    ErrorMessage([] { CheckDiffusionSolverOptions(SolverOptions{ { "gridspacing", 0.2 } }); }),
    "unknown solver option 'gridspacing' (known options: anisotropy, grid-spacing, multilevel, "
    "photons, seed, time-step-recycled, two-point-flux)");
  EXPECT_NO_THROW(CheckDiffusionSolverOptions(SolverOptions{ { "Seed", 3 }, { "photons", 9 } }));
}

// Each entry lists the linear solvers its solver accepts (what the filter
// checks and the plugin's Linear Solver drop-down offers): the solver object
// itself decides, independently of the list, by solving with every linear
// solver this build has. A listed name must solve; any other must be refused.
TEST(DiffusionRegistry, LinearSolverListsAreWhatEachSolverAccepts)
{
  const translucency::testing::MeshData data = translucency::testing::CubeMesh(3, 6.0, 0.2, 3);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  const double muA[3] = { 0.02, 0.03, 0.04 }, muS[3] = { 1.0, 1.2, 1.4 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, muS, 1.3);
  std::vector<double> irradiance(3 * static_cast<std::size_t>(mesh.GetNumberOfPoints()), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    for (int c = 0; c < 3; ++c)
    {
      irradiance[3 * static_cast<std::size_t>(i) + c] = mesh.GetPoint(i)[2] > 5.999 ? 0.1 : 0.0;
    }
  }
  const DiffusionProblem problem =
    translucency::testing::MakeProblem(mesh, material, irradiance);
  std::vector<std::string> built;
  for (const auto& entry : GetLinearSolverRegistry().GetEntries())
  {
    if (entry.Properties.Built)
    {
      built.push_back(entry.Name);
    }
  }
  for (const auto& entry : GetDiffusionSolverRegistry().GetEntries())
  {
    SCOPED_TRACE(entry.Name);
    const std::vector<std::string>& listed = entry.Properties.LinearSolvers;
    EXPECT_EQ(listed, GetAcceptedLinearSolvers(entry.Name));
    EXPECT_EQ(entry.Properties.HasLinearSolverChoice, !listed.empty());
    EXPECT_NO_THROW(CheckLinearSolverAccepted(entry.Name, ""));
    if (listed.empty())
    {
      EXPECT_TRUE(Contains(ErrorMessage([&] { CheckLinearSolverAccepted(entry.Name, "bicgstab"); }),
        "has no linear solver to choose"));
      continue;
    }
    for (const std::string& name : built)
    {
      SCOPED_TRACE(name);
      const bool accepted = std::find(listed.begin(), listed.end(), name) != listed.end();
      std::unique_ptr<DiffusionSolver> solver = entry.Create();
      solver->SetLinearSolver(name);
      solver->SetRelTol(1e-6);
      solver->SetMaxIter(20000);
      std::vector<double> fluence;
      SolverReport report;
      bool solved = false;
      std::string refused;
      try
      {
        solved = solver->Solve(problem, fluence, report);
      }
      catch (const Error& e)
      {
        refused = e.what();
      }
      EXPECT_EQ(accepted, solved) << refused;
      EXPECT_EQ(accepted, refused.empty()) << refused;
      if (accepted)
      {
        EXPECT_NO_THROW(CheckLinearSolverAccepted(entry.Name, name));
        // A composition names the same entry.
        EXPECT_NO_THROW(CheckLinearSolverAccepted(entry.Name, GetLinearSolverComposition(name)));
      }
      else
      {
        EXPECT_EQ(ErrorMessage([&] { CheckLinearSolverAccepted(entry.Name, name); }),
          "the " + entry.Name + " solver does not accept the linear solver '" + name +
            "' (it accepts: " + JoinNames(listed) + "; empty = its default)");
      }
    }
  }
  EXPECT_EQ(GetAcceptedLinearSolvers("sp3"), (std::vector<std::string>{ "bicgstab", "multigrid-agg" }));
  EXPECT_EQ(GetAcceptedLinearSolvers("quadgraph"), GetNonSymmetricLinearSolverNames());
  EXPECT_EQ(GetAcceptedLinearSolvers("fem"), GetLinearSolverNames());
  EXPECT_EQ(ErrorMessage([] { CheckLinearSolverAccepted("sp3", "nosuchsolver"); }),
    "unknown linear solver 'nosuchsolver' for the sp3 solver (it accepts: bicgstab, "
    "multigrid-agg; empty = its default)");
}
