/**
 * @file ComplexConjugateGradient.h
 * @brief COCG (conjugate orthogonal conjugate gradient; van der Vorst and
 * Melissen 1990, IEEE Trans. Magn. 26(2) 706-708) with the Jacobi
 * preconditioner, for the complex-symmetric systems (A + i B) x = b of the
 * frequency-domain diffusion equation: A the real SPD diffusion matrix, B a
 * real symmetric positive semi-definite mass matrix times 2 pi f eta / c.
 *
 * COCG is CG with the unconjugated bilinear form x^T y in place of the inner
 * product: the same short recurrence, one matrix-vector product and two
 * vectors more than CG per iteration, no restart; for a matrix A + i B with
 * B small against A (the modulation term against absorption plus
 * stiffness) it converges like CG on A. Documentation/DiffuseOptics.md says
 * why it was chosen over the real 2 x 2 block form.
 */
#pragma once

#include "LinearSolver.h"

#include <Eigen/Core>

#include <array>

#include <complex>
#include <functional>

namespace translucency
{

/**
 * Solve (A + i B) x = b, with A and B on one CSR pattern (n x n,
 * rowOffsets n + 1 entries, columns sorted or not), from x (used as the
 * initial guess if it has n entries, else zero). Stops when
 * ||b - (A + i B) x|| <= relTol ||b|| (the true residual is checked at the
 * end) or after maxIter iterations; b = 0 gives x = 0. `progress`, if set,
 * receives the iteration count and returns false to abort (then the
 * function returns false). A zero diagonal entry or a breakdown
 * (p^T (A + i B) p = 0) stops the iterations, not converged.
 * The sparse products run on Eigen's OpenMP threads.
 */
bool SolveComplexSymmetricCOCG(int n, const int* rowOffsets, const int* columns,
  const double* realValues, const double* imagValues, const Eigen::VectorXcd& b,
  Eigen::VectorXcd& x, double relTol, int maxIter, LinearSolveStats& stats,
  const std::function<bool(int)>& progress = {});

/// z = B r for the three channels interleaved (3 n real values, vertex i's
/// channels at 3 i .. 3 i + 2): a real symmetric positive definite
/// preconditioner, e.g. one multigrid cycle
/// (AggregationMultigridSolver::ApplyPreconditioner).
using InterleavedPreconditioner =
  std::function<void(const Eigen::VectorXd& r, Eigen::VectorXd& z)>;

/**
 * COCG on the three channels at once, (A_c + i B) x_c = b_c on one CSR
 * pattern (A_c real per channel, B real and the same for the three
 * channels: the modulation term omega eta / c does not depend on the
 * wavelength), preconditioned by a real symmetric positive definite M
 * applied to the real and the imaginary parts of the residuals. A real
 * symmetric preconditioner keeps the preconditioned system complex
 * symmetric, so COCG's short recurrence holds. Vectors are interleaved:
 * real and imaginary parts in separate arrays of 3 n values (vertex i's
 * channels at 3 i .. 3 i + 2); x is the initial guess if both parts have
 * 3 n values, else zero. Each iteration is one fused, OpenMP-parallel
 * product of the three channels with their bilinear forms, two
 * applications of M (real parts, imaginary parts) and one fused update.
 * Per channel: stops when ||b_c - (A_c + i B) x_c|| <= relTol ||b_c|| (a
 * channel that has converged keeps its x), the true residual checked at
 * the end; b_c = 0 gives x_c = 0; a breakdown stops that channel, not
 * converged. `progress` as SolveComplexSymmetricCOCG.
 * stats[c].SpMVEquivalents counts complex products (the caller adds M's).
 */
bool SolveComplexSymmetricCOCGChannels(int n, const int* rowOffsets, const int* columns,
  const std::array<const double*, 3>& realValues, const double* imagValues,
  const Eigen::VectorXd& bReal, const Eigen::VectorXd& bImag, Eigen::VectorXd& xReal,
  Eigen::VectorXd& xImag, double relTol, int maxIter, std::array<LinearSolveStats, 3>& stats,
  const InterleavedPreconditioner& precondition, const std::function<bool(int)>& progress = {});

} // namespace translucency
