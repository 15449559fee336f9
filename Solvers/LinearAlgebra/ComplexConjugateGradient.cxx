#include "ComplexConjugateGradient.h"

#include "BlockedKernels.h"
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

namespace translucency
{

namespace
{

using blocked::ChunkedSums;
using blocked::NC;

/// B compressed to its non-zero entries (any channel), 3 values per entry.
struct CompressedImaginary
{
  std::vector<int> Offsets, Columns;
  std::vector<double> Values;
};

CompressedImaginary Compress(const DiffusionSystem& system,
  const std::array<std::vector<double>, NumberOfChannels>& imag)
{
  const int n = system.NumberOfUnknowns;
  CompressedImaginary b;
  b.Offsets.assign(static_cast<std::size_t>(n) + 1, 0);
  for (int i = 0; i < n; ++i)
  {
    for (int k = system.RowOffsets[i]; k < system.RowOffsets[i + 1]; ++k)
    {
      if (imag[0][k] != 0.0 || imag[1][k] != 0.0 || imag[2][k] != 0.0)
      {
        b.Columns.push_back(system.ColumnIndices[k]);
        for (int c = 0; c < NC; ++c)
        {
          b.Values.push_back(imag[c][k]);
        }
      }
    }
    b.Offsets[i + 1] = static_cast<int>(b.Columns.size());
  }
  return b;
}

/**
 * The state of one blocked COCG solve: interleaved work vectors, real and
 * imaginary parts apart (the preconditioner takes each part as one real
 * interleaved vector), the active channels and the kernels of A + i B.
 */
struct BlockedCOCG
{
  BlockedCOCG(const DiffusionSystem& system,
    const std::array<std::vector<double>, NumberOfChannels>& imagValues)
    : System(system)
    , Imag(Compress(system, imagValues))
    , n(system.NumberOfUnknowns)
    , xr(3 * static_cast<long long>(n), 0.0)
    , xi(3 * static_cast<long long>(n), 0.0)
    , rr(3 * static_cast<long long>(n))
    , ri(3 * static_cast<long long>(n), 0.0)
    , zr(3 * static_cast<long long>(n))
    , zi(3 * static_cast<long long>(n))
    , pr(3 * static_cast<long long>(n))
    , pi(3 * static_cast<long long>(n))
    , qr(3 * static_cast<long long>(n))
    , qi(3 * static_cast<long long>(n))
  {
  }

  /// r = b (real and imaginary parts) and ||b|| per channel; a channel with
  /// b = 0 is inactive and converged.
  void LoadRightHandSides(const std::array<Eigen::VectorXd, NumberOfChannels>* imagRightHandSide,
    std::array<LinearSolveStats, NumberOfChannels>& stats)
  {
    for (int c = 0; c < NC; ++c)
    {
      stats[c] = LinearSolveStats();
      const Eigen::VectorXd& b = System.RightHandSide[c];
      for (int i = 0; i < n; ++i)
      {
        rr[3 * static_cast<std::size_t>(i) + c] = b[i];
      }
      normB[c] = b.norm();
      if (imagRightHandSide)
      {
        const Eigen::VectorXd& bi = (*imagRightHandSide)[c];
        for (int i = 0; i < n; ++i)
        {
          ri[3 * static_cast<std::size_t>(i) + c] = bi[i];
        }
        normB[c] = std::hypot(normB[c], bi.norm());
      }
      active[c] = normB[c] > 0.0;
      stats[c].Converged = !active[c];
    }
  }

  /// Row i of (A + i B) v into (outR, outI)[3 i ...].
  void Row(const double* vr, const double* vi, long long i, double* outR, double* outI) const
  {
    const int* ro = System.RowOffsets.data();
    const int* ci = System.ColumnIndices.data();
    const double* a[NC] = { System.Values[0].data(), System.Values[1].data(),
      System.Values[2].data() };
    const int* bo = Imag.Offsets.data();
    const int* bc = Imag.Columns.data();
    const double* bv = Imag.Values.data();
    double sr[NC] = { 0.0, 0.0, 0.0 }, si[NC] = { 0.0, 0.0, 0.0 };
    for (int k = ro[i]; k < ro[i + 1]; ++k)
    {
      const std::size_t j = 3 * static_cast<std::size_t>(ci[k]);
      for (int c = 0; c < NC; ++c)
      {
        sr[c] += a[c][k] * vr[j + c];
        si[c] += a[c][k] * vi[j + c];
      }
    }
    for (int k = bo[i]; k < bo[i + 1]; ++k)
    {
      const std::size_t j = 3 * static_cast<std::size_t>(bc[k]);
      const double* b = bv + 3 * static_cast<std::size_t>(k);
      for (int c = 0; c < NC; ++c)
      {
        sr[c] -= b[c] * vi[j + c];
        si[c] += b[c] * vr[j + c];
      }
    }
    for (int c = 0; c < NC; ++c)
    {
      outR[c] = sr[c];
      outI[c] = si[c];
    }
  }

  /// r^T z (unconjugated) per channel.
  std::array<std::complex<double>, NC> RhoOfResidual() const
  {
    const auto s = ChunkedSums<6>(n, [&](long long begin, long long end, double* sums) {
      for (long long k = 3 * begin; k < 3 * end; ++k)
      {
        sums[k % 3] += rr[k] * zr[k] - ri[k] * zi[k];
        sums[3 + k % 3] += rr[k] * zi[k] + ri[k] * zr[k];
      }
    });
    std::array<std::complex<double>, NC> out;
    for (int c = 0; c < NC; ++c)
    {
      out[c] = std::complex<double>(s[c], s[3 + c]);
    }
    return out;
  }

  /// q = (A + i B) p; returns p^T q per channel (sums 0-2 real, 3-5
  /// imaginary parts).
  auto ApplyToDirection()
  {
    return ChunkedSums<6>(n, [&](long long begin, long long end, double* sums) {
      for (long long i = begin; i < end; ++i)
      {
        Row(pr.data(), pi.data(), i, qr.data() + 3 * i, qi.data() + 3 * i);
        for (int c = 0; c < NC; ++c)
        {
          const long long k = 3 * i + c;
          sums[c] += pr[k] * qr[k] - pi[k] * qi[k];
          sums[3 + c] += pr[k] * qi[k] + pi[k] * qr[k];
        }
      }
    });
  }

  /// x += alpha p, r -= alpha q; returns ||r||^2 per channel.
  auto UpdateSolution(const std::array<std::complex<double>, NC>& alpha)
  {
    return ChunkedSums<3>(n, [&](long long begin, long long end, double* sums) {
      for (long long i = begin; i < end; ++i)
      {
        for (int c = 0; c < NC; ++c)
        {
          const long long k = 3 * i + c;
          const double ar = alpha[c].real(), ai = alpha[c].imag();
          xr[k] += ar * pr[k] - ai * pi[k];
          xi[k] += ar * pi[k] + ai * pr[k];
          rr[k] -= ar * qr[k] - ai * qi[k];
          ri[k] -= ar * qi[k] + ai * qr[k];
          sums[c] += rr[k] * rr[k] + ri[k] * ri[k];
        }
      }
    });
  }

  /// p = z + beta p on the active channels.
  void UpdateDirection(const std::array<std::complex<double>, NC>& beta)
  {
#pragma omp parallel for schedule(static) if(n > blocked::ParallelThreshold)
    for (long long i = 0; i < n; ++i)
    {
      for (int c = 0; c < NC; ++c)
      {
        if (!active[c])
        {
          continue;
        }
        const long long k = 3 * i + c;
        const double br = beta[c].real(), bi = beta[c].imag();
        const double p0 = pr[k], p1 = pi[k];
        pr[k] = zr[k] + br * p0 - bi * p1;
        pi[k] = zi[k] + br * p1 + bi * p0;
      }
    }
  }

  /// ||b - (A + i B) x||^2 per channel: the true residuals (the
  /// recurrence's may drift).
  auto TrueResidualSums(const std::array<Eigen::VectorXd, NumberOfChannels>* imagRightHandSide) const
  {
    return ChunkedSums<3>(n, [&](long long begin, long long end, double* sums) {
      for (long long i = begin; i < end; ++i)
      {
        double axr[NC], axi[NC];
        Row(xr.data(), xi.data(), i, axr, axi);
        for (int c = 0; c < NC; ++c)
        {
          const double er = System.RightHandSide[c][i] - axr[c],
                       ei = (imagRightHandSide ? (*imagRightHandSide)[c][i] : 0.0) - axi[c];
          sums[c] += er * er + ei * ei;
        }
      }
    });
  }

  bool AnyActive() const { return active[0] || active[1] || active[2]; }

  const DiffusionSystem& System;
  const CompressedImaginary Imag;
  const int n;
  std::vector<double> xr, xi, rr, ri, zr, zi, pr, pi, qr, qi;
  std::array<double, NC> normB{};
  std::array<bool, NC> active{};
};

} // namespace

bool SolveComplexSymmetricBlockedCOCG(const DiffusionSystem& system,
  const std::array<std::vector<double>, NumberOfChannels>& imagValues,
  const std::function<void(const double*, double*)>& precondition,
  std::array<Eigen::VectorXcd, NumberOfChannels>& x, double relTol, int maxIter,
  std::array<LinearSolveStats, NumberOfChannels>& stats, const std::function<bool(int)>& progress,
  const std::array<Eigen::VectorXd, NumberOfChannels>* imagRightHandSide)
{
  const int n = system.NumberOfUnknowns;
  const std::size_t nnz = system.ColumnIndices.size();
  bool ok = n >= 0 && system.RowOffsets.size() == static_cast<std::size_t>(n) + 1 &&
    static_cast<std::size_t>(system.RowOffsets.back()) == nnz;
  for (int c = 0; c < NC && ok; ++c)
  {
    ok = system.Values[c].size() == nnz && imagValues[c].size() == nnz &&
      system.RightHandSide[c].size() == n &&
      (!imagRightHandSide || (*imagRightHandSide)[c].size() == n);
  }
  if (!ok)
  {
    throw Error("COCG: the imaginary values or the right-hand sides do not match the system");
  }
  BlockedCOCG s(system, imagValues);
  s.LoadRightHandSides(imagRightHandSide, stats);
  std::array<bool, NC>& active = s.active;
  const double imagShare = static_cast<double>(s.Imag.Columns.size()) / std::max<double>(1.0, nnz);
  std::array<std::complex<double>, NC> rho{};
  if (s.AnyActive())
  {
    precondition(s.rr.data(), s.zr.data());
    precondition(s.ri.data(), s.zi.data());
    s.pr = s.zr;
    s.pi = s.zi;
    rho = s.RhoOfResidual();
  }
  int iteration = 0;
  for (; iteration < maxIter && s.AnyActive(); ++iteration)
  {
    if (progress && !progress(iteration))
    {
      return false;
    }
    // q = (A + i B) p with p^T q.
    const auto pqSums = s.ApplyToDirection();
    std::array<std::complex<double>, NC> alpha{};
    for (int c = 0; c < NC; ++c)
    {
      if (!active[c])
      {
        continue;
      }
      const std::complex<double> pq(pqSums[c], pqSums[3 + c]);
      if (std::abs(pq) == 0.0 || !std::isfinite(std::abs(pq)) || !std::isfinite(std::abs(rho[c])))
      {
        active[c] = false; // breakdown: not converged
        continue;
      }
      alpha[c] = rho[c] / pq;
      stats[c].Iterations = iteration + 1;
      stats[c].SpMVEquivalents += 2.0 + 2.0 * imagShare;
    }
    // x += alpha p, r -= alpha q, with ||r||^2.
    const auto rrSums = s.UpdateSolution(alpha);
    for (int c = 0; c < NC; ++c)
    {
      if (active[c])
      {
        stats[c].RelativeResidual = std::sqrt(rrSums[c]) / s.normB[c];
        if (stats[c].RelativeResidual <= relTol)
        {
          active[c] = false;
        }
      }
    }
    if (!s.AnyActive())
    {
      ++iteration;
      break;
    }
    precondition(s.rr.data(), s.zr.data());
    precondition(s.ri.data(), s.zi.data());
    const auto rhoNext = s.RhoOfResidual();
    std::array<std::complex<double>, NC> beta{};
    for (int c = 0; c < NC; ++c)
    {
      beta[c] = active[c] && std::abs(rho[c]) > 0.0 ? rhoNext[c] / rho[c] : 0.0;
      if (active[c] && std::abs(rho[c]) == 0.0)
      {
        active[c] = false; // breakdown
      }
    }
    // p = z + beta p on the active channels.
    s.UpdateDirection(beta);
    rho = rhoNext;
  }
  // The true residuals (the recurrence's may drift).
  const auto trueSums = s.TrueResidualSums(imagRightHandSide);
  for (int c = 0; c < NC; ++c)
  {
    x[c].resize(n);
    for (int i = 0; i < n; ++i)
    {
      const std::size_t k = 3 * static_cast<std::size_t>(i) + c;
      x[c][i] = std::complex<double>(s.xr[k], s.xi[k]);
    }
    if (s.normB[c] > 0.0)
    {
      const double residual = std::sqrt(trueSums[c]) / s.normB[c];
      stats[c].RelativeResidual = residual;
      stats[c].Converged = std::isfinite(residual) && residual <= relTol * 1.000001 + 1e-15;
      stats[c].SpMVEquivalents += 2.0 + 2.0 * imagShare;
    }
  }
  return true;
}

} // namespace translucency
