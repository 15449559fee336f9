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
template <typename Factorisation>
inline void SolveInterleaved(const Factorisation* factors, int n, const double* b, double* x)
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
      x[3 * static_cast<long long>(i) + c] = xc[i];
    }
  }
}

/// y = A x for the three channels of the level-0 system (one pass over the
/// pattern; x and y interleaved, 3 values per vertex).
inline void MultiplySystem(const DiffusionSystem& s, const double* x, double* y)
{
  const int n = s.NumberOfUnknowns;
  const int* ro = s.RowOffsets.data();
  const int* ci = s.ColumnIndices.data();
  const double* v0 = s.Values[0].data();
  const double* v1 = s.Values[1].data();
  const double* v2 = s.Values[2].data();
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
  for (int i = 0; i < n; ++i)
  {
    double a0 = 0.0, a1 = 0.0, a2 = 0.0;
    for (int k = ro[i]; k < ro[i + 1]; ++k)
    {
      const double* xj = x + 3 * static_cast<std::size_t>(ci[k]);
      a0 += v0[k] * xj[0];
      a1 += v1[k] * xj[1];
      a2 += v2[k] * xj[2];
    }
    y[3 * static_cast<std::size_t>(i)] = a0;
    y[3 * static_cast<std::size_t>(i) + 1] = a1;
    y[3 * static_cast<std::size_t>(i) + 2] = a2;
  }
}

/// y = A x with interleaved single-precision values (3 per non-zero).
inline void MultiplyFloat(const CsrPattern& p, const float* v, const double* x, double* y)
{
  const int n = p.Size;
  const int* ro = p.Offsets.data();
  const int* ci = p.Columns.data();
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
  for (int i = 0; i < n; ++i)
  {
    double a0 = 0.0, a1 = 0.0, a2 = 0.0;
    for (int k = ro[i]; k < ro[i + 1]; ++k)
    {
      const double* xj = x + 3 * static_cast<std::size_t>(ci[k]);
      const float* vk = v + 3 * static_cast<std::size_t>(k);
      a0 += vk[0] * xj[0];
      a1 += vk[1] * xj[1];
      a2 += vk[2] * xj[2];
    }
    y[3 * static_cast<std::size_t>(i)] = a0;
    y[3 * static_cast<std::size_t>(i) + 1] = a1;
    y[3 * static_cast<std::size_t>(i) + 2] = a2;
  }
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

/**
 * Conjugate gradient on the three channels at once (per-channel scalars,
 * one blocked SpMV and one blocked preconditioner application per
 * iteration). Channels that converge are frozen. Returns false if aborted.
 * flopsPerIteration: multiply-adds per channel of one iteration.
 */
template <typename Precondition>
inline bool BlockedPCG(const DiffusionSystem& system, Precondition precondition, Eigen::VectorXd& x,
  double tol, int maxIter, std::array<LinearSolveStats, NC>& stats, double flopsPerIteration,
  const std::function<bool(double)>& progress)
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
  for (int c = 0; c < NC; ++c)
  {
    normB[c] = std::sqrt(bb[c]);
    stats[c] = LinearSolveStats();
    stats[c].SpMVEquivalents = 1.0 + 4.0 * n / nnz; // initial residual
    if (normB[c] == 0.0)
    {
      // SPD: the solution is exactly zero.
      for (int i = 0; i < n; ++i)
      {
        x[3 * static_cast<long long>(i) + c] = 0.0;
      }
      active[c] = false;
      stats[c].Converged = true;
      continue;
    }
    stats[c].RelativeResidual = std::sqrt(rr[c]) / normB[c];
    active[c] = !(stats[c].RelativeResidual <= tol);
    stats[c].Converged = !active[c];
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
    std::array<double, NC> alpha{};
    for (int c = 0; c < NC; ++c)
    {
      alpha[c] = active[c] && pq[c] != 0.0 ? rz[c] / pq[c] : 0.0;
    }
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
    for (int c = 0; c < NC; ++c)
    {
      if (!active[c])
      {
        continue;
      }
      ++stats[c].Iterations;
      stats[c].SpMVEquivalents += flopsPerIteration / nnz;
      stats[c].RelativeResidual = std::sqrt(rr[c]) / normB[c];
      if (stats[c].RelativeResidual <= tol)
      {
        active[c] = false;
        stats[c].Converged = true;
      }
      else if (!(pq[c] > 0.0) || !std::isfinite(stats[c].RelativeResidual))
      {
        active[c] = false; // breakdown: not SPD, report not converged
      }
    }
    if (!anyActive())
    {
      break;
    }
    precondition(r, z);
    const auto rzNew = Dot3(r, z);
    std::array<double, NC> beta{};
    for (int c = 0; c < NC; ++c)
    {
      beta[c] = active[c] && rz[c] != 0.0 ? rzNew[c] / rz[c] : 0.0;
      if (active[c])
      {
        rz[c] = rzNew[c];
      }
    }
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
    for (long long i = 0; i < static_cast<long long>(n); ++i)
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
