/**
 * @file DiffusionSolverFactory.h
 * @brief Every diffusion solver by name: the one table of the family
 * (Registry.h). The interface (DiffusionSolver.h) sits below its
 * implementations in Discretizations/ and Diffusion/; this table sits above
 * them all. The factory, vtkSolveDiffusion (SetSolverByName, its error
 * messages and its SOLVER_* constants, whose order is tested against this
 * one) and the help texts read it, so a new solver is added here once
 * (and to the plugin XML's enumeration, which a test compares with
 * GetDiffusionSolverNames()).
 */
#pragma once

#include "DiffusionSolver.h"
#include "Registry.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace translucency
{

/// What callers may need to know about a solver without creating one.
struct DiffusionSolverTraits
{
  /// SetLinearSolver chooses among several linear solvers (all but Monte Carlo).
  bool HasLinearSolverChoice = false;
  /// The result is random: it depends on a seed and has a standard error.
  bool IsStochastic = false;
  /// The unknowns are the mesh vertices (VertexDiffusionSolver): incremental
  /// assembly after a paint (SetChangedTets) applies.
  bool UnknownsAtVertices = false;
  /// SolveFrequencyDomain is implemented (else the interface refuses it).
  bool SupportsFrequency = false;
  /// SolveTimeResolved is implemented (else the interface refuses it).
  bool SupportsTime = false;
  /**
   * The solver has a distributed variant: one system over the ranks of an
   * MPI communicator, every rank solving with its own piece of the mesh
   * (DiffusionSolver::SetCommunicator, DiffusionProblem::PointKeys). The
   * optional Parallel layer registers it when it is built
   * (RegisterDistributedDiffusionSolver: divergence and fem);
   * DiffusionFrontEnd::SetCommunicator chooses it by this trait.
   */
  bool Distributed = false;
  /**
   * With Distributed: the variant takes the whole problem on every rank,
   * not a piece, and splits its work over the ranks (the Monte Carlo's
   * photons, ReplicatedMonteCarloSolver). The filters then replicate the
   * whole mesh on every rank instead of handing each its piece.
   */
  bool Replicated = false;
  /// The distributed variant's factory (set with Distributed).
  std::function<std::unique_ptr<DiffusionSolver>()> CreateDistributed;
  /// The options its SetOptions reads (DiffusionOption names).
  std::vector<std::string> Options;
  /// The linear solvers its SetLinearSolver accepts: registered names of the
  /// linear-solver registry this build has (GetLinearSolverRegistry), in
  /// listing order; "" (the solver's own default by size) is accepted too.
  /// Empty exactly when HasLinearSolverChoice is false. The filter refuses
  /// any other name before solving, and the plugin's Linear Solver drop-down
  /// lists only these for the chosen Solver.
  std::vector<std::string> LinearSolvers;
};

/// The boolean traits as flags, to register an entry on one line:
/// MakeDiffusionSolverTraits(LinearSolverChoice | AtVertices | Frequency, {options}).
namespace DiffusionTrait
{
enum : unsigned
{
  LinearSolverChoice = 1u << 0, ///< HasLinearSolverChoice
  Stochastic = 1u << 1,         ///< IsStochastic
  AtVertices = 1u << 2,         ///< UnknownsAtVertices
  Frequency = 1u << 3,          ///< SupportsFrequency
  Time = 1u << 4,               ///< SupportsTime
  Distributed = 1u << 5         ///< Distributed
};
}

/// Traits from DiffusionTrait flags, the option names and the accepted
/// linear solvers (DiffusionSolverTraits::LinearSolvers).
DiffusionSolverTraits MakeDiffusionSolverTraits(unsigned flags,
  std::vector<std::string> options = {}, std::vector<std::string> linearSolvers = {});

/**
 * The linear solvers the solver called `name` accepts (its registry entry's
 * LinearSolvers; empty for a solver without a choice). Throws as
 * GetDiffusionSolverRegistry().Get(name) for an unknown solver.
 */
const std::vector<std::string>& GetAcceptedLinearSolvers(const std::string& name);

/**
 * Throws translucency::Error unless the solver called `solver` accepts the
 * linear solver `linearSolver` (a registered name or a composition
 * "KRYLOV/PRECONDITIONER"; "" is always accepted). The message names the
 * solver and lists what it accepts, e.g. "the sp3 solver does not accept
 * the linear solver 'relaxation' (it accepts: bicgstab, multigrid-agg;
 * empty = its default)", "unknown linear solver 'x' for the fem solver (it
 * accepts: ...)", or a linear solver of the registry this build lacks with
 * its remedy. A solver without a choice (Monte Carlo) accepts only "".
 */
void CheckLinearSolverAccepted(const std::string& solver, const std::string& linearSolver);

/// Names of the registered solvers with every trait of `flags` (listing order).
std::vector<std::string> GetDiffusionSolverNamesWith(unsigned flags);

using DiffusionSolverRegistry = Registry<DiffusionSolver, DiffusionSolverTraits>;

/**
 * The table, in listing order (the first is the default): "divergence",
 * "fem", "quadgraph", "grid", "montecarlo", "sp3". vtkSolveDiffusion's SOLVER_*
 * constants are indices into it.
 */
const DiffusionSolverRegistry& GetDiffusionSolverRegistry();

/// Names accepted by CreateDiffusionSolver, in the order they are listed.
std::vector<std::string> GetDiffusionSolverNames();

/**
 * A new solver by name (case-insensitive). Throws translucency::Error
 * naming the unknown name and listing the known ones.
 */
std::unique_ptr<DiffusionSolver> CreateDiffusionSolver(const std::string& name);

/**
 * Registers `create` as the distributed variant of the registered solver
 * `name` (its traits then say Distributed, and Replicated if `replicated`:
 * the variant takes the whole problem on every rank). Called by the
 * Parallel layer when the library is loaded
 * (Solvers/Parallel/DistributedVertexSolver.cxx, ReplicatedMonteCarlo.cxx),
 * so a build without it has no distributed variant. Throws
 * translucency::Error for an unknown name.
 */
void RegisterDistributedDiffusionSolver(const std::string& name,
  std::function<std::unique_ptr<DiffusionSolver>()> create, bool replicated = false);

/**
 * A new distributed variant of the solver `name` (trait Distributed), to be
 * given its communicator (DiffusionSolver::SetCommunicator). Throws
 * translucency::Error for an unknown name or a solver without one, naming
 * those with one ("the quadgraph solver has no distributed variant
 * (solvers with one: divergence, fem)").
 */
std::unique_ptr<DiffusionSolver> CreateDistributedDiffusionSolver(const std::string& name);

/// "  name    one line of help" per solver, for --help texts.
std::string GetDiffusionSolverHelp(const std::string& indent = "  ");

/// Every option name some solver reads (sorted, no duplicates).
std::vector<std::string> GetDiffusionSolverOptionNames();

/**
 * Throws translucency::Error if `options` has a name that no solver reads
 * (a typo: "unknown solver option 'gridspacing' (known options: ...)").
 * Values are checked by the solver that reads them (SetOptions).
 */
void CheckDiffusionSolverOptions(const SolverOptions& options);

} // namespace translucency
