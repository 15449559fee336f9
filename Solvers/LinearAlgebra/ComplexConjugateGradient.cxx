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

namespace
{
constexpr int NC = 3;
using Triple = std::array<double, NC>;

/// The three channels' A_c + i B entries of one nonzero, interleaved.
struct ChannelMatrix
{
  int N = 0;
  const int* RowOffsets = nullptr;
  const int* Columns = nullptr;
  std::vector<double> Real; ///< 3 per nonzero
  const double* Imag = nullptr;

  /// q = (A + i B) p for the three channels; returns p^T q per channel
  /// (the bilinear form, unconjugated) as real and imaginary parts.
  void Multiply(const double* pr, const double* pi, double* qr, double* qi, Triple& dotRe,
    Triple& dotIm) const
  {
    double re0 = 0, re1 = 0, re2 = 0, im0 = 0, im1 = 0, im2 = 0;
#pragma omp parallel for schedule(static) reduction(+ : re0, re1, re2, im0, im1, im2)
    for (int i = 0; i < N; ++i)
    {
      double sr[NC] = { 0, 0, 0 }, si[NC] = { 0, 0, 0 };
      for (int k = RowOffsets[i]; k < RowOffsets[i + 1]; ++k)
      {
        const std::size_t j = 3 * static_cast<std::size_t>(Columns[k]);
        const double* a = &Real[3 * static_cast<std::size_t>(k)];
        const double b = Imag[k];
        for (int c = 0; c < NC; ++c)
        {
          sr[c] += a[c] * pr[j + c] - b * pi[j + c];
          si[c] += a[c] * pi[j + c] + b * pr[j + c];
        }
      }
      const std::size_t o = 3 * static_cast<std::size_t>(i);
      for (int c = 0; c < NC; ++c)
      {
        qr[o + c] = sr[c];
        qi[o + c] = si[c];
      }
      re0 += pr[o] * sr[0] - pi[o] * si[0];
      im0 += pr[o] * si[0] + pi[o] * sr[0];
      re1 += pr[o + 1] * sr[1] - pi[o + 1] * si[1];
      im1 += pr[o + 1] * si[1] + pi[o + 1] * sr[1];
      re2 += pr[o + 2] * sr[2] - pi[o + 2] * si[2];
      im2 += pr[o + 2] * si[2] + pi[o + 2] * sr[2];
    }
    dotRe = { re0, re1, re2 };
    dotIm = { im0, im1, im2 };
  }
};

/// Per channel: sum over the vertices of |v_r|^2 + |v_i|^2.
Triple SquaredNorms(int n, const double* vr, const double* vi)
{
  double s0 = 0, s1 = 0, s2 = 0;
#pragma omp parallel for schedule(static) reduction(+ : s0, s1, s2)
  for (int i = 0; i < n; ++i)
  {
    const std::size_t o = 3 * static_cast<std::size_t>(i);
    s0 += vr[o] * vr[o] + vi[o] * vi[o];
    s1 += vr[o + 1] * vr[o + 1] + vi[o + 1] * vi[o + 1];
    s2 += vr[o + 2] * vr[o + 2] + vi[o + 2] * vi[o + 2];
  }
  return { s0, s1, s2 };
}
} // namespace

bool SolveComplexSymmetricCOCGChannels(int n, const int* rowOffsets, const int* columns,
  const std::array<const double*, 3>& realValues, const double* imagValues,
  const Eigen::VectorXd& bReal, const Eigen::VectorXd& bImag, Eigen::VectorXd& xReal,
  Eigen::VectorXd& xImag, double relTol, int maxIter, std::array<LinearSolveStats, 3>& stats,
  const InterleavedPreconditioner& precondition, const std::function<bool(int)>& progress)
{
  using Complex = std::complex<double>;
  const Eigen::Index size = 3 * static_cast<Eigen::Index>(std::max(n, 0));
  if (n < 0 || bReal.size() != size || bImag.size() != size)
  {
    throw Error("COCG: the right-hand side does not match the matrix");
  }
  stats = {};
  ChannelMatrix matrix;
  matrix.N = n;
  matrix.RowOffsets = rowOffsets;
  matrix.Columns = columns;
  matrix.Imag = imagValues;
  const int nnz = n > 0 ? rowOffsets[n] : 0;
  matrix.Real.resize(3 * static_cast<std::size_t>(nnz));
#pragma omp parallel for schedule(static)
  for (int k = 0; k < nnz; ++k)
  {
    for (int c = 0; c < NC; ++c)
    {
      matrix.Real[3 * static_cast<std::size_t>(k) + c] = realValues[c][k];
    }
  }
  if (xReal.size() != size || xImag.size() != size)
  {
    xReal.setZero(size);
    xImag.setZero(size);
  }
  Eigen::VectorXd rr(size), ri(size), zr, zi, pr(size), pi(size), qr(size), qi(size);
  Triple dotRe, dotIm;
  // r = b - (A + i B) x.
  matrix.Multiply(xReal.data(), xImag.data(), qr.data(), qi.data(), dotRe, dotIm);
  rr = bReal - qr;
  ri = bImag - qi;
  const Triple bNorm2 = SquaredNorms(n, bReal.data(), bImag.data());
  Triple residual2 = SquaredNorms(n, rr.data(), ri.data());
  std::array<double, NC> bNorm{}, residual{};
  std::array<bool, NC> active{};
  for (int c = 0; c < NC; ++c)
  {
    bNorm[c] = std::sqrt(bNorm2[c]);
    if (bNorm[c] == 0.0)
    {
      for (int i = 0; i < n; ++i)
      {
        xReal[3 * i + c] = xImag[3 * i + c] = 0.0;
      }
      stats[c].Converged = true;
      continue;
    }
    residual[c] = std::sqrt(residual2[c]) / bNorm[c];
    active[c] = residual[c] > relTol;
  }
  std::array<Complex, NC> rho{};
  // z = M r; rho = r^T z; p = z (channels not active: p = 0).
  const auto preconditionAndDot = [&](std::array<Complex, NC>& out) {
    precondition(rr, zr);
    precondition(ri, zi);
    double re0 = 0, re1 = 0, re2 = 0, im0 = 0, im1 = 0, im2 = 0;
#pragma omp parallel for schedule(static) reduction(+ : re0, re1, re2, im0, im1, im2)
    for (int i = 0; i < n; ++i)
    {
      const std::size_t o = 3 * static_cast<std::size_t>(i);
      re0 += rr[o] * zr[o] - ri[o] * zi[o];
      im0 += rr[o] * zi[o] + ri[o] * zr[o];
      re1 += rr[o + 1] * zr[o + 1] - ri[o + 1] * zi[o + 1];
      im1 += rr[o + 1] * zi[o + 1] + ri[o + 1] * zr[o + 1];
      re2 += rr[o + 2] * zr[o + 2] - ri[o + 2] * zi[o + 2];
      im2 += rr[o + 2] * zi[o + 2] + ri[o + 2] * zr[o + 2];
    }
    out = { Complex(re0, im0), Complex(re1, im1), Complex(re2, im2) };
  };
  preconditionAndDot(rho);
  pr.setZero();
  pi.setZero();
  {
    std::array<double, NC> keep{};
    for (int c = 0; c < NC; ++c)
    {
      keep[c] = active[c] ? 1.0 : 0.0;
    }
#pragma omp parallel for schedule(static)
    for (int i = 0; i < n; ++i)
    {
      for (int c = 0; c < NC; ++c)
      {
        const std::size_t o = 3 * static_cast<std::size_t>(i) + c;
        pr[o] = keep[c] * zr[o];
        pi[o] = keep[c] * zi[o];
      }
    }
  }
  int iteration = 0;
  while ((active[0] || active[1] || active[2]) && iteration < maxIter)
  {
    if (progress && !progress(iteration))
    {
      for (int c = 0; c < NC; ++c)
      {
        stats[c].RelativeResidual = residual[c];
      }
      return false;
    }
    ++iteration;
    matrix.Multiply(pr.data(), pi.data(), qr.data(), qi.data(), dotRe, dotIm);
    std::array<double, NC> alphaRe{}, alphaIm{};
    for (int c = 0; c < NC; ++c)
    {
      if (!active[c])
      {
        continue;
      }
      const Complex pq(dotRe[c], dotIm[c]);
      if (std::abs(pq) == 0.0 || !std::isfinite(std::abs(pq)))
      {
        active[c] = false; // breakdown: this channel stops, not converged
        continue;
      }
      const Complex alpha = rho[c] / pq;
      alphaRe[c] = alpha.real();
      alphaIm[c] = alpha.imag();
      stats[c].Iterations = iteration;
    }
    // x += alpha p, r -= alpha q (alpha = 0 for the channels not active).
    double s0 = 0, s1 = 0, s2 = 0;
#pragma omp parallel for schedule(static) reduction(+ : s0, s1, s2)
    for (int i = 0; i < n; ++i)
    {
      double sums[NC];
      for (int c = 0; c < NC; ++c)
      {
        const std::size_t o = 3 * static_cast<std::size_t>(i) + c;
        const double ar = alphaRe[c], ai = alphaIm[c];
        xReal[o] += ar * pr[o] - ai * pi[o];
        xImag[o] += ar * pi[o] + ai * pr[o];
        rr[o] -= ar * qr[o] - ai * qi[o];
        ri[o] -= ar * qi[o] + ai * qr[o];
        sums[c] = rr[o] * rr[o] + ri[o] * ri[o];
      }
      s0 += sums[0];
      s1 += sums[1];
      s2 += sums[2];
    }
    const Triple norms = { s0, s1, s2 };
    for (int c = 0; c < NC; ++c)
    {
      if (active[c])
      {
        residual[c] = std::sqrt(norms[c]) / bNorm[c];
        if (residual[c] <= relTol)
        {
          active[c] = false;
        }
      }
    }
    if (!(active[0] || active[1] || active[2]))
    {
      break;
    }
    std::array<Complex, NC> rhoNext;
    preconditionAndDot(rhoNext);
    std::array<double, NC> betaRe{}, betaIm{}, keep{};
    for (int c = 0; c < NC; ++c)
    {
      if (active[c] && std::abs(rho[c]) == 0.0)
      {
        active[c] = false;
      }
      if (!active[c])
      {
        continue;
      }
      const Complex beta = rhoNext[c] / rho[c];
      betaRe[c] = beta.real();
      betaIm[c] = beta.imag();
      keep[c] = 1.0;
      rho[c] = rhoNext[c];
    }
    // p = z + beta p (channels not active: p = 0).
#pragma omp parallel for schedule(static)
    for (int i = 0; i < n; ++i)
    {
      for (int c = 0; c < NC; ++c)
      {
        const std::size_t o = 3 * static_cast<std::size_t>(i) + c;
        const double br = betaRe[c], bi = betaIm[c];
        const double nr = zr[o] + br * pr[o] - bi * pi[o];
        const double ni = zi[o] + br * pi[o] + bi * pr[o];
        pr[o] = keep[c] * nr;
        pi[o] = keep[c] * ni;
      }
    }
  }
  // The true residual (the recurrence's may drift).
  matrix.Multiply(xReal.data(), xImag.data(), qr.data(), qi.data(), dotRe, dotIm);
  rr = bReal - qr;
  ri = bImag - qi;
  residual2 = SquaredNorms(n, rr.data(), ri.data());
  for (int c = 0; c < NC; ++c)
  {
    if (bNorm[c] == 0.0)
    {
      continue;
    }
    const double trueResidual = std::sqrt(residual2[c]) / bNorm[c];
    stats[c].RelativeResidual = trueResidual;
    stats[c].Converged =
      std::isfinite(trueResidual) && trueResidual <= relTol * 1.000001 + 1e-15;
    stats[c].SpMVEquivalents = stats[c].Iterations + 2;
  }
  return true;
}

} // namespace translucency
