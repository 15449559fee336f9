/**
 * @file LinearSolverFactory.cxx
 * @brief The linear-solver registry: one entry per name (factory, traits,
 * help), each a Krylov method x preconditioner composition that can also be
 * named "KRYLOV/PRECONDITIONER"; CreateLinearSolver, GetLinearSolverNames
 * and their non-symmetric counterparts are views of it.
 */
#include "LinearSolver.h"

#include "DistributedLinearSolver.h"

#include "AggregationMultigrid.h"
#include "BiCGSTAB.h"
#include "ConjugateGradient.h"
#include "Error.h"
#include "MultiresSolvers.h"
#include "Strings.h"
#include "IncompleteCholeskySolver.h"
#include "Relaxation.h"
#ifdef TRANSLUCENCY_HAVE_CHOLMOD
#include "CholmodSolver.h"
#endif
#ifdef TRANSLUCENCY_HAVE_HYPRE
#include "HypreSolver.h"
#include "SchwarzAggregation.h"
#endif

#include <algorithm>
#include <cctype>

namespace translucency
{

namespace
{

/// Jacobi-preconditioned CG (Eigen), the default.
class JacobiConjugateGradient : public LinearSolver
{
public:
  std::string GetName() const override { return "cg-jacobi"; }

  bool Solve(const DiffusionSystem& system, std::array<Eigen::VectorXd, NumberOfChannels>& x,
    bool warmStart, std::array<LinearSolveStats, NumberOfChannels>& stats) override
  {
    CG_.SetRelTol(RelTol_);
    CG_.SetMaxIter(MaxIter_);
    CG_.SetMinIter(MinIter_);
    CG_.SetProgressCallback(Progress_);
    const bool done = CG_.Solve(system, x, warmStart);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      stats[c].Iterations = CG_.GetNumIterations(c);
      stats[c].RelativeResidual = CG_.GetFinalNorm(c);
      stats[c].Converged = CG_.GetConverged(c);
      // One SpMV per iteration plus the initial residual.
      stats[c].SpMVEquivalents = CG_.GetNumIterations(c) + 1.0;
    }
    return done;
  }

  std::size_t GetMemoryBytes() const override { return CG_.GetMemoryBytes(); }

protected:
  // ConjugateGradient checks the system itself.
  void CheckSetup(const DiffusionSystem&, const TetMesh*) const override {}
  // Set-up keeps the diagonal of the values it was given (a Solve on other
  // value arrays builds its own, as a Solve without Setup does).
  void SetupValues(const DiffusionSystem& system, const TetMesh*) override
  {
    CG_.Prepare(system);
  }

private:
  ConjugateGradient CG_;
};

/// An entry whose factory makes a T.
template <typename T>
LinearSolverRegistry::Entry Make(
  const std::string& name, LinearSolverTraits traits, const std::string& help)
{
  return { name, [] { return std::unique_ptr<LinearSolver>(std::make_unique<T>()); },
    std::move(traits), help };
}

/// An entry of an optional library this build lacks: listed (so that its
/// name gives a specific error), never created.
LinearSolverRegistry::Entry Missing(
  const std::string& name, LinearSolverTraits traits, const std::string& help)
{
  traits.Built = false;
  return { name, []() -> std::unique_ptr<LinearSolver> { return nullptr; }, std::move(traits),
    help };
}

LinearSolverRegistry MakeRegistry()
{
  LinearSolverRegistry r("linear solver");
  // Symmetric positive definite systems (divergence, FEM, radiosity).
  r.Add(Make<JacobiConjugateGradient>("cg-jacobi", { "cg", "jacobi" },
    "CG with the diagonal preconditioner (Eigen), the default"));
  r.Add(Make<TransCutMultiresSolver>("transcut-multires",
    { "none", "multires", true, true },
    "the TransCut multiresolution hierarchy as a solver (TransCut, Sec. 4)"));
  r.Add(Make<MultigridConjugateGradient>("multigrid-cg", { "cg", "multires", true, true },
    "CG preconditioned by a V-cycle on the TransCut hierarchy"));
  LinearSolverTraits aggregation{ "cg", "aggregation", true, true };
#ifdef TRANSLUCENCY_HAVE_HYPRE
  // The distributed variant: hypre's PCG on the whole matrix, additive
  // Schwarz (block Jacobi over the ranks) with one aggregation cycle on
  // each rank's owned block (SchwarzAggregation.h).
  aggregation.CreateDistributed = [](const Communicator& comm) {
    return std::unique_ptr<DistributedLinearSolver>(
      std::make_unique<SchwarzAggregationPCG>(GetMPIComm(comm)));
  };
#endif
  r.Add(Make<AggregationMultigridSolver>("multigrid-agg", aggregation,
    "CG preconditioned by an aggregation multigrid W-cycle"));
  r.Add(Make<IncompleteCholeskySolver>("cg-ichol", { "cg", "ichol" },
    "CG with Eigen's incomplete Cholesky (AMD ordering)"));
  const LinearSolverTraits cholmod{ "none", "direct", true, false, "CHOLMOD", true,
    "TRANSLUCENCY_USE_CHOLMOD was off or CMake did not find CHOLMOD: install libsuitesparse-dev" };
  const std::string cholmodHelp = "sparse Cholesky factorisation (CHOLMOD), a direct solver";
#ifdef TRANSLUCENCY_HAVE_CHOLMOD
  r.Add(Make<CholmodSolver>("cholmod", cholmod, cholmodHelp));
#else
  r.Add(Missing("cholmod", cholmod, cholmodHelp));
#endif
  const LinearSolverTraits hypre{ "cg", "boomeramg", true, false, "hypre", true,
    "TRANSLUCENCY_USE_HYPRE was off or CMake did not find hypre: install libhypre-dev" };
  const std::string hypreHelp = "CG preconditioned by hypre's BoomerAMG";
#ifdef TRANSLUCENCY_HAVE_HYPRE
  // The distributed variant: BoomerAMG with the settings measured best for
  // the distributed diffusion solve (BoomerAMGOptions::Tuned()).
  LinearSolverTraits distributedHypre = hypre;
  distributedHypre.CreateDistributed = [](const Communicator& comm) {
    return std::unique_ptr<DistributedLinearSolver>(
      std::make_unique<HypreBoomerAMGPCG>(GetMPIComm(comm), BoomerAMGOptions::Tuned()));
  };
  r.Add(Make<HypreSolver>("hypre-amg", distributedHypre, hypreHelp));
#else
  r.Add(Missing("hypre-amg", hypre, hypreHelp));
#endif
  // Non-symmetric systems (QuadGraph, grid).
  r.Add(Make<BiCGSTABSolver>("bicgstab", { "bicgstab", "jacobi", false },
    "BiCGSTAB with the diagonal preconditioner, for non-symmetric systems (default there)"));
  r.Add(Make<RelaxationSolver>("relaxation", { "none", "relaxation", false },
    "the papers' relaxation sweeps (QuadGraph, eq. 8-9; Polygrid, Sec. 5.2)"));
  return r;
}

/// Names of the built entries with the given symmetry requirement.
std::vector<std::string> NamesOf(bool symmetric)
{
  std::vector<std::string> names;
  for (const auto& entry : GetLinearSolverRegistry().GetEntries())
  {
    if (entry.Properties.Built && entry.Properties.NeedsSymmetricPositiveDefinite == symmetric)
    {
      names.push_back(entry.Name);
    }
  }
  return names;
}

} // namespace

const LinearSolverRegistry& GetLinearSolverRegistry()
{
  static const LinearSolverRegistry registry = MakeRegistry();
  return registry;
}

std::string GetLinearSolverComposition(const std::string& name)
{
  const LinearSolverTraits& traits =
    GetLinearSolverRegistry().Get(ResolveLinearSolverName(name)).Properties;
  return traits.Krylov + "/" + traits.Preconditioner;
}

std::string ResolveLinearSolverName(const std::string& name)
{
  const LinearSolverRegistry& registry = GetLinearSolverRegistry();
  if (const auto* entry = registry.Find(name))
  {
    return entry->Name;
  }
  const std::string key = ToLower(name);
  const std::size_t slash = key.find('/');
  if (slash == std::string::npos)
  {
    return name;
  }
  const std::string krylov = key.substr(0, slash), preconditioner = key.substr(slash + 1);
  for (const auto& entry : registry.GetEntries())
  {
    if (entry.Properties.Krylov == krylov && entry.Properties.Preconditioner == preconditioner)
    {
      return entry.Name;
    }
  }
  return name;
}

const LinearSolverRegistry::Entry& FindLinearSolver(
  const std::string& krylov, const std::string& preconditioner)
{
  for (const auto& entry : GetLinearSolverRegistry().GetEntries())
  {
    if (entry.Properties.Built && entry.Properties.Krylov == krylov &&
      entry.Properties.Preconditioner == preconditioner)
    {
      return entry;
    }
  }
  throw Error("no linear solver " + krylov + "/" + preconditioner + " in this build");
}

std::unique_ptr<DistributedLinearSolver> CreateDistributedLinearSolver(
  const std::string& name, const Communicator& comm)
{
  const auto* entry = GetLinearSolverRegistry().Find(ResolveLinearSolverName(name));
  std::vector<std::string> with;
  for (const auto& e : GetLinearSolverRegistry().GetEntries())
  {
    if (e.Properties.Built && e.Properties.CreateDistributed)
    {
      with.push_back(e.Properties.Krylov + "/" + e.Properties.Preconditioner);
    }
  }
  const std::string known = with.empty() ? std::string("this build has none: it needs hypre")
                                         : "those with one: " + JoinNames(with);
  if (entry && !entry->Properties.Built)
  {
    throw Error("linear solver '" + name + "' is not in this build (" + entry->Properties.Remedy +
      " and reconfigure)");
  }
  if (!entry || !entry->Properties.CreateDistributed)
  {
    throw Error("linear solver '" + name + "' has no distributed variant (" + known + ")");
  }
  return entry->Properties.CreateDistributed(comm);
}

std::vector<std::string> GetLinearSolverNames()
{
  return NamesOf(true);
}

std::vector<std::string> GetNonSymmetricLinearSolverNames()
{
  return NamesOf(false);
}

std::unique_ptr<LinearSolver> CreateLinearSolver(const std::string& name)
{
  const auto* entry = GetLinearSolverRegistry().Find(ResolveLinearSolverName(name));
  const std::string known = JoinNames(GetLinearSolverNames());
  if (entry && !entry->Properties.Built)
  {
    throw Error("linear solver '" + name + "' is not in this build (" + entry->Properties.Remedy +
      " and reconfigure; this build has: " + known + ")");
  }
  if (!entry || !entry->Properties.NeedsSymmetricPositiveDefinite)
  {
    throw Error("unknown linear solver '" + name + "' (this build has: " + known + ")");
  }
  return entry->Create();
}

std::unique_ptr<ChannelLinearSolver> CreateNonSymmetricLinearSolver(
  const std::string& name, const std::string& who)
{
  const std::string key = name.empty() ? std::string("bicgstab") : name;
  const auto* entry = GetLinearSolverRegistry().Find(ResolveLinearSolverName(key));
  const std::string known = JoinNames(GetNonSymmetricLinearSolverNames());
  if (entry && entry->Properties.Built && entry->Properties.NeedsSymmetricPositiveDefinite)
  {
    throw Error(who + ": linear solver '" + name + "' needs a symmetric positive definite matrix; " +
      "this system is not symmetric (known: " + known + ")");
  }
  if (!entry || !entry->Properties.Built)
  {
    throw Error(who + ": unknown linear solver '" + name + "' (known: " + known + ")");
  }
  std::unique_ptr<LinearSolver> solver = entry->Create();
  auto* channel = dynamic_cast<ChannelLinearSolver*>(solver.get());
  if (!channel)
  {
    throw Error("linear solver '" + entry->Name +
      "': an entry for non-symmetric systems must be a ChannelLinearSolver");
  }
  solver.release();
  return std::unique_ptr<ChannelLinearSolver>(channel);
}

} // namespace translucency
