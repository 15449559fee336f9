#include "DiffusionSolverFactory.h"

#include "DiscreteDivergence.h"
#include "Error.h"
#include "FiniteElement.h"
#include "GridSolver.h"
#include "MonteCarlo.h"
#include "QuadGraph.h"
#include "Sp3Solver.h"
#include "Strings.h"
#include "VertexDiffusionSolver.h"

#include <algorithm>

namespace translucency
{

namespace
{
DiffusionSolverRegistry MakeRegistry()
{
  DiffusionSolverRegistry registry("solver");
  //                   linear choice, stochastic, vertices, options
  registry.Add({ "divergence",
    [] { return std::make_unique<VertexDiffusionSolver>(std::make_unique<DiscreteDivergence>()); },
    { true, false, true, {} },
    "TransCut discrete divergence at the vertices (TransCut, eq. 10-14), CG (default)" });
  registry.Add({ "fem",
    [] { return std::make_unique<VertexDiffusionSolver>(std::make_unique<FiniteElement>()); },
    { true, false, true, {} }, "linear finite elements (Galerkin) at the vertices, CG" });
  registry.Add({ "quadgraph", [] { return std::make_unique<QuadGraphSolver>(); },
    { true, false, false, { DiffusionOption::MultiLevel, DiffusionOption::TwoPointFlux } },
    "finite differences on the tet dual graph (QuadGraph, eq. 5-6), BiCGSTAB" });
  registry.Add({ "grid", [] { return std::make_unique<GridSolver>(); },
    { true, false, false, { DiffusionOption::GridSpacing, DiffusionOption::MultiLevel } },
    "regular-grid finite differences (Polygrid), BiCGSTAB" });
  registry.Add({ "montecarlo", [] { return std::make_unique<MonteCarloSolver>(); },
    { false, true, false, { DiffusionOption::Photons, DiffusionOption::Seed } },
    "photon random walk, the reference (slow, with standard errors)" });
  registry.Add({ "sp3", [] { return std::make_unique<Sp3Solver>(); }, { true, false, false, {} },
    "simplified spherical harmonics SP3 (Klose & Larsen 2006) at the vertices, anisotropy g, "
    "Fresnel boundary; continuous wave only" });
  return registry;
}
} // namespace

const DiffusionSolverRegistry& GetDiffusionSolverRegistry()
{
  static const DiffusionSolverRegistry registry = MakeRegistry();
  return registry;
}

std::vector<std::string> GetDiffusionSolverNames()
{
  return GetDiffusionSolverRegistry().GetNames();
}

std::unique_ptr<DiffusionSolver> CreateDiffusionSolver(const std::string& name)
{
  return GetDiffusionSolverRegistry().Create(name);
}

std::string GetDiffusionSolverHelp(const std::string& indent)
{
  return GetDiffusionSolverRegistry().FormatHelp(indent);
}

std::vector<std::string> GetDiffusionSolverOptionNames()
{
  std::vector<std::string> names;
  for (const auto& entry : GetDiffusionSolverRegistry().GetEntries())
  {
    names.insert(names.end(), entry.Properties.Options.begin(), entry.Properties.Options.end());
  }
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  return names;
}

void CheckDiffusionSolverOptions(const SolverOptions& options)
{
  const std::vector<std::string> known = GetDiffusionSolverOptionNames();
  for (const auto& option : options.GetValues())
  {
    if (std::find(known.begin(), known.end(), option.first) == known.end())
    {
      throw Error("unknown solver option '" + option.first + "' (known options: " +
        JoinNames(known) + ")");
    }
  }
}

} // namespace translucency
