#include "DistributedPCG.h"

#include "Error.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <string>
#include <vector>

namespace translucency
{

namespace
{

constexpr int NC = NumberOfChannels;

/// The reductions of one SolveChannelsPCG: each sums its values over the
/// ranks with this rank's failure flag appended (one MPI_Allreduce), so that
/// an exception on one rank stops every rank at the same point.
class Reductions
{
public:
  explicit Reductions(MPI_Comm comm)
    : Comm_(comm)
  {
  }

  /// Runs `f`, keeping the first exception's message (nothing once failed).
  template <typename F>
  void Guard(F&& f)
  {
    if (Failed_)
      return;
    try
    {
      f();
    }
    catch (const std::exception& e)
    {
      Failed_ = true;
      Error_ = e.what();
    }
  }

  /// values[0 .. count) summed over the ranks; false if any rank failed.
  bool Sum(double* values, int count)
  {
    Buffer_.assign(values, values + count);
    Buffer_.push_back(Failed_ ? 1.0 : 0.0);
    MPI_Allreduce(MPI_IN_PLACE, Buffer_.data(), count + 1, MPI_DOUBLE, MPI_SUM, Comm_);
    std::copy_n(Buffer_.begin(), count, values);
    return Buffer_[static_cast<std::size_t>(count)] == 0.0;
  }

  /// Rethrows this rank's exception, if any.
  void Finish() const
  {
    if (Failed_)
      throw Error(Error_);
  }

private:
  MPI_Comm Comm_;
  bool Failed_ = false;
  std::string Error_;
  std::vector<double> Buffer_;
};

} // namespace

void SolveChannelsPCG(MPI_Comm comm, int rows,
  const std::array<DistributedPCGChannel*, NumberOfChannels>& channels,
  const std::array<const double*, NumberOfChannels>& b, const std::array<double*, NumberOfChannels>& x,
  const std::array<bool, NumberOfChannels>& guess, const DistributedSolveControl& control,
  std::array<DistributedChannelStats, NumberOfChannels>& stats)
{
  const long long n = rows > 0 ? rows : 0;
  const double tol = control.RelTol;
  Reductions reduce(comm);
  std::array<bool, NC> active{};
  std::array<double, NC> normB{}, rz{};
  auto anyActive = [&active]() { return active[0] || active[1] || active[2]; };

  static const std::vector<int> none;
  const std::vector<int>& changeRows = control.ChangeRows ? *control.ChangeRows : none;
  reduce.Guard([&] {
    for (const int i : changeRows)
    {
      if (i < 0 || i >= n)
      {
        throw Error("SolveChannels: change rule row " + std::to_string(i) + " outside [0, " +
          std::to_string(n) + ")");
      }
    }
  });

  // The initial residual r = b - A x (x = 0: r = b), with b.b and r.r.
  std::array<double, 2 * NC> start{};
  for (int c = 0; c < NC; ++c)
  {
    if (!channels[c])
      continue;
    stats[c] = DistributedChannelStats();
    DistributedPCGChannel& ch = *channels[c];
    if (guess[c])
    {
      std::copy_n(x[c], n, ch.P);
      reduce.Guard(ch.Multiply);
      for (long long i = 0; i < n; ++i)
        ch.R[i] = b[c][i] - ch.Q[i];
    }
    else
    {
      std::fill_n(x[c], n, 0.0);
      std::copy_n(b[c], n, ch.R);
    }
    for (long long i = 0; i < n; ++i)
    {
      start[c] += b[c][i] * b[c][i];
      start[NC + c] += ch.R[i] * ch.R[i];
    }
  }
  if (!reduce.Sum(start.data(), 2 * NC))
    return reduce.Finish();
  for (int c = 0; c < NC; ++c)
  {
    if (!channels[c])
      continue;
    const double bb = start[c], rr = start[NC + c];
    normB[c] = std::sqrt(bb);
    if (bb == 0.0)
    {
      std::fill_n(x[c], n, 0.0); // A SPD: the solution of A x = 0
      stats[c].Converged = true;
      continue;
    }
    stats[c].RelativeResidual = std::sqrt(rr) / normB[c];
    if (!std::isfinite(stats[c].RelativeResidual))
    {
      stats[c].Iterations = 1; // a breakdown in the first iteration: not converged
      continue;
    }
    // Within RelTol: no iteration, unless MinIter asks for one (a paint).
    active[c] = !(stats[c].RelativeResidual <= tol) || (control.MinIter[c] > 0 && rr > 0.0);
    stats[c].Converged = !active[c];
  }

  // z = M r, r.z, and the new directions; false once a rank failed.
  auto precondition = [&](bool first) {
    std::array<double, NC> rzNew{};
    for (int c = 0; c < NC; ++c)
    {
      if (!active[c])
        continue;
      DistributedPCGChannel& ch = *channels[c];
      reduce.Guard(ch.Precondition);
      for (long long i = 0; i < n; ++i)
        rzNew[c] += ch.R[i] * ch.Z[i];
    }
    if (!reduce.Sum(rzNew.data(), NC))
      return false;
    for (int c = 0; c < NC; ++c)
    {
      if (!active[c])
        continue;
      DistributedPCGChannel& ch = *channels[c];
      // r != 0 here: r.z <= 0 is an indefinite preconditioner (a breakdown,
      // counted in the iteration it ends: at least one).
      if (!(rzNew[c] > 0.0) || !std::isfinite(rzNew[c]))
      {
        active[c] = false;
        stats[c].Iterations = std::max(stats[c].Iterations, 1);
        continue;
      }
      const double beta = first ? 0.0 : rzNew[c] / rz[c];
      rz[c] = rzNew[c];
      if (first)
        std::copy_n(ch.Z, n, ch.P);
      else
        for (long long i = 0; i < n; ++i)
          ch.P[i] = ch.Z[i] + beta * ch.P[i];
    }
    return true;
  };
  if (anyActive() && !precondition(true))
    return reduce.Finish();

  // The change rule's state (BlockedKernels.h, ChangeRule).
  const bool change = control.ChangeTol > 0.0;
  std::array<double, NC> lastChange{ -1.0, -1.0, -1.0 }, lastRatio{ -1.0, -1.0, -1.0 };

  for (int it = 0; it < control.MaxIter && anyActive(); ++it)
  {
    // q = A p, p.q
    std::array<double, NC> pq{};
    for (int c = 0; c < NC; ++c)
    {
      if (!active[c])
        continue;
      DistributedPCGChannel& ch = *channels[c];
      reduce.Guard(ch.Multiply);
      for (long long i = 0; i < n; ++i)
        pq[c] += ch.P[i] * ch.Q[i];
    }
    if (!reduce.Sum(pq.data(), NC))
      return reduce.Finish();

    // x += alpha p, r -= alpha q, with r.r and the change rule's sums:
    // sums[c] r.r, sums[NC + c] ||alpha p||^2 and sums[2 NC + c] ||x||^2
    // over the observed rows.
    std::array<double, 3 * NC> sums{};
    std::array<double, NC> alpha{};
    for (int c = 0; c < NC; ++c)
    {
      if (!active[c])
        continue;
      alpha[c] = rz[c] / pq[c];
      if (!(pq[c] > 0.0) || !std::isfinite(alpha[c]))
      {
        // Not SPD (or not finite): stopped, not converged, x the last
        // iterate; the iteration counted (as the serial blocked PCG).
        active[c] = false;
        ++stats[c].Iterations;
        continue;
      }
      DistributedPCGChannel& ch = *channels[c];
      double* xc = x[c];
      double rr = 0.0;
      for (long long i = 0; i < n; ++i)
      {
        xc[i] += alpha[c] * ch.P[i];
        ch.R[i] -= alpha[c] * ch.Q[i];
        rr += ch.R[i] * ch.R[i];
      }
      sums[c] = rr;
      if (change)
      {
        for (const int i : changeRows)
        {
          const double d = alpha[c] * ch.P[i];
          sums[NC + c] += d * d;
          sums[2 * NC + c] += xc[i] * xc[i];
        }
      }
    }
    if (!reduce.Sum(sums.data(), change ? 3 * NC : NC))
      return reduce.Finish();
    for (int c = 0; c < NC; ++c)
    {
      if (!active[c])
        continue;
      ++stats[c].Iterations;
      stats[c].RelativeResidual = std::sqrt(sums[c]) / normB[c];
      if ((stats[c].RelativeResidual <= tol && stats[c].Iterations >= control.MinIter[c]) ||
        sums[c] == 0.0)
      {
        active[c] = false;
        stats[c].Converged = true;
        continue;
      }
      if (!std::isfinite(stats[c].RelativeResidual))
      {
        active[c] = false;
        continue;
      }
      if (!change)
        continue;
      // The change rule: the same decision on every rank (global sums).
      const double xx = sums[2 * NC + c];
      const double delta = xx > 0.0 ? std::sqrt(sums[NC + c] / xx) : -1.0;
      const double ratio = delta >= 0.0 && lastChange[c] > 0.0 ? delta / lastChange[c] : -1.0;
      const double previousRatio = lastRatio[c];
      lastChange[c] = delta;
      lastRatio[c] = ratio;
      if (ratio < 0.0 || previousRatio < 0.0 ||
        stats[c].Iterations < std::max(3, control.MinIter[c]))
        continue;
      const double rho = std::max(ratio, previousRatio);
      if (rho < 1.0 && delta * rho / (1.0 - rho) <= control.ChangeTol)
      {
        active[c] = false;
        stats[c].Converged = true;
        stats[c].StoppedByChange = true;
      }
    }
    if (anyActive() && !precondition(false))
      return reduce.Finish();
  }
  reduce.Finish();
}

} // namespace translucency
