/**
 * @file BiCGSTAB.h
 * @brief "bicgstab": BiCGSTAB with the Jacobi preconditioner for the
 * non-symmetric systems of the QuadGraph and grid discretisations.
 */
#pragma once

#include "LinearSolver.h"

namespace translucency
{

/**
 * BiCGSTAB (van der Vorst 1992) with the diagonal (Jacobi) preconditioner
 * applied on the right, as Eigen's BiCGSTAB, with the vector updates fused
 * into the products (5 parallel loops per iteration) and deterministic block
 * sums, so that the result does not depend on the number of threads.
 * Restarts (r0 = r) when r0 . r underflows, and from the true residual when
 * the recurrence claims a convergence the true residual does not confirm.
 * The reported residual is the true ||b - M x|| / ||b||; converged means it
 * is <= GetRelTol(). A zero diagonal entry is taken as 1 in the
 * preconditioner. Threads: SetNumberOfThreads (0 = OpenMP's default).
 */
class BiCGSTABSolver : public ChannelLinearSolver
{
public:
  std::string GetName() const override { return "bicgstab"; }
  std::size_t GetMemoryBytes() const override { return MemoryBytes_; }

  /// Iterations between two progress reports within a channel (250).
  static constexpr int ProgressInterval = 250;

  /// Restart (r0 = r = b - M x, the search directions dropped) every this
  /// many iterations; 0 (default) restarts only on breakdown or a false
  /// convergence. QuadGraph restarts every 250 iterations, as it did when it
  /// ran Eigen's BiCGSTAB in calls of 250: on its systems that converges in
  /// about half the iterations.
  void SetRestartInterval(int n) { RestartInterval_ = n; }
  int GetRestartInterval() const { return RestartInterval_; }

protected:
  bool Iterate(const DiffusionSystem& system, int c, Eigen::VectorXd& x, double bNorm,
    LinearSolveStats& stats, const std::function<bool(int)>& progress) override;

private:
  std::size_t MemoryBytes_ = 0;
  int RestartInterval_ = 0;
};

} // namespace translucency
