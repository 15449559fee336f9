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
#include <vector>

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

/**
 * Preconditioned COCG on the three channels of a DiffusionSystem together:
 * (A_c + i B_c) x_c = b_c, A_c = system.Values[c] (the real SPD matrix),
 * B_c = imagValues[c] on the same pattern (zeros allowed: they are dropped),
 * b_c = system.RightHandSide[c] + i imagRightHandSide[c] (real when
 * imagRightHandSide is null: sources modulated with phase 0; the extended
 * collimated beam's delayed source is complex).
 * precondition(r, z) computes z = P r on 3 n interleaved real values (channel
 * c of unknown i at 3 i + c) with P a fixed real symmetric positive definite
 * operator, e.g. the multigrid cycle of A (LinearSolver::ApplyPreconditioner);
 * it is applied to the real and the imaginary part of the residual
 * separately, so P (A + i B) stays complex symmetric in the P-bilinear form
 * and COCG's short recurrence holds. Each channel has its own scalars and
 * stops when its ||b - (A + i B) x|| <= relTol ||b|| (the recurrence's
 * residual; the true one is computed at the end for the statistics) or after
 * maxIter iterations; b_c = 0 gives x_c = 0. Starts from x = 0. `progress`
 * receives the iteration count and returns false to abort (the function
 * then returns false). A breakdown (p^T (A + i B) p = 0 or not finite)
 * stops that channel, not converged. The dot products are summed in a fixed
 * chunk order: the result does not depend on the number of threads.
 * SpMVEquivalents counts the complex products in units of a real product
 * with A (a complex product is 2 plus B's share; the preconditioner's work
 * is not counted).
 */
bool SolveComplexSymmetricBlockedCOCG(const DiffusionSystem& system,
  const std::array<std::vector<double>, NumberOfChannels>& imagValues,
  const std::function<void(const double*, double*)>& precondition,
  std::array<Eigen::VectorXcd, NumberOfChannels>& x, double relTol, int maxIter,
  std::array<LinearSolveStats, NumberOfChannels>& stats,
  const std::function<bool(int)>& progress = {},
  const std::array<Eigen::VectorXd, NumberOfChannels>* imagRightHandSide = nullptr);

} // namespace translucency
