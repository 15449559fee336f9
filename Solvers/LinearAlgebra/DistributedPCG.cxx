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

/// SolveChannelsPCG's state and phases (each collective).
class ChannelsPCG
{
public:
  ChannelsPCG(MPI_Comm comm, int rows, const std::array<DistributedPCGChannel*, NC>& channels,
    const std::array<const double*, NC>& b, const std::array<double*, NC>& x,
    const DistributedSolveControl& control, std::array<DistributedChannelStats, NC>& stats)
    : Reduce(comm)
    , N(rows > 0 ? rows : 0)
    , Channels(channels)
    , B(b)
    , X(x)
    , Control(control)
    , Stats(stats)
  {
    static const std::vector<int> none;
    ChangeRows = control.ChangeRows ? control.ChangeRows : &none;
  }

  bool AnyActive() const { return Active[0] || Active[1] || Active[2]; }

  /// The initial residual r = b - A x (x = 0 unless guess: r = b) with b.b
  /// and r.r, and which channels iterate. False once a rank failed.
  bool Start(const std::array<bool, NC>& guess)
  {
    Reduce.Guard([this] {
      for (const int i : *ChangeRows)
      {
        if (i < 0 || i >= N)
        {
          throw Error("SolveChannels: change rule row " + std::to_string(i) + " outside [0, " +
            std::to_string(N) + ")");
        }
      }
    });
    std::array<double, 2 * NC> sums{};
    for (int c = 0; c < NC; ++c)
    {
      if (!Channels[c])
        continue;
      Stats[c] = DistributedChannelStats();
      DistributedPCGChannel& ch = *Channels[c];
      if (guess[c])
      {
        std::copy_n(X[c], N, ch.P);
        Reduce.Guard(ch.Multiply);
        for (long long i = 0; i < N; ++i)
          ch.R[i] = B[c][i] - ch.Q[i];
      }
      else
      {
        std::fill_n(X[c], N, 0.0);
        std::copy_n(B[c], N, ch.R);
      }
      for (long long i = 0; i < N; ++i)
      {
        sums[c] += B[c][i] * B[c][i];
        sums[NC + c] += ch.R[i] * ch.R[i];
      }
    }
    if (!Reduce.Sum(sums.data(), 2 * NC))
      return false;
    for (int c = 0; c < NC; ++c)
    {
      if (!Channels[c])
        continue;
      const double bb = sums[c], rr = sums[NC + c];
      NormB[c] = std::sqrt(bb);
      if (bb == 0.0)
      {
        std::fill_n(X[c], N, 0.0); // A SPD: the solution of A x = 0
        Stats[c].Converged = true;
        continue;
      }
      Stats[c].RelativeResidual = std::sqrt(rr) / NormB[c];
      if (!std::isfinite(Stats[c].RelativeResidual))
      {
        Stats[c].Iterations = 1; // a breakdown in the first iteration: not converged
        continue;
      }
      // Within RelTol: no iteration, unless MinIter asks for one (a paint).
      Active[c] = !(Stats[c].RelativeResidual <= Control.RelTol) || (Control.MinIter[c] > 0 && rr > 0.0);
      Stats[c].Converged = !Active[c];
    }
    return true;
  }

  /// z = M r and r.z of the active channels, and beta for their next
  /// direction p = z (first) or z + beta p, made in Iterate just before its
  /// product. False once a rank failed.
  bool Precondition(bool first)
  {
    std::array<double, NC> rzNew{};
    // The reverse of Iterate's order (FuseChannels): the channel whose
    // matrix Iterate streamed last is preconditioned first.
    for (int c = NC - 1; c >= 0; --c)
    {
      if (!Active[c])
        continue;
      DistributedPCGChannel& ch = *Channels[c];
      Reduce.Guard(ch.Precondition);
      for (long long i = 0; i < N; ++i)
        rzNew[c] += ch.R[i] * ch.Z[i];
    }
    if (!Reduce.Sum(rzNew.data(), NC))
      return false;
    for (int c = 0; c < NC; ++c)
    {
      if (!Active[c])
        continue;
      // r != 0 here: r.z <= 0 is an indefinite preconditioner (a breakdown,
      // counted in the iteration it ends: at least one).
      if (!(rzNew[c] > 0.0) || !std::isfinite(rzNew[c]))
      {
        Active[c] = false;
        Stats[c].Iterations = std::max(Stats[c].Iterations, 1);
        continue;
      }
      Beta[c] = first ? 0.0 : rzNew[c] / Rz[c];
      FirstDirection[c] = first;
      Rz[c] = rzNew[c];
    }
    return true;
  }

  /// One iteration's q = A p, x += alpha p, r -= alpha q and its tests
  /// (RelTol after MinIter, breakdown, the change rule). False once a rank
  /// failed.
  bool Iterate()
  {
    std::array<double, NC> pq{};
    for (int c = 0; c < NC; ++c)
    {
      if (!Active[c])
        continue;
      DistributedPCGChannel& ch = *Channels[c];
      // The direction of Precondition's beta, then q = A p and p.q.
      if (FirstDirection[c])
        std::copy_n(ch.Z, N, ch.P);
      else
        for (long long i = 0; i < N; ++i)
          ch.P[i] = ch.Z[i] + Beta[c] * ch.P[i];
      Reduce.Guard(ch.Multiply);
      for (long long i = 0; i < N; ++i)
        pq[c] += ch.P[i] * ch.Q[i];
    }
    if (!Reduce.Sum(pq.data(), NC))
      return false;
    // sums[c] r.r, sums[NC + c] ||alpha p||^2 and sums[2 NC + c] ||x||^2
    // over the observed rows.
    std::array<double, 3 * NC> sums{};
    for (int c = NC - 1; c >= 0; --c) // the last product's channel first
    {
      if (Active[c])
        Update(c, pq[c], sums);
    }
    const bool change = Control.ChangeTol > 0.0;
    if (!Reduce.Sum(sums.data(), change ? 3 * NC : NC))
      return false;
    for (int c = 0; c < NC; ++c)
    {
      if (!Active[c])
        continue;
      ++Stats[c].Iterations;
      Stats[c].RelativeResidual = std::sqrt(sums[c]) / NormB[c];
      if ((Stats[c].RelativeResidual <= Control.RelTol && Stats[c].Iterations >= Control.MinIter[c]) ||
        sums[c] == 0.0)
      {
        Active[c] = false;
        Stats[c].Converged = true;
      }
      else if (!std::isfinite(Stats[c].RelativeResidual))
        Active[c] = false;
      else if (change)
        ChangeRule(c, sums[NC + c], sums[2 * NC + c]);
    }
    return true;
  }

  void Finish() const { Reduce.Finish(); }

private:
  /// Channel c's x += alpha p, r -= alpha q with its local sums (Iterate);
  /// a breakdown (p.q <= 0, a non-finite step) stops it instead.
  void Update(int c, double pq, std::array<double, 3 * NC>& sums)
  {
    const double alpha = Rz[c] / pq;
    if (!(pq > 0.0) || !std::isfinite(alpha))
    {
      // Not SPD (or not finite): stopped, not converged, x the last
      // iterate; the iteration counted (as the serial blocked PCG).
      Active[c] = false;
      ++Stats[c].Iterations;
      return;
    }
    DistributedPCGChannel& ch = *Channels[c];
    double* x = X[c];
    double rr = 0.0;
    for (long long i = 0; i < N; ++i)
    {
      x[i] += alpha * ch.P[i];
      ch.R[i] -= alpha * ch.Q[i];
      rr += ch.R[i] * ch.R[i];
    }
    sums[c] = rr;
    if (Control.ChangeTol > 0.0)
    {
      for (const int i : *ChangeRows)
      {
        const double d = alpha * ch.P[i];
        sums[NC + c] += d * d;
        sums[2 * NC + c] += x[i] * x[i];
      }
    }
  }

  /// The change rule (BlockedKernels.h, ChangeRule) of channel c from the
  /// global sums ||x_k - x_{k-1}||^2 (dd) and ||x_k||^2 (xx) over the
  /// observed rows: the same decision on every rank.
  void ChangeRule(int c, double dd, double xx)
  {
    const double delta = xx > 0.0 ? std::sqrt(dd / xx) : -1.0;
    const double ratio = delta >= 0.0 && LastChange[c] > 0.0 ? delta / LastChange[c] : -1.0;
    const double previousRatio = LastRatio[c];
    LastChange[c] = delta;
    LastRatio[c] = ratio;
    if (ratio < 0.0 || previousRatio < 0.0 || Stats[c].Iterations < std::max(3, Control.MinIter[c]))
      return;
    const double rho = std::max(ratio, previousRatio);
    if (rho < 1.0 && delta * rho / (1.0 - rho) <= Control.ChangeTol)
    {
      Active[c] = false;
      Stats[c].Converged = true;
      Stats[c].StoppedByChange = true;
    }
  }

  Reductions Reduce;
  const long long N;
  const std::array<DistributedPCGChannel*, NC>& Channels;
  const std::array<const double*, NC>& B;
  const std::array<double*, NC>& X;
  const DistributedSolveControl& Control;
  std::array<DistributedChannelStats, NC>& Stats;
  const std::vector<int>* ChangeRows = nullptr;
  std::array<bool, NC> Active{};
  std::array<double, NC> NormB{}, Rz{}, Beta{};
  /// The next direction is z itself (the first iteration).
  std::array<bool, NC> FirstDirection{};
  /// The change rule: per channel the last change and ratio (-1: unknown).
  std::array<double, NC> LastChange{ -1.0, -1.0, -1.0 }, LastRatio{ -1.0, -1.0, -1.0 };
};

} // namespace

void SolveChannelsPCG(MPI_Comm comm, int rows,
  const std::array<DistributedPCGChannel*, NumberOfChannels>& channels,
  const std::array<const double*, NumberOfChannels>& b, const std::array<double*, NumberOfChannels>& x,
  const std::array<bool, NumberOfChannels>& guess, const DistributedSolveControl& control,
  std::array<DistributedChannelStats, NumberOfChannels>& stats)
{
  auto solve = [&](const std::array<DistributedPCGChannel*, NC>& solved) {
    ChannelsPCG pcg(comm, rows, solved, b, x, control, stats);
    bool ok = pcg.Start(guess) && (!pcg.AnyActive() || pcg.Precondition(true));
    for (int it = 0; ok && it < control.MaxIter && pcg.AnyActive(); ++it)
      ok = pcg.Iterate() && (!pcg.AnyActive() || pcg.Precondition(false));
    pcg.Finish();
  };
  if (control.FuseChannels)
  {
    solve(channels);
    return;
  }
  // One channel after the other: the same iterations, each reduction of one
  // channel.
  for (int c = 0; c < NC; ++c)
  {
    if (!channels[c])
      continue;
    std::array<DistributedPCGChannel*, NC> one{};
    one[c] = channels[c];
    solve(one);
  }
}

} // namespace translucency
