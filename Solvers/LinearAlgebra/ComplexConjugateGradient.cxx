#include "ComplexConjugateGradient.h"

#include "Error.h"

#include <Eigen/Sparse>

#include <cmath>
#include <vector>

namespace translucency
{

bool SolveComplexSymmetricCOCG(int n, const int* rowOffsets, const int* columns,
  const double* realValues, const double* imagValues, const Eigen::VectorXcd& b,
  Eigen::VectorXcd& x, double relTol, int maxIter, LinearSolveStats& stats,
  const std::function<bool(int)>& progress)
{
  using Complex = std::complex<double>;
  stats = LinearSolveStats();
  if (n < 0 || b.size() != n)
  {
    throw Error("COCG: the right-hand side does not match the matrix");
  }
  const int nnz = rowOffsets[n];
  std::vector<Complex> values(static_cast<std::size_t>(nnz));
  Eigen::VectorXcd inverseDiagonal = Eigen::VectorXcd::Zero(n);
  for (int i = 0; i < n; ++i)
  {
    for (int k = rowOffsets[i]; k < rowOffsets[i + 1]; ++k)
    {
      values[k] = Complex(realValues[k], imagValues[k]);
      if (columns[k] == i)
      {
        inverseDiagonal[i] = values[k];
      }
    }
  }
  for (int i = 0; i < n; ++i)
  {
    if (inverseDiagonal[i] == Complex(0.0, 0.0))
    {
      return true; // no Jacobi preconditioner: not converged (stats say so)
    }
    inverseDiagonal[i] = 1.0 / inverseDiagonal[i];
  }
  const Eigen::Map<const Eigen::SparseMatrix<Complex, Eigen::RowMajor, int>> matrix(
    n, n, nnz, rowOffsets, columns, values.data());
  // x^T y without conjugation: the bilinear form of COCG.
  const auto dot = [](const Eigen::VectorXcd& u, const Eigen::VectorXcd& v) {
    return (u.array() * v.array()).sum();
  };

  if (x.size() != n)
  {
    x.setZero(n);
  }
  const double bNorm = b.norm();
  if (bNorm == 0.0)
  {
    x.setZero(n);
    stats.Converged = true;
    return true;
  }
  Eigen::VectorXcd r = b - matrix * x;
  Eigen::VectorXcd z = inverseDiagonal.cwiseProduct(r);
  Eigen::VectorXcd p = z;
  Eigen::VectorXcd q(n);
  Complex rho = dot(r, z);
  double residual = r.norm() / bNorm;
  int iteration = 0;
  while (residual > relTol && iteration < maxIter)
  {
    if (progress && !progress(iteration))
    {
      stats.Iterations = iteration;
      stats.RelativeResidual = residual;
      return false;
    }
    q.noalias() = matrix * p;
    const Complex pq = dot(p, q);
    if (std::abs(pq) == 0.0 || !std::isfinite(std::abs(pq)))
    {
      break; // breakdown
    }
    const Complex alpha = rho / pq;
    x += alpha * p;
    r -= alpha * q;
    ++iteration;
    residual = r.norm() / bNorm;
    z = inverseDiagonal.cwiseProduct(r);
    const Complex rhoNext = dot(r, z);
    if (std::abs(rho) == 0.0)
    {
      break;
    }
    p = z + (rhoNext / rho) * p;
    rho = rhoNext;
  }
  // The true residual (the recurrence's may drift).
  residual = (b - matrix * x).norm() / bNorm;
  stats.Iterations = iteration;
  stats.RelativeResidual = residual;
  stats.Converged = std::isfinite(residual) && residual <= relTol * 1.000001 + 1e-15;
  stats.SpMVEquivalents = iteration + 2;
  return true;
}

} // namespace translucency
