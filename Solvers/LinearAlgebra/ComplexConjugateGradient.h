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

} // namespace translucency
