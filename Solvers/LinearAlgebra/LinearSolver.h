/**
 * @file LinearSolver.h
 * @brief The seam between the vertex discretisations (discrete divergence,
 * FEM) and the linear solvers a user can pick for their SPD systems:
 * Jacobi-CG (the default), the TransCut multiresolution hierarchy, multigrid-
 * preconditioned CG and the peer libraries (Eigen incomplete Cholesky,
 * CHOLMOD, hypre BoomerAMG). Every solver works on the three channels of one
 * DiffusionSystem (shared pattern, one value array per channel).
 *
 * Life cycle: Setup() whenever the matrix changes (the flag says whether the
 * pattern, i.e. the topology, changed too, so a solver can keep symbolic work
 * or the structure of its hierarchy while only values change); Solve() for
 * every new right-hand side (relighting), optionally from the previous x.
 */
#pragma once

#include "DiffusionSystem.h"

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace translucency
{

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
   */
  virtual void Setup(const DiffusionSystem& system, const TetMesh* mesh, bool patternChanged) = 0;

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

  /// Fraction done in [0, 1]; returning false aborts the solve.
  void SetProgressCallback(std::function<bool(double)> callback) { Progress_ = std::move(callback); }

  /// Bytes held beyond the system itself (factor, hierarchy, preconditioner).
  virtual std::size_t GetMemoryBytes() const { return 0; }

protected:
  bool ReportProgress(double fraction) const { return !Progress_ || Progress_(fraction); }

  double RelTol_ = 1e-6;
  int MaxIter_ = 2000;
  std::function<bool(double)> Progress_;
};

/// The linear solver called `name` (case-insensitive). Throws
/// translucency::Error naming the known solvers if it is unknown or was not
/// built (optional libraries).
std::unique_ptr<LinearSolver> CreateLinearSolver(const std::string& name);

/// Names of the linear solvers this build has, the default first.
std::vector<std::string> GetLinearSolverNames();

} // namespace translucency
