#include "Relaxation.h"

#include "BlockSums.h"

#include <omp.h>

#include <cmath>

namespace translucency
{

namespace
{
/// Progress is reported every this many sweeps.
constexpr int ProgressInterval = 64;
} // namespace

bool RelaxationSolver::Iterate(const DiffusionSystem& system,
  int c,
  Eigen::VectorXd& x,
  double bNorm,
  LinearSolveStats& stats,
  const std::function<bool(int)>& progress)
{
  const int threads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();
  return Colours_ ? GaussSeidel(system, c, x, bNorm, stats, progress, threads)
                  : Jacobi(system, c, x, bNorm, stats, progress, threads);
}

bool RelaxationSolver::Jacobi(const DiffusionSystem& system,
  int c,
  Eigen::VectorXd& x,
  double bNorm,
  LinearSolveStats& stats,
  const std::function<bool(int)>& progress,
  int threads) const
{
  // Rows in fixed blocks: the residual sum has the same order for any
  // number of threads.
  constexpr int Block = 2048;
  const int n = system.NumberOfUnknowns;
  const int* rows = system.RowOffsets.data();
  const int* cols = system.ColumnIndices.data();
  const double* values = system.Values[c].data();
  const Eigen::VectorXd& b = system.RightHandSide[c];
  Eigen::VectorXd inverseDiagonal(n);
  for (int i = 0; i < n; ++i)
  {
    for (int k = rows[i]; k < rows[i + 1]; ++k)
    {
      if (cols[k] == i)
      {
        inverseDiagonal[i] = 1.0 / values[k];
      }
    }
  }
  Eigen::VectorXd next(n);
  int iterations = 0;
  while (true)
  {
    const double r2 = blocksums::BlockLoop<1, Block>(n, threads,
      [&](int begin, int end)
      {
        double sum = 0.0;
        for (int i = begin; i < end; ++i)
        {
          double r = b[i];
          for (int k = rows[i]; k < rows[i + 1]; ++k)
          {
            r -= values[k] * x[cols[k]];
          }
          next[i] = x[i] + inverseDiagonal[i] * r;
          sum += r * r;
        }
        return std::array<double, 1>{ sum };
      })[0];
    stats.RelativeResidual = std::sqrt(r2) / bNorm; // of x, before the update
    stats.Converged = stats.RelativeResidual <= RelTol_;
    stats.Iterations = iterations;
    stats.SpMVEquivalents = iterations + 1.0;
    if (stats.Converged || iterations >= MaxIter_ || !std::isfinite(stats.RelativeResidual))
    {
      return true;
    }
    x.swap(next);
    ++iterations;
    if (iterations % ProgressInterval == 0 && !progress(iterations))
    {
      stats.Iterations = iterations;
      return false;
    }
  }
}

bool RelaxationSolver::GaussSeidel(const DiffusionSystem& system,
  int c,
  Eigen::VectorXd& x,
  double bNorm,
  LinearSolveStats& stats,
  const std::function<bool(int)>& progress,
  int threads) const
{
  constexpr int Block = 4096;
  const int n = system.NumberOfUnknowns;
  const int* offsets = system.RowOffsets.data();
  const int* columns = system.ColumnIndices.data();
  const double* values = system.Values[c].data();
  const double* rhs = system.RightHandSide[c].data();
  double* xv = x.data();
  // ||b - M x|| with a summation order independent of the thread count.
  const auto residualNorm = [&]()
  {
    return std::sqrt(blocksums::BlockedSum<Block>(n, threads,
      [&](int i)
      {
        double r = rhs[i];
        for (int k = offsets[i]; k < offsets[i + 1]; ++k)
        {
          r -= values[k] * xv[columns[k]];
        }
        return r * r;
      }));
  };
  double res = residualNorm() / bNorm;
  int it = 0;
  bool aborted = false;
  while (res > RelTol_ && it < MaxIter_)
  {
    for (int k = 0; k < NumberOfColours_; ++k)
    {
      const std::vector<int>& colour = Colours_[k];
      const int* ids = colour.data();
      const int count = static_cast<int>(colour.size());
#pragma omp parallel for schedule(static) num_threads(threads)
      for (int m = 0; m < count; ++m)
      {
        const int i = ids[m];
        double sum = rhs[i], diagonal = 1.0;
        for (int e = offsets[i]; e < offsets[i + 1]; ++e)
        {
          if (columns[e] == i)
          {
            diagonal = values[e];
          }
          else
          {
            sum -= values[e] * xv[columns[e]];
          }
        }
        xv[i] = sum / diagonal;
      }
    }
    ++it;
    res = residualNorm() / bNorm;
    if (it % ProgressInterval == 0 && !progress(it))
    {
      aborted = true;
      break;
    }
  }
  stats.Iterations = it;
  stats.RelativeResidual = res;
  stats.Converged = res <= RelTol_;
  stats.SpMVEquivalents = 2.0 * it + 1.0;
  return !aborted;
}

} // namespace translucency
