/**
 * @file LinearSolver.h
 * @brief The seam between the vertex discretisations (discrete divergence,
 * FEM) and the linear solvers a user can pick for their SPD systems:
 * Jacobi-CG (the default), the TransCut multiresolution hierarchy, multigrid-
 * preconditioned CG and the peer libraries (Eigen incomplete Cholesky,
 * CHOLMOD, hypre BoomerAMG). Every solver works on the three channels of one
 * DiffusionSystem (shared pattern, one value array per channel).
 *
 * The non-symmetric discretisations (QuadGraph, grid) pick theirs from the
 * same registry: BiCGSTAB with the Jacobi preconditioner and the papers'
 * relaxation sweeps (ChannelLinearSolver, which also solves one channel).
 *
 * Life cycle: Setup() whenever the matrix changes (the flag says whether the
 * pattern, i.e. the topology, changed too, so a solver can keep symbolic work
 * or the structure of its hierarchy while only values change); Solve() for
 * every new right-hand side (relighting), optionally from the previous x.
 * Setup() decides once, here, between a rebuild (SetupStructure, then
 * SetupValues) and a values-only set-up (SetupValues), as PETSc's PCSetUp.
 */
#pragma once

#include "Communicator.h"
#include "DiffusionSystem.h"
#include "Registry.h"

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace translucency
{
class DistributedLinearSolver;


class TetMesh;

/// What one channel's solve cost and how it ended.
struct LinearSolveStats
{
  int Iterations = 0;            ///< outer iterations (0 for a direct solve)
  double RelativeResidual = 0.0; ///< ||b - Mx|| / ||b|| at the end
  bool Converged = false;
  /// Work in units of one SpMV with this channel's matrix (multiply-adds of
  /// the solve divided by the matrix's nonzeros), for the bench's table.
  double SpMVEquivalents = 0.0;
  /// True when the channel stopped by the change rule (SetChangeRule), not
  /// by RelTol; Converged is then true too.
  bool StoppedByChange = false;
};

class LinearSolver
{
public:
  virtual ~LinearSolver() = default;

  /// The name scripts use, e.g. "cg-jacobi".
  virtual std::string GetName() const = 0;

  /**
   * Prepare for the matrices of `system` (its pattern and Values). `mesh`
   * is the mesh the unknowns live on (the multiresolution hierarchy needs its
   * vertex graph and positions; matrix-only solvers ignore it; it may be
   * null for those). patternChanged = false promises that only Values changed
   * since the last Setup (same unknowns, same pattern).
   *
   * Checks the system (CheckSetup), then rebuilds (SetupStructure and
   * SetupValues) when the pattern changed, on the first call, after a failed
   * Setup or when the number of unknowns or nonzeros differs from the last
   * Setup; otherwise only SetupValues runs.
   */
  void Setup(const DiffusionSystem& system, const TetMesh* mesh, bool patternChanged);

  /**
   * Values-only Setup after a change confined to `rows` (a paint stroke):
   * every entry of the matrices that changed since the last Setup lies in
   * one of these rows (for a symmetric system list both i and j of a changed
   * a_ij, e.g. every vertex of a repainted tet; duplicates are allowed).
   * Solvers that can refresh part of their set-up do (SetupRows: multigrid-
   * agg refreshes the level-0 smoother of these rows and keeps its coarse
   * levels), the others run SetupValues. Without a successful Setup for a
   * system of this size this is Setup(system, mesh, true). Throws
   * translucency::Error for a row out of range.
   */
  void SetupChangedRows(const DiffusionSystem& system, const TetMesh* mesh,
    const std::vector<int>& rows);

  /**
   * Solve the three channels of `system` (the one given to Setup, with its
   * current right-hand sides). If warmStart and x[c] has the right size it is
   * the initial guess, otherwise the solve starts from zero. Returns false if
   * the progress callback aborted. Not converging is not an error.
   */
  virtual bool Solve(const DiffusionSystem& system, std::array<Eigen::VectorXd, NumberOfChannels>& x,
    bool warmStart, std::array<LinearSolveStats, NumberOfChannels>& stats) = 0;

  ///@{
  /// Relative residual to reach (default 1e-6) and iteration limit (default 2000).
  void SetRelTol(double tol) { RelTol_ = tol; }
  double GetRelTol() const { return RelTol_; }
  void SetMaxIter(int n) { MaxIter_ = n; }
  int GetMaxIter() const { return MaxIter_; }
  ///@}

  ///@{
  /**
   * Fewest iterations of a channel whose initial residual is not zero
   * (default 0: a warm start already within RelTol runs none). The vertex
   * solvers set 1 for the warm start after a paint stroke, so that the
   * stroke's own change of the solution is resolved even when the stroke
   * moves the global relative residual by less than a loose RelTol
   * (Documentation/Solvers.md, "The interactive stopping rule"). Honoured by
   * the CG solvers (cg-jacobi, multigrid-agg, multigrid-cg); the others
   * ignore it.
   */
  void SetMinIter(int n) { MinIter_ = n < 0 ? 0 : n; }
  int GetMinIter() const { return MinIter_; }
  ///@}

  ///@{
  /**
   * The interactive accuracy rule (Documentation/Solvers.md, "The
   * interactive stopping rule"): with tol > 0 and observed rows (e.g. the
   * boundary points, what the picture shows), a channel also stops, as
   * converged, once the estimated error of its solution over those rows is
   * at most tol relative to the solution there (RMS). After iteration k >=
   * max(3, MinIter), with Delta_k = ||x_k - x_{k-1}||_R / ||x_k||_R and
   * rho the larger of Delta_k / Delta_{k-1} and Delta_{k-1} / Delta_{k-2},
   * the estimate is the geometric tail of the changes still to come,
   * Delta_k rho / (1 - rho); rho >= 1 never stops. tol = 0 (the default) or no rows: off, the residual rule alone.
   * Rows are checked (in [0, unknowns)) by the solve. Honoured by
   * multigrid-agg; the other solvers ignore it.
   */
  void SetChangeRule(double tol, std::vector<int> rows)
  {
    ChangeTol_ = tol > 0.0 ? tol : 0.0;
    ChangeRows_ = std::move(rows);
  }
  double GetChangeTol() const { return ChangeTol_; }
  const std::vector<int>& GetChangeRows() const { return ChangeRows_; }
  ///@}

  /// Fraction done in [0, 1]; returning false aborts the solve.
  void SetProgressCallback(std::function<bool(double)> callback) { Progress_ = std::move(callback); }

  /// OpenMP threads of the solver's own loops (default 0: OpenMP's default).
  /// Solvers whose loops run on Eigen's or a library's threads ignore it.
  virtual void SetNumberOfThreads(int n) { NumberOfThreads_ = n; }
  int GetNumberOfThreads() const { return NumberOfThreads_; }

  /// Bytes held beyond the system itself (factor, hierarchy, preconditioner).
  virtual std::size_t GetMemoryBytes() const { return 0; }

  ///@{
  /**
   * The preconditioner-apply hook, for Krylov methods outside this solver
   * (the frequency-domain COCG preconditions with the real part's multigrid;
   * Documentation/DiffuseOptics.md). HasPreconditioner() says whether the
   * solver has a fixed symmetric positive definite operator B ~ A^-1 of the
   * matrices given to the last Setup (default false; multigrid-agg: its
   * cycle). ApplyPreconditioner computes z = B r on the three channels
   * interleaved (3 n values, channel c of unknown i at 3 i + c; r and z do
   * not overlap); it throws translucency::Error (naming the solver) without
   * a preconditioner or before a successful Setup. B is linear: a complex
   * vector is preconditioned by applying it to its real and imaginary parts.
   */
  virtual bool HasPreconditioner() const { return false; }
  virtual void ApplyPreconditioner(const double* r, double* z) const;
  ///@}

protected:
  bool ReportProgress(double fraction) const { return !Progress_ || Progress_(fraction); }

  /// Throws translucency::Error unless Setup() can work on `system` (and
  /// `mesh`). Default: CheckLinearSystem with GetName() as the prefix.
  virtual void CheckSetup(const DiffusionSystem& system, const TetMesh* mesh) const;
  /// The pattern-dependent part of Setup (symbolic analysis, hierarchy);
  /// runs before SetupValues when Setup decided to rebuild. Default: nothing.
  virtual void SetupStructure(const DiffusionSystem&, const TetMesh*) {}
  /// The value-dependent part of Setup (numeric factorisation, coarse
  /// values); runs on every Setup. Default: nothing.
  virtual void SetupValues(const DiffusionSystem&, const TetMesh*) {}
  /// The part of SetupChangedRows after its checks (rows in range, a Setup
  /// for this size done). Default: SetupValues.
  virtual void SetupRows(
    const DiffusionSystem& system, const TetMesh* mesh, const std::vector<int>& /*rows*/)
  {
    SetupValues(system, mesh);
  }
  /// Whether the last Setup succeeded for a system of this size.
  bool IsSetUpFor(const DiffusionSystem& system) const
  {
    return Ready_ && Unknowns_ == system.NumberOfUnknowns &&
      NonZeros_ == system.ColumnIndices.size();
  }

  double RelTol_ = 1e-6;
  int MaxIter_ = 2000;
  int MinIter_ = 0;
  double ChangeTol_ = 0.0;
  std::vector<int> ChangeRows_;
  int NumberOfThreads_ = 0;
  std::function<bool(double)> Progress_;
  ///@{
  /// State of the last Setup (IsSetUpFor); Ready_ is false until a Setup
  /// succeeds and again while one runs.
  bool Ready_ = false;
  int Unknowns_ = -1;
  std::size_t NonZeros_ = 0;
  ///@}
};

/**
 * A solver that works channel by channel (the non-symmetric entries of the
 * registry, "bicgstab" and "relaxation"): Solve() runs SolveChannel on the
 * three channels; the discretisations that interleave channels and levels
 * (QuadGraph's multi-level initialisation) call SolveChannel directly. No
 * Setup() is needed: each solve reads the current values.
 */
class ChannelLinearSolver : public LinearSolver
{
public:
  bool Solve(const DiffusionSystem& system, std::array<Eigen::VectorXd, NumberOfChannels>& x,
    bool warmStart, std::array<LinearSolveStats, NumberOfChannels>& stats) override;

  /**
   * Solve channel c from x (the guess when warmStart and x has the right
   * size, else zero). A zero right-hand side gives x = 0, converged, 0
   * iterations. During the iterations the progress callback receives
   * progressBase + progressSpan * iterations / MaxIter. Returns false if it
   * aborted.
   */
  bool SolveChannel(const DiffusionSystem& system, int c, Eigen::VectorXd& x, bool warmStart,
    LinearSolveStats& stats, double progressBase = 0.0, double progressSpan = 0.0);

protected:
  void CheckSetup(const DiffusionSystem&, const TetMesh*) const override {}
  /// The iterations on channel c from x (b != 0); `progress(iterations)`
  /// returns false to abort, and then so does Iterate.
  virtual bool Iterate(const DiffusionSystem& system, int c, Eigen::VectorXd& x, double bNorm,
    LinearSolveStats& stats, const std::function<bool(int)>& progress) = 0;
};

/// What the registry says about a linear solver.
struct LinearSolverTraits
{
  /// The Krylov method: "cg", "bicgstab", or "none" (direct, relaxation).
  std::string Krylov;
  /// The preconditioner (or the whole method when Krylov is "none"):
  /// "jacobi", "ichol", "multires", "aggregation", "boomeramg", "direct",
  /// "relaxation".
  std::string Preconditioner;
  /// Needs a symmetric positive definite matrix (the systems of the vertex
  /// discretisations); false for the solvers of the non-symmetric QuadGraph
  /// and grid systems, which are ChannelLinearSolver.
  bool NeedsSymmetricPositiveDefinite = true;
  /// Setup() needs the mesh the unknowns live on (multiresolution hierarchy).
  bool NeedsMesh = false;
  /// The optional library it needs ("" = always built), e.g. "CHOLMOD".
  std::string Library;
  /// Whether this build has it (false: optional library not found; the
  /// entry is listed so that its name gives a specific error).
  bool Built = true;
  /// How to get the library when it is not built (for the error message).
  std::string Remedy;
  /// The composition's distributed variant (one matrix over the ranks of an
  /// MPI communicator: DistributedLinearSolver.h), or empty: "cg/boomeramg".
  std::function<std::unique_ptr<DistributedLinearSolver>(const Communicator&)> CreateDistributed;
};

using LinearSolverRegistry = Registry<LinearSolver, LinearSolverTraits>;

/// Every linear solver this code knows, built or not (Traits::Built), the
/// default "cg-jacobi" first.
const LinearSolverRegistry& GetLinearSolverRegistry();

/**
 * A linear solver is a Krylov method composed with a preconditioner
 * (LinearSolverTraits::Krylov x Preconditioner, as PETSc composes a KSP with
 * a PC): every entry of the registry is one composition, named
 * "KRYLOV/PRECONDITIONER" ("cg/jacobi", "cg/ichol", "cg/aggregation",
 * "cg/multires", "cg/boomeramg", "none/multires", "none/direct",
 * "bicgstab/jacobi", "none/relaxation"; "none": the preconditioner is the
 * whole method). The registered names ("cg-jacobi", "multigrid-agg", ...)
 * are aliases of their compositions: CreateLinearSolver and
 * CreateNonSymmetricLinearSolver take either spelling (case-insensitive) and
 * create the same solver.
 */
/// The composition "KRYLOV/PRECONDITIONER" of the entry called `name` (a
/// registered name or a composition); throws translucency::Error for an
/// unknown name.
std::string GetLinearSolverComposition(const std::string& name);

/// The registered name of `name`: itself (lower case) for a registered
/// name, the entry's name for a composition "KRYLOV/PRECONDITIONER" of the
/// registry (built or not), else `name` unchanged (CreateLinearSolver then
/// names it unknown).
std::string ResolveLinearSolverName(const std::string& name);

/// The built entry with the given Krylov method and preconditioner (traits,
/// not a name, e.g. ("cg", "jacobi")); throws translucency::Error if this
/// build has none.
const LinearSolverRegistry::Entry& FindLinearSolver(
  const std::string& krylov, const std::string& preconditioner);

/// The solver of symmetric positive definite systems called `name`
/// (case-insensitive). Throws translucency::Error naming the known solvers
/// if it is unknown, not built (optional libraries) or for non-symmetric
/// systems only.
std::unique_ptr<LinearSolver> CreateLinearSolver(const std::string& name);

/// Names of the solvers of symmetric positive definite systems this build
/// has (the vertex discretisations' and radiosity's choice), default first.
std::vector<std::string> GetLinearSolverNames();

/// Names of the solvers of non-symmetric systems (QuadGraph, grid), the
/// default "bicgstab" first.
std::vector<std::string> GetNonSymmetricLinearSolverNames();

/// The solver of non-symmetric systems called `name` (case-insensitive; ""
/// is "bicgstab"). Throws translucency::Error prefixed with `who` ("grid:")
/// naming the known ones, e.g. "unknown linear solver 'x' (known: bicgstab,
/// relaxation)".
std::unique_ptr<ChannelLinearSolver> CreateNonSymmetricLinearSolver(
  const std::string& name, const std::string& who);

} // namespace translucency
