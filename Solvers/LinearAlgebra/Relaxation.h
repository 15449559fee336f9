/**
 * @file Relaxation.h
 * @brief "relaxation": the papers' relaxation sweeps for the non-symmetric
 * systems of the QuadGraph and grid discretisations.
 */
#pragma once

#include "LinearSolver.h"

#include <vector>

namespace translucency
{

/**
 * Without colours (QuadGraph): Jacobi sweeps x <- x + D^-1 (b - M x), which
 * are QuadGraph, eq. 8 for inner rows and eq. 9 for surface rows; the
 * residual of each sweep is that of x before the update (blocks of 2048
 * rows). With colours (grid, SetColours): multicolour Gauss-Seidel, the
 * update of Polygrid, Sec. 5.2, phi_i <- (b_i - sum_j m_ij phi_j) / m_ii on
 * each colour in turn (rows of one colour must not couple); the residual is
 * computed after each sweep (blocks of 4096 rows). Both need O(n^2) sweeps
 * for n unknowns across. Results do not depend on the number of threads.
 */
class RelaxationSolver : public ChannelLinearSolver
{
public:
  std::string GetName() const override { return "relaxation"; }

  /// The rows of each of `count` colours, swept in this order; null
  /// (default) = Jacobi. The array must live while Solve runs.
  void SetColours(const std::vector<int>* colours, int count)
  {
    Colours_ = colours;
    NumberOfColours_ = colours ? count : 0;
  }

protected:
  bool Iterate(const DiffusionSystem& system, int c, Eigen::VectorXd& x, double bNorm,
    LinearSolveStats& stats, const std::function<bool(int)>& progress) override;

private:
  bool Jacobi(const DiffusionSystem& system, int c, Eigen::VectorXd& x, double bNorm,
    LinearSolveStats& stats, const std::function<bool(int)>& progress, int threads) const;
  bool GaussSeidel(const DiffusionSystem& system, int c, Eigen::VectorXd& x, double bNorm,
    LinearSolveStats& stats, const std::function<bool(int)>& progress, int threads) const;

  const std::vector<int>* Colours_ = nullptr;
  int NumberOfColours_ = 0;
};

} // namespace translucency
