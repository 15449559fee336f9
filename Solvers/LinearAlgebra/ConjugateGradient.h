/**
 * @file ConjugateGradient.h
 * @brief Jacobi-preconditioned conjugate gradient per colour channel for the
 * SPD systems of the vertex discretisations (Eigen's ConjugateGradient on the
 * shared-pattern maps; its SpMV runs on OpenMP threads).
 */
#pragma once

#include "DiffusionSystem.h"

#include <array>
#include <functional>
#include <memory>

namespace translucency
{

class ConjugateGradient
{
public:
  ConjugateGradient();
  ~ConjugateGradient();
  ConjugateGradient(ConjugateGradient&&) noexcept;
  ConjugateGradient& operator=(ConjugateGradient&&) noexcept;

  /// Relative residual ||b - Mx|| / ||b|| to reach. Default 1e-6.
  void SetRelTol(double tol) { RelTol_ = tol; }
  double GetRelTol() const { return RelTol_; }
  /// Iteration limit per channel. Default 2000.
  void SetMaxIter(int n) { MaxIter_ = n; }
  int GetMaxIter() const { return MaxIter_; }
  /// Fewest iterations of a channel whose initial residual is not zero
  /// (LinearSolver::SetMinIter). Default 0.
  void SetMinIter(int n) { MinIter_ = n < 0 ? 0 : n; }
  int GetMinIter() const { return MinIter_; }

  /**
   * Called between channels with the fraction done in [0, 1]; returning
   * false aborts the solve (Solve then returns false and the statistics of
   * the unsolved channels say not converged).
   */
  void SetProgressCallback(std::function<bool(double)> callback) { Progress_ = std::move(callback); }

  /**
   * Solve the three channels. If warmStart and x[c] has the right size, it
   * is the initial guess; otherwise iteration starts from zero. A zero
   * right-hand side gives x = 0 with 0 iterations. Returns false if
   * aborted. Not converging is not an error: see GetConverged().
   */
  bool Solve(const DiffusionSystem& system, std::array<Eigen::VectorXd, NumberOfChannels>& x,
    bool warmStart = false);

  /**
   * Builds the three channels' diagonal preconditioners of `system` now and
   * keeps them for the Solves of the same value arrays (many right-hand
   * sides of one matrix, e.g. time steps: one pass over the matrix less per
   * Solve). A Solve on other value arrays (or after the values were
   * reallocated) builds its own, as without Prepare; Prepare again after
   * changing the values in place. Throws translucency::Error for a zero or
   * non-finite diagonal.
   */
  void Prepare(const DiffusionSystem& system);
  /// Bytes held by the prepared preconditioners (3 n after Prepare).
  std::size_t GetMemoryBytes() const;

  /// Statistics of the last Solve, per channel: iterations done, the final
  /// relative residual ||b - Mx|| / ||b|| (as updated by the CG recurrence;
  /// 0 for a zero right-hand side) and whether it reached GetRelTol().
  int GetNumIterations(int c) const { return Iterations_[c]; }
  double GetFinalNorm(int c) const { return FinalNorm_[c]; }
  bool GetConverged(int c) const { return Converged_[c]; }

private:
  struct Prepared;
  std::unique_ptr<Prepared> Prepared_;
  double RelTol_ = 1e-6;
  int MaxIter_ = 2000;
  int MinIter_ = 0;
  std::function<bool(double)> Progress_;
  std::array<int, NumberOfChannels> Iterations_{};
  std::array<double, NumberOfChannels> FinalNorm_{};
  std::array<bool, NumberOfChannels> Converged_{};
};

} // namespace translucency
