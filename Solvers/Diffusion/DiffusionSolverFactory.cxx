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
  using namespace DiffusionTrait;
  DiffusionSolverRegistry registry("solver");
  registry.Add({ "divergence",
    [] { return std::make_unique<VertexDiffusionSolver>(std::make_unique<DiscreteDivergence>()); },
    MakeDiffusionSolverTraits(LinearSolverChoice | AtVertices | Frequency | Time,
      { DiffusionOption::TimeStepRecycled }),
    "TransCut discrete divergence at the vertices (TransCut, eq. 10-14), CG (default)" });
  registry.Add({ "fem",
    [] { return std::make_unique<VertexDiffusionSolver>(std::make_unique<FiniteElement>()); },
    MakeDiffusionSolverTraits(LinearSolverChoice | AtVertices | Frequency | Time,
      { DiffusionOption::TimeStepRecycled }),
    "linear finite elements (Galerkin) at the vertices, CG" });
  registry.Add({ "quadgraph", [] { return std::make_unique<QuadGraphSolver>(); },
    MakeDiffusionSolverTraits(
      LinearSolverChoice, { DiffusionOption::MultiLevel, DiffusionOption::TwoPointFlux }),
    "finite differences on the tet dual graph (QuadGraph, eq. 5-6), BiCGSTAB" });
  registry.Add({ "grid", [] { return std::make_unique<GridSolver>(); },
    MakeDiffusionSolverTraits(
      LinearSolverChoice, { DiffusionOption::GridSpacing, DiffusionOption::MultiLevel }),
    "regular-grid finite differences (Polygrid), BiCGSTAB" });
  registry.Add({ "montecarlo", [] { return std::make_unique<MonteCarloSolver>(); },
    MakeDiffusionSolverTraits(Stochastic | Time,
      { DiffusionOption::Photons, DiffusionOption::Seed, DiffusionOption::Anisotropy }),
    "photon random walk, the reference (slow, with standard errors)" });
  registry.Add({ "sp3", [] { return std::make_unique<Sp3Solver>(); },
    MakeDiffusionSolverTraits(LinearSolverChoice | Frequency, { DiffusionOption::Anisotropy }),
    "simplified spherical harmonics SP3 (Klose & Larsen 2006) at the vertices, anisotropy g, "
    "Fresnel boundary; continuous wave and frequency domain" });
  return registry;
}
} // namespace

DiffusionSolverTraits MakeDiffusionSolverTraits(unsigned flags, std::vector<std::string> options)
{
  DiffusionSolverTraits traits;
  traits.HasLinearSolverChoice = (flags & DiffusionTrait::LinearSolverChoice) != 0;
  traits.IsStochastic = (flags & DiffusionTrait::Stochastic) != 0;
  traits.UnknownsAtVertices = (flags & DiffusionTrait::AtVertices) != 0;
  traits.SupportsFrequency = (flags & DiffusionTrait::Frequency) != 0;
  traits.SupportsTime = (flags & DiffusionTrait::Time) != 0;
  traits.Distributed = (flags & DiffusionTrait::Distributed) != 0;
  traits.Options = std::move(options);
  return traits;
}

std::vector<std::string> GetDiffusionSolverNamesWith(unsigned flags)
{
  std::vector<std::string> names;
  for (const auto& entry : GetDiffusionSolverRegistry().GetEntries())
  {
    const DiffusionSolverTraits& t = entry.Properties;
    const unsigned has = (t.HasLinearSolverChoice ? DiffusionTrait::LinearSolverChoice : 0u) |
      (t.IsStochastic ? DiffusionTrait::Stochastic : 0u) |
      (t.UnknownsAtVertices ? DiffusionTrait::AtVertices : 0u) |
      (t.SupportsFrequency ? DiffusionTrait::Frequency : 0u) |
      (t.SupportsTime ? DiffusionTrait::Time : 0u) |
      (t.Distributed ? DiffusionTrait::Distributed : 0u);
    if ((has & flags) == flags)
    {
      names.push_back(entry.Name);
    }
  }
  return names;
}

namespace
{
/// The table; changed only by RegisterDistributedDiffusionSolver (when the
/// library is loaded), read-only after.
DiffusionSolverRegistry& MutableRegistry()
{
  static DiffusionSolverRegistry registry = MakeRegistry();
  return registry;
}
} // namespace

const DiffusionSolverRegistry& GetDiffusionSolverRegistry()
{
  return MutableRegistry();
}

void RegisterDistributedDiffusionSolver(
  const std::string& name, std::function<std::unique_ptr<DiffusionSolver>()> create)
{
  DiffusionSolverRegistry& registry = MutableRegistry();
  const std::string key = registry.Get(name).Name; // throws for an unknown name
  // Registry entries are read-only: rebuild the table with the new traits.
  DiffusionSolverRegistry updated("solver");
  for (DiffusionSolverRegistry::Entry entry : registry.GetEntries())
  {
    if (entry.Name == key)
    {
      entry.Properties.Distributed = true;
      entry.Properties.CreateDistributed = create;
    }
    updated.Add(std::move(entry));
  }
  registry = std::move(updated);
}

std::unique_ptr<DiffusionSolver> CreateDistributedDiffusionSolver(const std::string& name)
{
  const DiffusionSolverRegistry::Entry& entry = GetDiffusionSolverRegistry().Get(name);
  if (!entry.Properties.Distributed || !entry.Properties.CreateDistributed)
  {
    const std::vector<std::string> with = GetDiffusionSolverNamesWith(DiffusionTrait::Distributed);
    throw Error("the " + entry.Name + " solver has no distributed variant (" +
      (with.empty() ? std::string("this build has none: it needs hypre and MPI")
                    : "solvers with one: " + JoinNames(with)) +
      ")");
  }
  return entry.Properties.CreateDistributed();
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
