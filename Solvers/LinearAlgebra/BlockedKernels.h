/**
 * @file BlockedKernels.h
 * @brief Kernels shared by the solvers that treat the three channels of a
 * DiffusionSystem together (internal): vectors interleaved per vertex
 * (3 values per vertex), one pass over the shared pattern per product, and a
 * blocked preconditioned CG with per-channel scalars. Dot products are summed
 * over fixed chunks in a fixed order, so results do not depend on the number
 * of OpenMP threads.
 */
#pragma once

#include "DiffusionSystem.h"
#include "SolutionRecycler.h"
#include "LinearSolver.h"
#include "MultiresHierarchy.h"
#include "Error.h"
#include "TetMesh.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace translucency
{
namespace blocked
{

constexpr int NC = NumberOfChannels;
static_assert(NC == 3, "the blocked kernels assume three channels");

/// Loops over fewer rows than this run on one thread: on small (coarse)
/// levels a parallel region costs more than the work, and much more when
/// the cores are shared with other processes. Results do not depend on it.
constexpr long long ParallelThreshold = 8192;

/**
 * Throws translucency::Error (naming `solver`) unless the solver is set up
 * (`ready`) for a system of this size and `system` has right-hand sides and
 * values of the sizes of the last Setup.
 */
inline void CheckSolveMatchesSetup(const std::string& solver, const DiffusionSystem& system,
  bool ready, std::size_t unknowns, std::size_t nonZeros)
{
  if (!ready)
  {
    throw Error(solver + ": Solve() before Setup()");
  }
  bool ok = static_cast<std::size_t>(system.NumberOfUnknowns) == unknowns &&
    system.ColumnIndices.size() == nonZeros;
  for (int c = 0; c < NC && ok; ++c)
  {
    ok = static_cast<std::size_t>(system.RightHandSide[c].size()) == unknowns &&
      system.Values[c].size() == nonZeros;
  }
  if (!ok)
  {
    std::ostringstream os;
    os << solver << ": the system (" << system.NumberOfUnknowns << " unknowns, "
       << system.ColumnIndices.size() << " non-zeros) does not match the last Setup ("
       << unknowns << ", " << nonZeros << ") or its right-hand sides have the wrong size";
    throw Error(os.str());
  }
}

/**
 * Throws translucency::Error (naming `solver`) unless `system` is a CSR
 * system on the points of `mesh` with one value per non-zero in every
 * channel. The multiresolution solvers need the mesh (graph, positions).
 */
inline void CheckSystemOnMesh(
  const std::string& solver, const DiffusionSystem& system, const TetMesh* mesh)
{
  if (!mesh)
  {
    throw Error(solver + ": needs the mesh of the unknowns (vertex graph and positions)");
  }
  const int n = system.NumberOfUnknowns;
  if (n < 1 || mesh->GetNumberOfPoints() != n ||
    system.RowOffsets.size() != static_cast<std::size_t>(n) + 1 || system.RowOffsets.front() != 0 ||
    static_cast<std::size_t>(system.RowOffsets.back()) != system.ColumnIndices.size())
  {
    std::ostringstream os;
    os << solver << ": the system (" << n << " unknowns, " << system.RowOffsets.size()
       << " row offsets) does not match the mesh (" << mesh->GetNumberOfPoints() << " points)";
    throw Error(os.str());
  }
  for (int c = 0; c < NC; ++c)
  {
    if (system.Values[c].size() != system.ColumnIndices.size())
    {
      throw Error(solver + ": channel " + std::to_string(c) + " has " +
        std::to_string(system.Values[c].size()) + " values for " +
        std::to_string(system.ColumnIndices.size()) + " non-zeros");
    }
  }
}

/**
 * The coarsest level of the multigrid solvers: x = A_c^-1 b for each channel
 * c with its own factorisation factors[c], on interleaved vectors of n
 * unknowns (value 3 i + c).
 */
template <typename Factorisation, typename TB, typename TX>
inline void SolveInterleaved(const Factorisation* factors, int n, const TB* b, TX* x)
{
  Eigen::VectorXd bc(n);
  for (int c = 0; c < NC; ++c)
  {
    for (int i = 0; i < n; ++i)
    {
      bc[i] = b[3 * static_cast<long long>(i) + c];
    }
    const Eigen::VectorXd xc = factors[c].solve(bc);
    for (int i = 0; i < n; ++i)
    {
      x[3 * static_cast<long long>(i) + c] = static_cast<TX>(xc[i]);
    }
  }
}

/// Row i of A x with interleaved single-precision values v (3 per non-zero)
/// and an interleaved x of any precision, accumulated in double.
template <typename T>
inline void FloatRow(const int* ro, const int* ci, const float* v, const T* x, int i, double* a)
{
  double a0 = 0.0, a1 = 0.0, a2 = 0.0;
  for (int k = ro[i]; k < ro[i + 1]; ++k)
  {
    const T* xj = x + 3 * static_cast<std::size_t>(ci[k]);
    const float* vk = v + 3 * static_cast<std::size_t>(k);
    a0 += static_cast<double>(vk[0]) * static_cast<double>(xj[0]);
    a1 += static_cast<double>(vk[1]) * static_cast<double>(xj[1]);
    a2 += static_cast<double>(vk[2]) * static_cast<double>(xj[2]);
  }
  a[0] = a0;
  a[1] = a1;
  a[2] = a2;
}

/// Row i of the level-0 matrix times an interleaved x: double values (three
/// arrays) or, if `single` is given, its interleaved single-precision copy.
template <bool Single, typename T>
inline void SystemRow(const DiffusionSystem& s, const float* single, const T* x, int i, double* a)
{
  if constexpr (Single)
  {
    FloatRow(s.RowOffsets.data(), s.ColumnIndices.data(), single, x, i, a);
  }
  else
  {
    const int* ro = s.RowOffsets.data();
    const int* ci = s.ColumnIndices.data();
    const double* v0 = s.Values[0].data();
    const double* v1 = s.Values[1].data();
    const double* v2 = s.Values[2].data();
    double a0 = 0.0, a1 = 0.0, a2 = 0.0;
    for (int k = ro[i]; k < ro[i + 1]; ++k)
    {
      const T* xj = x + 3 * static_cast<std::size_t>(ci[k]);
      a0 += v0[k] * xj[0];
      a1 += v1[k] * xj[1];
      a2 += v2[k] * xj[2];
    }
    a[0] = a0;
    a[1] = a1;
    a[2] = a2;
  }
}

/// y = A x for the three channels of the level-0 system (one pass over the
/// pattern; x and y interleaved, 3 values per vertex).
inline void MultiplySystem(const DiffusionSystem& s, const double* x, double* y)
{
  const int n = s.NumberOfUnknowns;
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
  for (int i = 0; i < n; ++i)
  {
    SystemRow<false>(s, nullptr, x, i, y + 3 * static_cast<std::size_t>(i));
  }
}

/// y = A x with interleaved single-precision values (3 per non-zero).
inline void MultiplyFloat(const CsrPattern& p, const float* v, const double* x, double* y)
{
  const int n = p.Size;
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
  for (int i = 0; i < n; ++i)
  {
    FloatRow(p.Offsets.data(), p.Columns.data(), v, x, i, y + 3 * static_cast<std::size_t>(i));
  }
}

/// Vertices per chunk of the deterministic sums (Dot3, ChunkedSums).
constexpr long long SumChunk = 4096;

/**
 * Runs body(begin, end, sums) on the vertex ranges of fixed chunks of
 * SumChunk vertices covering [0, n) (in parallel over the chunks when
 * n > ParallelThreshold); body adds its chunk's S partial sums to sums
 * (zero on entry). The chunks' sums are then added in chunk order, so the
 * result does not depend on the number of threads. Lets a pass over the
 * vectors compute its dot products on the fly (fused kernels).
 */
template <int S, typename Body>
inline std::array<double, S> ChunkedSums(long long n, const Body& body)
{
  const long long chunks = (n + SumChunk - 1) / SumChunk;
  std::array<double, S> total{};
  if (chunks <= 1)
  {
    body(0LL, n, total.data());
    return total;
  }
  std::vector<double> partial(S * static_cast<std::size_t>(chunks), 0.0);
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
  for (long long q = 0; q < chunks; ++q)
  {
    body(q * SumChunk, std::min(n, (q + 1) * SumChunk), partial.data() + S * q);
  }
  for (long long q = 0; q < chunks; ++q)
  {
    for (int c = 0; c < S; ++c)
    {
      total[c] += partial[S * q + c];
    }
  }
  return total;
}

/// Per-channel dot products of interleaved vectors, summed over fixed chunks
/// of 4096 vertices and then over the chunks in order: the same rounding for
/// any number of threads.
inline std::array<double, NC> Dot3(const Eigen::VectorXd& a, const Eigen::VectorXd& b)
{
  const long long n = a.size() / 3;
  constexpr long long chunk = 4096;
  const long long chunks = (n + chunk - 1) / chunk;
  if (chunks <= 1)
  {
    double s0 = 0.0, s1 = 0.0, s2 = 0.0;
    for (long long i = 0; i < n; ++i)
    {
      s0 += a[3 * i] * b[3 * i];
      s1 += a[3 * i + 1] * b[3 * i + 1];
      s2 += a[3 * i + 2] * b[3 * i + 2];
    }
    return { s0, s1, s2 };
  }
  std::vector<double> partial(3 * static_cast<std::size_t>(chunks));
#pragma omp parallel for schedule(static) if(chunks > 2)
  for (long long q = 0; q < chunks; ++q)
  {
    double s0 = 0.0, s1 = 0.0, s2 = 0.0;
    const long long end = std::min(n, (q + 1) * chunk);
    for (long long i = q * chunk; i < end; ++i)
    {
      s0 += a[3 * i] * b[3 * i];
      s1 += a[3 * i + 1] * b[3 * i + 1];
      s2 += a[3 * i + 2] * b[3 * i + 2];
    }
    partial[3 * q] = s0;
    partial[3 * q + 1] = s1;
    partial[3 * q + 2] = s2;
  }
  std::array<double, NC> s{ 0.0, 0.0, 0.0 };
  for (long long q = 0; q < chunks; ++q)
  {
    for (int c = 0; c < NC; ++c)
    {
      s[c] += partial[3 * q + c];
    }
  }
  return s;
}

/// Interleave / de-interleave between Eigen channel vectors and one vector.
inline void Interleave(const std::array<Eigen::VectorXd, NC>& in, Eigen::VectorXd& out)
{
  const long long n = in[0].size();
  out.resize(3 * n);
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
  for (long long i = 0; i < n; ++i)
  {
    for (int c = 0; c < NC; ++c)
    {
      out[3 * i + c] = in[c][i];
    }
  }
}

inline void Deinterleave(const Eigen::VectorXd& in, std::array<Eigen::VectorXd, NC>& out)
{
  const long long n = in.size() / 3;
  for (int c = 0; c < NC; ++c)
  {
    out[c].resize(n);
  }
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
  for (long long i = 0; i < n; ++i)
  {
    for (int c = 0; c < NC; ++c)
    {
      out[c][i] = in[3 * i + c];
    }
  }
}

/// Per-channel start of the blocked CG loops from b.b and r.r of the
/// initial residual: the norms of b, the stats (initialSpMV SpMV-equivalents
/// so far) and which channels still iterate (a channel within tol iterates
/// anyway when minIter > 0 and its residual is not zero: LinearSolver::
/// SetMinIter). Returns the channels with b = 0, whose solution is exactly 0
/// (SPD) and which the caller zeroes.
inline std::array<bool, NC> StartChannels(const std::array<double, NC>& bb,
  const std::array<double, NC>& rr, double tol, double initialSpMV, std::array<double, NC>& normB,
  std::array<bool, NC>& active, std::array<LinearSolveStats, NC>& stats, int minIter = 0)
{
  std::array<bool, NC> zero{};
  for (int c = 0; c < NC; ++c)
  {
    normB[c] = std::sqrt(bb[c]);
    stats[c] = LinearSolveStats();
    stats[c].SpMVEquivalents = initialSpMV;
    if (normB[c] == 0.0)
    {
      zero[c] = true;
      active[c] = false;
      stats[c].Converged = true;
      continue;
    }
    stats[c].RelativeResidual = std::sqrt(rr[c]) / normB[c];
    active[c] = !(stats[c].RelativeResidual <= tol) || (minIter > 0 && rr[c] > 0.0);
    stats[c].Converged = !active[c];
  }
  return zero;
}

/// Per-channel end of a CG iteration: counts it for the active channels,
/// freezes those that reached tol after at least minIter iterations
/// (converged) or broke down (p.A p <= 0 or a non-finite residual: not SPD,
/// not converged).
inline void UpdateChannels(const std::array<double, NC>& pq, const std::array<double, NC>& rr,
  const std::array<double, NC>& normB, double tol, double spmvPerIteration,
  std::array<bool, NC>& active, std::array<LinearSolveStats, NC>& stats, int minIter = 0)
{
  for (int c = 0; c < NC; ++c)
  {
    if (!active[c])
    {
      continue;
    }
    ++stats[c].Iterations;
    stats[c].SpMVEquivalents += spmvPerIteration;
    stats[c].RelativeResidual = std::sqrt(rr[c]) / normB[c];
    if ((stats[c].RelativeResidual <= tol && stats[c].Iterations >= minIter) || rr[c] == 0.0)
    {
      active[c] = false;
      stats[c].Converged = true;
    }
    else if (!(pq[c] > 0.0) || !std::isfinite(stats[c].RelativeResidual))
    {
      active[c] = false;
    }
  }
}

/**
 * The change rule of LinearSolver::SetChangeRule: the observed rows, the
 * tolerance on the estimated error there, and per channel the last relative
 * change (-1 before the first iteration).
 */
struct ChangeRule
{
  const std::vector<int>* Rows = nullptr;
  double Tol = 0.0;
  /// Per channel: the last relative change and the last ratio of two
  /// successive changes (-1 while unknown).
  std::array<double, NC> LastChange{ -1.0, -1.0, -1.0 };
  std::array<double, NC> LastRatio{ -1.0, -1.0, -1.0 };

  /// Whether the rule is on (tol > 0 and rows).
  bool IsOn() const { return Tol > 0.0 && Rows && !Rows->empty(); }

  /// Throws translucency::Error for a row outside [0, n).
  void Check(int n, const std::string& who) const
  {
    for (int i : *Rows)
    {
      if (i < 0 || i >= n)
      {
        throw Error(who + ": change rule row " + std::to_string(i) + " outside [0, " +
          std::to_string(n) + ")");
      }
    }
  }

  /**
   * After the update x += alpha p of one iteration (p interleaved, x the
   * channel arrays, already updated): the relative change Delta_k of the
   * active channels over the rows, and the stop of those whose estimated
   * error Delta_k rho / (1 - rho) is within Tol, rho the larger of the last
   * two ratios Delta_k / Delta_{k-1} and Delta_{k-1} / Delta_{k-2} (so after
   * at least max(3, minIter) iterations: the first steps of a warm start
   * shrink faster than the later ones, and one ratio underestimated the
   * error by 25 % in TestLinearSolvers' relight). Serial over the rows (a
   * boundary: a small part of the unknowns), so the same bits at any
   * thread count.
   */
  void Update(const std::array<double, NC>& alpha, const double* p,
    const std::array<const double*, NC>& x, int minIter, std::array<bool, NC>& active,
    std::array<LinearSolveStats, NC>& stats)
  {
    std::array<double, NC> dd{}, xx{};
    for (int i : *Rows)
    {
      const long long k = i;
      for (int c = 0; c < NC; ++c)
      {
        const double d = alpha[c] * p[3 * k + c];
        dd[c] += d * d;
        xx[c] += x[c][k] * x[c][k];
      }
    }
    for (int c = 0; c < NC; ++c)
    {
      if (!active[c])
      {
        continue;
      }
      const double change = xx[c] > 0.0 ? std::sqrt(dd[c] / xx[c]) : -1.0;
      const double ratio = change >= 0.0 && LastChange[c] > 0.0 ? change / LastChange[c] : -1.0;
      const double previousRatio = LastRatio[c];
      LastChange[c] = change;
      LastRatio[c] = ratio;
      if (ratio < 0.0 || previousRatio < 0.0 || stats[c].Iterations < std::max(3, minIter))
      {
        continue;
      }
      const double rho = std::max(ratio, previousRatio);
      if (rho < 1.0 && change * rho / (1.0 - rho) <= Tol)
      {
        active[c] = false;
        stats[c].Converged = true;
        stats[c].StoppedByChange = true;
      }
    }
  }
};

/// CG step lengths alpha = r.z / p.A p of the active channels.
inline std::array<double, NC> StepLengths(const std::array<bool, NC>& active,
  const std::array<double, NC>& rz, const std::array<double, NC>& pq)
{
  std::array<double, NC> alpha{};
  for (int c = 0; c < NC; ++c)
  {
    alpha[c] = active[c] && pq[c] != 0.0 ? rz[c] / pq[c] : 0.0;
  }
  return alpha;
}

/// CG beta = r.z (new) / r.z (old) of the active channels; rz takes the new
/// values.
inline std::array<double, NC> NextBeta(const std::array<bool, NC>& active,
  std::array<double, NC>& rz, const std::array<double, NC>& rzNew)
{
  std::array<double, NC> beta{};
  for (int c = 0; c < NC; ++c)
  {
    beta[c] = active[c] && rz[c] != 0.0 ? rzNew[c] / rz[c] : 0.0;
    if (active[c])
    {
      rz[c] = rzNew[c];
    }
  }
  return beta;
}

/// CG search directions p = z + beta p of the active channels (blocked
/// vectors of n unknowns).
inline void UpdateDirections(double* p, const double* z, const std::array<double, NC>& beta,
  const std::array<bool, NC>& active, long long n)
{
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
  for (long long i = 0; i < n; ++i)
  {
    for (int c = 0; c < NC; ++c)
    {
      if (active[c])
      {
        p[3 * i + c] = z[3 * i + c] + beta[c] * p[3 * i + c];
      }
    }
  }
}

/**
 * Conjugate gradient on the three channels at once (per-channel scalars,
 * one blocked SpMV and one blocked preconditioner application per
 * iteration). Channels that converge are frozen. Returns false if aborted.
 * flopsPerIteration: multiply-adds per channel of one iteration.
 */
template <typename Precondition>
inline bool BlockedPCG(const DiffusionSystem& system, Precondition precondition, Eigen::VectorXd& x,
  double tol, int maxIter, std::array<LinearSolveStats, NC>& stats, double flopsPerIteration,
  const std::function<bool(double)>& progress, int minIter = 0)
{
  const int n = system.NumberOfUnknowns;
  const double nnz = std::max<double>(1.0, static_cast<double>(system.ColumnIndices.size()));
  Eigen::VectorXd b;
  Interleave(system.RightHandSide, b);
  Eigen::VectorXd r(3 * static_cast<long long>(n)), z(r.size()), p(r.size()), q(r.size());
  MultiplySystem(system, x.data(), q.data());
  r = b - q;
  const auto bb = Dot3(b, b);
  std::array<bool, NC> active;
  std::array<double, NC> normB, rz{};
  auto rr = Dot3(r, r);
  const auto zero = StartChannels(bb, rr, tol, 1.0 + 4.0 * n / nnz, normB, active, stats, minIter);
  for (int c = 0; c < NC; ++c)
  {
    for (int i = 0; zero[c] && i < n; ++i)
    {
      x[3 * static_cast<long long>(i) + c] = 0.0;
    }
  }
  auto anyActive = [&]() { return active[0] || active[1] || active[2]; };
  if (anyActive())
  {
    precondition(r, z);
    p = z;
    rz = Dot3(r, z);
  }
  for (int it = 0; it < maxIter && anyActive(); ++it)
  {
    if (progress && !progress(static_cast<double>(it) / maxIter))
    {
      return false;
    }
    MultiplySystem(system, p.data(), q.data());
    const auto pq = Dot3(p, q);
    const std::array<double, NC> alpha = StepLengths(active, rz, pq);
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
    for (long long i = 0; i < static_cast<long long>(n); ++i)
    {
      for (int c = 0; c < NC; ++c)
      {
        x[3 * i + c] += alpha[c] * p[3 * i + c];
        r[3 * i + c] -= alpha[c] * q[3 * i + c];
      }
    }
    rr = Dot3(r, r);
    UpdateChannels(pq, rr, normB, tol, flopsPerIteration / nnz, active, stats, minIter);
    if (!anyActive())
    {
      break;
    }
    precondition(r, z);
    const auto rzNew = Dot3(r, z);
    UpdateDirections(p.data(), z.data(), NextBeta(active, rz, rzNew), active, n);
  }
  if (progress)
  {
    progress(1.0);
  }
  return true;
}

/// Work vectors of FusedBlockedPCG, kept by the solver between solves (a
/// fresh 4.4 MB vector per solve at 180k unknowns costs its page faults).
struct FusedPCGWorkspace
{
  Eigen::VectorXd R, Z, P, Q;
};

/// FusedBlockedPCG's initial residual r = b - A x (from x = 0 when not
/// warm: no product) with b.b (sums 0-2) and r.r (sums 3-5); S: the single-
/// precision values.
template <bool S>
inline auto FusedInitialResidual(const DiffusionSystem& system, const float* single,
  const double* const bc[NC], const double* const xc[NC], bool warm, double* r)
{
  const int n = system.NumberOfUnknowns;
  return ChunkedSums<6>(n,
    [&](long long begin, long long end, double* sums)
    {
      double local[6] = { 0.0, 0.0, 0.0, 0.0, 0.0, 0.0 };
      for (long long i = begin; i < end; ++i)
      {
        double ax[3] = { 0.0, 0.0, 0.0 };
        if (warm)
        {
          // Row i of A x with x in the channel arrays.
          const int* ro = system.RowOffsets.data();
          const int* ci = system.ColumnIndices.data();
          for (int k = ro[i]; k < ro[i + 1]; ++k)
          {
            const int j = ci[k];
            for (int c = 0; c < NC; ++c)
            {
              const double a = S ? static_cast<double>(single[3 * static_cast<std::size_t>(k) + c])
                                 : system.Values[c][k];
              ax[c] += a * xc[c][j];
            }
          }
        }
        for (int c = 0; c < NC; ++c)
        {
          const double b = bc[c][i];
          const double ri = b - ax[c];
          r[3 * i + c] = ri;
          local[c] += b * b;
          local[3 + c] += ri * ri;
        }
      }
      for (int c = 0; c < 6; ++c)
      {
        sums[c] += local[c];
      }
    });
}

/// FusedBlockedPCG: q = A p with p.q per channel; S: the single-precision
/// values.
template <bool S>
inline auto FusedProduct(const DiffusionSystem& system, const float* single, const double* p, double* q)
{
  const int n = system.NumberOfUnknowns;
  return ChunkedSums<3>(n,
    [&](long long begin, long long end, double* sums)
    {
      double s0 = 0.0, s1 = 0.0, s2 = 0.0;
      for (long long i = begin; i < end; ++i)
      {
        double* qi = q + 3 * i;
        SystemRow<S>(system, single, p, static_cast<int>(i), qi);
        s0 += p[3 * i] * qi[0];
        s1 += p[3 * i + 1] * qi[1];
        s2 += p[3 * i + 2] * qi[2];
      }
      sums[0] += s0;
      sums[1] += s1;
      sums[2] += s2;
    });
}

/// FusedBlockedPCG: x += alpha p (x in the channel arrays x0, x1, x2),
/// r -= alpha q, with r.r per channel.
inline auto FusedUpdate(int n, const std::array<double, NC>& alpha, const double* p, const double* q,
  double* x0, double* x1, double* x2, double* r)
{
  return ChunkedSums<3>(n,
    [&](long long begin, long long end, double* sums)
    {
      double s0 = 0.0, s1 = 0.0, s2 = 0.0;
      for (long long i = begin; i < end; ++i)
      {
        x0[i] += alpha[0] * p[3 * i];
        x1[i] += alpha[1] * p[3 * i + 1];
        x2[i] += alpha[2] * p[3 * i + 2];
        const double r0 = r[3 * i] - alpha[0] * q[3 * i];
        const double r1 = r[3 * i + 1] - alpha[1] * q[3 * i + 1];
        const double r2 = r[3 * i + 2] - alpha[2] * q[3 * i + 2];
        r[3 * i] = r0;
        r[3 * i + 1] = r1;
        r[3 * i + 2] = r2;
        s0 += r0 * r0;
        s1 += r1 * r1;
        s2 += r2 * r2;
      }
      sums[0] += s0;
      sums[1] += s1;
      sums[2] += s2;
    });
}

/**
 * BlockedPCG with fused passes over the vectors (the same iteration and the
 * same per-channel scalars; each dot product is computed, in the chunked
 * deterministic order of Dot3, inside the pass that produces its operand):
 *
 * - initial residual r = b - A x together with b.b and r.r, reading b and x
 *   from the channel arrays (no interleaved copies; from x = 0 no product);
 * - q = A p together with p.q;
 * - x += alpha p, r -= alpha q together with r.r; x stays in the caller's
 *   three channel arrays (it is only streamed, never gathered);
 * - precondition(r, z) returns r.z (it computes it in its last pass);
 * - p = z + beta p (the first p is z itself: the buffers are swapped).
 *
 * single: interleaved single-precision values of the level-0 matrix (3 per
 * non-zero) for the products of CG itself, or nullptr for the double values.
 * With single values CG solves the rounded system A_f x = b, so RelTol is
 * reached for A_f: use it only for tolerances well above the rounding
 * (the caller's rule). warm: start from x (else from 0; x is resized).
 * Work vectors in `w`. recycler (optional): a warm start is first replaced
 * by its projection onto span{x, kept solutions} (SolutionRecycler), and
 * the solution is kept there after a solve that was not aborted. minIter:
 * LinearSolver::SetMinIter. change (optional): the change rule
 * (LinearSolver::SetChangeRule; rows checked by the caller). Returns false
 * if aborted.
 */
template <typename Precondition>
inline bool FusedBlockedPCG(const DiffusionSystem& system, const float* single,
  Precondition precondition, std::array<Eigen::VectorXd, NC>& x, bool warm, double tol,
  int maxIter, std::array<LinearSolveStats, NC>& stats, double flopsPerIteration,
  const std::function<bool(double)>& progress, FusedPCGWorkspace& w,
  SolutionRecycler* recycler = nullptr, int minIter = 0, ChangeRule* change = nullptr)
{
  const int n = system.NumberOfUnknowns;
  const long long n3 = 3 * static_cast<long long>(n);
  if (change && !change->IsOn())
  {
    change = nullptr;
  }
  const double nnz = std::max<double>(1.0, static_cast<double>(system.ColumnIndices.size()));
  for (auto* v : { &w.R, &w.Z, &w.P, &w.Q })
  {
    if (v->size() != n3)
    {
      v->resize(n3);
    }
  }
  for (int c = 0; c < NC; ++c)
  {
    if (!warm || x[c].size() != n)
    {
      warm = false;
    }
  }
  if (!warm)
  {
    for (int c = 0; c < NC; ++c)
    {
      x[c].setZero(n);
    }
  }
  double* r = w.R.data();
  double* q = w.Q.data();
  // Initial residual with b.b and r.r (sums 0-2: b.b, 3-5: r.r).
  const double* bc[NC] = { system.RightHandSide[0].data(), system.RightHandSide[1].data(),
    system.RightHandSide[2].data() };
  const double* xc[NC] = { x[0].data(), x[1].data(), x[2].data() };
  std::array<double, 6> start = single ? FusedInitialResidual<true>(system, single, bc, xc, warm, r)
                                       : FusedInitialResidual<false>(system, single, bc, xc, warm, r);
  double recycleSpMV = 0.0;
  if (recycler && warm && recycler->GetSize() > 0)
  {
    const int k = recycler->GetSize();
    const auto rr = recycler->Project(n, { bc[0], bc[1], bc[2] }, { x[0].data(), x[1].data(), x[2].data() }, r);
    start[3] = rr[0];
    start[4] = rr[1];
    start[5] = rr[2];
    // Two passes over x, r, b and 2k single-precision vectors (multiply-adds
    // per channel: (k + 1)^2 + (k + 1) + 2k + 2 per vertex).
    recycleSpMV = ((k + 1.0) * (k + 1.0) + 3.0 * k + 3.0) * n / nnz;
  }
  std::array<bool, NC> active;
  std::array<double, NC> normB, rz{};
  const auto zero = StartChannels({ start[0], start[1], start[2] },
    { start[3], start[4], start[5] }, tol, (warm ? 1.0 : 0.0) + 4.0 * n / nnz + recycleSpMV,
    normB, active, stats, minIter);
  for (int c = 0; c < NC; ++c)
  {
    if (zero[c])
    {
      x[c].setZero();
      for (int i = 0; i < n; ++i)
      {
        r[3 * static_cast<long long>(i) + c] = 0.0; // b = 0, x = 0
      }
    }
  }
  auto anyActive = [&]() { return active[0] || active[1] || active[2]; };
  if (anyActive())
  {
    rz = precondition(static_cast<const double*>(r), w.Z.data());
    w.P.swap(w.Z); // p = z
  }
  for (int it = 0; it < maxIter && anyActive(); ++it)
  {
    if (progress && !progress(static_cast<double>(it) / maxIter))
    {
      return false;
    }
    const auto pq = single ? FusedProduct<true>(system, single, w.P.data(), q)
                           : FusedProduct<false>(system, single, w.P.data(), q);
    const std::array<double, NC> alpha = StepLengths(active, rz, pq);
    const auto rr = FusedUpdate(n, alpha, w.P.data(), q, x[0].data(), x[1].data(), x[2].data(), r);
    UpdateChannels(pq, rr, normB, tol, flopsPerIteration / nnz, active, stats, minIter);
    if (change)
    {
      change->Update(alpha, w.P.data(), { x[0].data(), x[1].data(), x[2].data() }, minIter,
        active, stats);
    }
    if (!anyActive())
    {
      break;
    }
    const auto rzNew = precondition(static_cast<const double*>(r), w.Z.data());
    UpdateDirections(w.P.data(), w.Z.data(), NextBeta(active, rz, rzNew), active, n);
  }
  if (recycler)
  {
    recycler->Store(n, { bc[0], bc[1], bc[2] }, { x[0].data(), x[1].data(), x[2].data() }, r);
  }
  if (progress)
  {
    progress(1.0);
  }
  return true;
}

/// Level-0 Jacobi preconditioner z = D^-1 r.
struct JacobiApply
{
  const Eigen::VectorXd* InverseDiagonal;
  void operator()(const Eigen::VectorXd& r, Eigen::VectorXd& z) const
  {
    z = r.cwiseProduct(*InverseDiagonal);
  }
};
} // namespace blocked
} // namespace translucency
