#include "DiffusionSolverFactory.h"

#include "DiscreteDivergence.h"
#include "Error.h"
#include "FiniteElement.h"
#include "GridSolver.h"
#include "LinearSolver.h"
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
  // The linear solvers each accepts: the vertex discretisations' systems are
  // symmetric positive definite (every such solver this build has), QuadGraph's
  // and the grid's are not (BiCGSTAB, relaxation); SP3's BiCGSTAB takes the
  // block-diagonal Jacobi ("bicgstab") or one multigrid-agg cycle per block
  // (Sp3Solver::ChoosePreconditioner maps the names to these two).
  const std::vector<std::string> symmetric = GetLinearSolverNames();
  const std::vector<std::string> nonSymmetric = GetNonSymmetricLinearSolverNames();
  const std::vector<std::string> sp3 = { "bicgstab", "multigrid-agg" };
  registry.Add({ "divergence",
    [] { return std::make_unique<VertexDiffusionSolver>(std::make_unique<DiscreteDivergence>()); },
    MakeDiffusionSolverTraits(LinearSolverChoice | AtVertices | Frequency | Time,
      { DiffusionOption::TimeStepRecycled }, symmetric),
    "TransCut discrete divergence at the vertices (TransCut, eq. 10-14), CG (default)" });
  registry.Add({ "fem",
    [] { return std::make_unique<VertexDiffusionSolver>(std::make_unique<FiniteElement>()); },
    MakeDiffusionSolverTraits(LinearSolverChoice | AtVertices | Frequency | Time,
      { DiffusionOption::TimeStepRecycled }, symmetric),
    "linear finite elements (Galerkin) at the vertices, CG" });
  registry.Add({ "quadgraph", [] { return std::make_unique<QuadGraphSolver>(); },
    MakeDiffusionSolverTraits(
      LinearSolverChoice, { DiffusionOption::MultiLevel, DiffusionOption::TwoPointFlux },
      nonSymmetric),
    "finite differences on the tet dual graph (QuadGraph, eq. 5-6), BiCGSTAB" });
  registry.Add({ "grid", [] { return std::make_unique<GridSolver>(); },
    MakeDiffusionSolverTraits(
      LinearSolverChoice, { DiffusionOption::GridSpacing, DiffusionOption::MultiLevel },
      nonSymmetric),
    "regular-grid finite differences (Polygrid), BiCGSTAB" });
  registry.Add({ "montecarlo", [] { return std::make_unique<MonteCarloSolver>(); },
    MakeDiffusionSolverTraits(Stochastic | Time,
      { DiffusionOption::Photons, DiffusionOption::Seed, DiffusionOption::Anisotropy }),
    "photon random walk, the reference (slow, with standard errors)" });
  registry.Add({ "sp3", [] { return std::make_unique<Sp3Solver>(); },
    MakeDiffusionSolverTraits(
      LinearSolverChoice | Frequency, { DiffusionOption::Anisotropy }, sp3),
    "simplified spherical harmonics SP3 (Klose & Larsen 2006) at the vertices, anisotropy g, "
    "Fresnel boundary; continuous wave and frequency domain" });
  return registry;
}
} // namespace

DiffusionSolverTraits MakeDiffusionSolverTraits(
  unsigned flags, std::vector<std::string> options, std::vector<std::string> linearSolvers)
{
  DiffusionSolverTraits traits;
  traits.HasLinearSolverChoice = (flags & DiffusionTrait::LinearSolverChoice) != 0;
  traits.IsStochastic = (flags & DiffusionTrait::Stochastic) != 0;
  traits.UnknownsAtVertices = (flags & DiffusionTrait::AtVertices) != 0;
  traits.SupportsFrequency = (flags & DiffusionTrait::Frequency) != 0;
  traits.SupportsTime = (flags & DiffusionTrait::Time) != 0;
  traits.Distributed = (flags & DiffusionTrait::Distributed) != 0;
  traits.Options = std::move(options);
  traits.LinearSolvers = std::move(linearSolvers);
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

void RegisterDistributedDiffusionSolver(const std::string& name,
  std::function<std::unique_ptr<DiffusionSolver>()> create, bool replicated)
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
      entry.Properties.Replicated = replicated;
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

const std::vector<std::string>& GetAcceptedLinearSolvers(const std::string& name)
{
  return GetDiffusionSolverRegistry().Get(name).Properties.LinearSolvers;
}

void CheckLinearSolverAccepted(const std::string& solver, const std::string& linearSolver)
{
  const auto& entry = GetDiffusionSolverRegistry().Get(solver);
  if (linearSolver.empty())
  {
    return;
  }
  const std::vector<std::string>& accepted = entry.Properties.LinearSolvers;
  if (accepted.empty())
  {
    throw Error("the " + entry.Name + " solver has no linear solver to choose; leave the " +
      "linear solver empty (it was '" + linearSolver + "')");
  }
  const std::string name = ToLower(ResolveLinearSolverName(linearSolver));
  if (std::find(accepted.begin(), accepted.end(), name) != accepted.end())
  {
    return;
  }
  const std::string choices = " (it accepts: " + JoinNames(accepted) + "; empty = its default)";
  const auto* known = GetLinearSolverRegistry().Find(name);
  if (!known)
  {
    throw Error("unknown linear solver '" + linearSolver + "' for the " + entry.Name + " solver" +
      choices);
  }
  if (!known->Properties.Built)
  {
    throw Error("linear solver '" + linearSolver + "' is not in this build (" +
      known->Properties.Remedy + " and reconfigure); the " + entry.Name + " solver" + choices);
  }
  throw Error("the " + entry.Name + " solver does not accept the linear solver '" +
    linearSolver + "'" + choices);
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
