#include "SolutionRecycler.h"

#include "BlockedKernels.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace translucency
{

void SolutionRecycler::SetCapacity(int k)
{
  Capacity_ = std::min(std::max(k, 0), MaxCapacity);
  Size_ = std::min(Size_, Capacity_);
  X_.resize(Double_ ? 0 : Capacity_);
  W_.resize(Double_ ? 0 : Capacity_);
  XD_.resize(Double_ ? Capacity_ : 0);
  WD_.resize(Double_ ? Capacity_ : 0);
}

void SolutionRecycler::SetDoublePrecision(bool on)
{
  if (on == Double_)
  {
    return;
  }
  Double_ = on;
  Size_ = 0;
  X_.clear();
  W_.clear();
  XD_.clear();
  WD_.clear();
  SetCapacity(Capacity_);
}

std::array<double, NumberOfChannels> SolutionRecycler::Project(int n,
  const std::array<const double*, NumberOfChannels>& b,
  const std::array<double*, NumberOfChannels>& x, double* r) const
{
  return Double_ ? ProjectWith(XD_, WD_, n, b, x, r) : ProjectWith(X_, W_, n, b, x, r);
}

template <typename T>
std::array<double, NumberOfChannels> SolutionRecycler::ProjectWith(
  const std::vector<std::vector<T>>& xs, const std::vector<std::vector<T>>& ws, int n,
  const std::array<const double*, NumberOfChannels>& b,
  const std::array<double*, NumberOfChannels>& x, double* r) const
{
  constexpr int K = MaxCapacity, M = K + 1;
  const int k = N_ == n ? Size_ : 0;
  if (k == 0)
  {
    return blocked::ChunkedSums<NumberOfChannels>(n,
      [&](long long begin, long long end, double* sums)
      {
        for (long long i = begin; i < end; ++i)
          for (int c = 0; c < NumberOfChannels; ++c)
            sums[c] += r[3 * i + c] * r[3 * i + c];
      });
  }
  const int m = k + 1;
  // Per channel: G (M x M, row-major; basis 0 = x0, i = X_{i-1}) and g = V^T b.
  constexpr int PerChannel = M * M + M;
  const T* X[K] = {};
  const T* W[K] = {};
  for (int i = 0; i < k; ++i)
  {
    X[i] = xs[i].data();
    W[i] = ws[i].data();
  }
  const auto sums = blocked::ChunkedSums<NumberOfChannels * PerChannel>(n,
    [&](long long begin, long long end, double* out)
    {
      for (long long v = begin; v < end; ++v)
      {
        for (int c = 0; c < NumberOfChannels; ++c)
        {
          double* s = out + c * PerChannel;
          const std::size_t q = 3 * static_cast<std::size_t>(v) + c;
          const double bi = b[c][v], ax0 = bi - r[q], x0 = x[c][v];
          s[0] += x0 * ax0;
          s[M * M] += x0 * bi;
          for (int i = 0; i < k; ++i)
          {
            const double xi = X[i][q];
            s[i + 1] += xi * ax0; // G(0, i+1)
            s[M * M + i + 1] += xi * bi;
            for (int j = 0; j < k; ++j)
            {
              s[(i + 1) * M + j + 1] += xi * static_cast<double>(W[j][q]);
            }
          }
        }
      }
    });
  std::array<std::array<double, M>, NumberOfChannels> coef{};
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    const double* s = sums.data() + c * PerChannel;
    Eigen::MatrixXd G(m, m);
    Eigen::VectorXd g(m);
    for (int i = 0; i < m; ++i)
    {
      g[i] = s[M * M + i];
      for (int j = 0; j < m; ++j)
      {
        const double gij = i == 0 ? s[j] : (j == 0 ? s[i] : s[i * M + j]);
        const double gji = j == 0 ? s[i] : (i == 0 ? s[j] : s[j * M + i]);
        G(i, j) = 0.5 * (gij + gji);
      }
    }
    coef[c][0] = 1.0; // keep x0 unless the projection is better
    // Scaled to a unit diagonal; directions with no energy (x0 = 0) or
    // dependent ones (x0 = x_1) dropped by a pseudo-inverse.
    Eigen::VectorXd d(m);
    for (int i = 0; i < m; ++i)
    {
      d[i] = G(i, i) > 0.0 && std::isfinite(G(i, i)) ? 1.0 / std::sqrt(G(i, i)) : 0.0;
    }
    const Eigen::MatrixXd S = d.asDiagonal() * G * d.asDiagonal();
    if (!S.allFinite())
    {
      continue;
    }
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(S);
    const double top = eig.eigenvalues().cwiseAbs().maxCoeff();
    if (eig.info() != Eigen::Success || !(top > 0.0))
    {
      continue;
    }
    Eigen::VectorXd y = eig.eigenvectors().transpose() * (d.asDiagonal() * g);
    for (int i = 0; i < m; ++i)
    {
      const double lambda = eig.eigenvalues()[i];
      y[i] = lambda > 1e-9 * top ? y[i] / lambda : 0.0;
    }
    const Eigen::VectorXd cvec = d.asDiagonal() * (eig.eigenvectors() * y);
    // A-norm error up to a constant: c^T G c - 2 c^T g; x0 is c = e_0.
    const double keep = G(0, 0) - 2.0 * g[0];
    const double projected = cvec.dot(G * cvec) - 2.0 * cvec.dot(g);
    if (cvec.allFinite() && projected < keep)
    {
      for (int i = 0; i < m; ++i)
      {
        coef[c][i] = cvec[i];
      }
    }
  }
  return blocked::ChunkedSums<NumberOfChannels>(n,
    [&](long long begin, long long end, double* rr)
    {
      for (long long v = begin; v < end; ++v)
      {
        for (int c = 0; c < NumberOfChannels; ++c)
        {
          const std::size_t q = 3 * static_cast<std::size_t>(v) + c;
          const double* a = coef[c].data();
          const double bi = b[c][v];
          double xv = a[0] * x[c][v];
          double rv = (1.0 - a[0]) * bi + a[0] * r[q];
          for (int i = 0; i < k; ++i)
          {
            xv += a[i + 1] * static_cast<double>(X[i][q]);
            rv -= a[i + 1] * static_cast<double>(W[i][q]);
          }
          x[c][v] = xv;
          r[q] = rv;
          rr[c] += rv * rv;
        }
      }
    });
}

void SolutionRecycler::Store(int n, const std::array<const double*, NumberOfChannels>& b,
  const std::array<const double*, NumberOfChannels>& x, const double* r)
{
  if (Capacity_ == 0)
  {
    return;
  }
  if (N_ != n)
  {
    Size_ = 0;
    N_ = n;
  }
  if (Double_)
  {
    StoreIn(XD_, WD_, n, b, x, r);
  }
  else
  {
    StoreIn(X_, W_, n, b, x, r);
  }
}

template <typename T>
void SolutionRecycler::StoreIn(std::vector<std::vector<T>>& xs, std::vector<std::vector<T>>& ws,
  int n, const std::array<const double*, NumberOfChannels>& b,
  const std::array<const double*, NumberOfChannels>& x, const double* r)
{
  // The oldest buffers become the newest.
  std::rotate(xs.begin(), xs.begin() + (Capacity_ - 1), xs.end());
  std::rotate(ws.begin(), ws.begin() + (Capacity_ - 1), ws.end());
  Size_ = std::min(Size_ + 1, Capacity_);
  std::vector<T>& X = xs[0];
  std::vector<T>& W = ws[0];
  X.resize(3 * static_cast<std::size_t>(n));
  W.resize(3 * static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static) if(n > blocked::ParallelThreshold)
  for (int v = 0; v < n; ++v)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      const std::size_t q = 3 * static_cast<std::size_t>(v) + c;
      X[q] = static_cast<T>(x[c][v]);
      W[q] = static_cast<T>(b[c][v] - r[q]);
    }
  }
}

std::size_t SolutionRecycler::GetMemoryBytes() const
{
  std::size_t bytes = 0;
  for (std::size_t i = 0; i < X_.size(); ++i)
  {
    bytes += (X_[i].capacity() + W_[i].capacity()) * sizeof(float);
  }
  for (std::size_t i = 0; i < XD_.size(); ++i)
  {
    bytes += (XD_[i].capacity() + WD_[i].capacity()) * sizeof(double);
  }
  return bytes;
}

} // namespace translucency
