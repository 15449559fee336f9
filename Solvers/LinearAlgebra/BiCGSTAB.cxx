#include "BiCGSTAB.h"

#include "BlockSums.h"

#include <omp.h>

#include <cmath>
#include <limits>
#include <vector>

namespace translucency
{

namespace
{
/// Rows per block of the deterministic sums.
constexpr int Block = 4096;

/// The vectors and fused kernels of one BiCGSTAB solve of channel c (van
/// der Vorst 1992, Jacobi on the right); every sum is a deterministic block
/// sum.
struct BiCGSTABKernels
{
  BiCGSTABKernels(const DiffusionSystem& system, int c, Eigen::VectorXd& x, int threadCount)
    : n(system.NumberOfUnknowns)
    , threads(threadCount)
    , offsets(system.RowOffsets.data())
    , columns(system.ColumnIndices.data())
    , values(system.Values[c].data())
    , b(system.RightHandSide[c].data())
    , xv(x.data())
    , inverseDiagonal(static_cast<size_t>(n))
    , r(n)
    , r0(n)
    , p(n)
    , v(n)
    , y(n)
    , z(n)
    , sv(n)
    , t(n)
  {
  }

  /// The Jacobi preconditioner (1 where the diagonal is 0); returns ||b||^2.
  double Prepare()
  {
    return blocksums::BlockLoop<1, Block>(n,
      threads,
      [&](int begin, int end)
      {
        double sum = 0.0;
        for (int i = begin; i < end; ++i)
        {
          double d = 0.0;
          for (int k = offsets[i]; k < offsets[i + 1]; ++k)
          {
            d = columns[k] == i ? values[k] : d;
          }
          inverseDiagonal[i] = d != 0.0 ? 1.0 / d : 1.0;
          sum += b[i] * b[i];
        }
        return std::array<double, 1>{ sum };
      })[0];
  }

  double Row(int i, const double* u) const
  {
    double sum = 0.0;
    for (int k = offsets[i]; k < offsets[i + 1]; ++k)
    {
      sum += values[k] * u[columns[k]];
    }
    return sum;
  }

  /// r = r0 = b - M x; returns ||r||^2.
  double Restart()
  {
    return blocksums::BlockLoop<1, Block>(n,
      threads,
      [&](int begin, int end)
      {
        double sum = 0.0;
        for (int i = begin; i < end; ++i)
        {
          r[i] = r0[i] = b[i] - Row(i, xv);
          sum += r[i] * r[i];
        }
        return std::array<double, 1>{ sum };
      })[0];
  }

  /// One iteration from (rho, rhoOld, alpha, w): x and r updated; returns
  /// ||r||^2 and the next r0 . r in rho (the old one in rhoOld).
  double Step(double& rho, double& rhoOld, double& alpha, double& w)
  {
    const double beta = (rho / rhoOld) * (alpha / w);
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int i = 0; i < n; ++i)
    {
      p[i] = r[i] + beta * (p[i] - w * v[i]);
      y[i] = inverseDiagonal[i] * p[i];
    }
    // v = M y and r0 . v.
    const double r0v = blocksums::BlockLoop<1, Block>(n,
      threads,
      [&](int begin, int end)
      {
        double sum = 0.0;
        for (int i = begin; i < end; ++i)
        {
          v[i] = Row(i, y.data());
          sum += r0[i] * v[i];
        }
        return std::array<double, 1>{ sum };
      })[0];
    alpha = rho / r0v;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int i = 0; i < n; ++i)
    {
      sv[i] = r[i] - alpha * v[i];
      z[i] = inverseDiagonal[i] * sv[i];
    }
    // t = M z, t . t and t . s.
    const auto tDots = blocksums::BlockLoop<2, Block>(n,
      threads,
      [&](int begin, int end)
      {
        std::array<double, 2> sum{};
        for (int i = begin; i < end; ++i)
        {
          t[i] = Row(i, z.data());
          sum[0] += t[i] * t[i];
          sum[1] += t[i] * sv[i];
        }
        return sum;
      });
    w = tDots[0] > 0.0 ? tDots[1] / tDots[0] : 0.0;
    // x += alpha y + w z, r = s - w t, ||r||^2 and the next r0 . r.
    const auto rDots = blocksums::BlockLoop<2, Block>(n,
      threads,
      [&](int begin, int end)
      {
        std::array<double, 2> sum{};
        for (int i = begin; i < end; ++i)
        {
          xv[i] += alpha * y[i] + w * z[i];
          r[i] = sv[i] - w * t[i];
          sum[0] += r[i] * r[i];
          sum[1] += r0[i] * r[i];
        }
        return sum;
      });
    rhoOld = rho;
    rho = rDots[1];
    return rDots[0];
  }

  const int n, threads;
  const int* offsets;
  const int* columns;
  const double* values;
  const double* b;
  double* xv;
  std::vector<double> inverseDiagonal;
  std::vector<double> r, r0, p, v, y, z, sv, t;
};

} // namespace

// The fused iteration GridSolver had (van der Vorst 1992, Jacobi on the
// right); ||b|| is recomputed as a block sum for the stopping test.
bool BiCGSTABSolver::Iterate(const DiffusionSystem& system,
  int c,
  Eigen::VectorXd& x,
  double,
  LinearSolveStats& stats,
  const std::function<bool(int)>& progress)
{
  const int n = system.NumberOfUnknowns;
  const int threads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();
  MemoryBytes_ = 9 * static_cast<std::size_t>(n) * sizeof(double);
  BiCGSTABKernels k(system, c, x, threads);
  const double bNorm2 = k.Prepare();
  const double tol = RelTol_;
  const int maxIter = MaxIter_;
  const double tol2 = tol * tol * bNorm2;
  const double eps2 =
    std::numeric_limits<double>::epsilon() * std::numeric_limits<double>::epsilon();
  int it = 0;
  int products = 1;
  bool aborted = false;
  double rNorm2 = k.Restart();
  while (rNorm2 > tol2 && it < maxIter && std::isfinite(rNorm2))
  {
    double r0Norm2 = rNorm2, rho = rNorm2, rhoOld = 1.0, alpha = 1.0, w = 1.0;
    std::fill(k.v.begin(), k.v.end(), 0.0);
    std::fill(k.p.begin(), k.p.end(), 0.0);
    while (rNorm2 > tol2 && it < maxIter)
    {
      if (std::abs(rho) < eps2 * r0Norm2)
      {
        rho = r0Norm2 = k.Restart(); // r0 . r underflowed: new shadow residual
        ++products;
      }
      rNorm2 = k.Step(rho, rhoOld, alpha, w);
      ++it;
      products += 2;
      if (!std::isfinite(rNorm2))
      {
        break;
      }
      if (it % ProgressInterval == 0 && !progress(it))
      {
        aborted = true;
        break;
      }
      if (RestartInterval_ > 0 && it % RestartInterval_ == 0)
      {
        break; // restart from the true residual with a new shadow residual
      }
    }
    if (aborted)
    {
      break;
    }
    // The recurrence residual drifts from the true one: check it, and go on
    // from the true residual if it is not small enough.
    rNorm2 = k.Restart();
    ++products;
  }
  stats.Iterations = it;
  stats.RelativeResidual = std::sqrt(rNorm2 / bNorm2);
  stats.Converged = stats.RelativeResidual <= RelTol_;
  stats.SpMVEquivalents = products;
  return !aborted;
}

} // namespace translucency
