#include "AggregationMultigrid.h"

#include "BlockedKernels.h"
#include "Error.h"
#include "TetMesh.h"

#include <Eigen/SparseCholesky>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>

namespace translucency
{

namespace
{

using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
using ColMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using namespace blocked;

double Since(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
    .count();
}

int Threads(int requested)
{
  return requested > 0 ? requested : omp_get_max_threads();
}

} // namespace

struct AggregationMultigridSolver::Internals
{
  struct Level
  {
    CsrPattern Pattern;
    std::vector<int> MeshIds;
    /// Level l -> l + 1 (empty on the coarsest level).
    std::vector<int> Aggregate;
    /// Members of each aggregate (coarse vertex), ascending fine ids.
    std::vector<int> MemberOffsets, Members;
    /// Fine non-zero k -> its slot in the coarse pattern (Galerkin by summation).
    std::vector<int> CoarseSlot;
    /// Double values (levels >= 1; interleaved, 3 per non-zero).
    std::vector<double> Values;
    /// Single-precision values for smoothing and residuals (interleaved).
    std::vector<float> Single;
    /// 1 / sum_j |a_ij| per vertex and channel (interleaved).
    Eigen::VectorXd InverseL1;
    mutable Eigen::VectorXd B, X, R, D, T, Saved, Sum;
  };
  std::vector<Level> Levels;
  std::array<Eigen::SimplicialLDLT<ColMatrix>, NC> Coarsest;
  ColMatrix CoarsestTemplate; ///< pattern of the coarsest level (values rewritten)
  std::size_t CoarsestFactorNonZeros = 0;
  double VCycleFlops = 0.0; ///< multiply-adds per channel of one V-cycle
};

AggregationMultigridSolver::AggregationMultigridSolver()
  : Internal_(new Internals)
{
}

AggregationMultigridSolver::~AggregationMultigridSolver() = default;

void AggregationMultigridSolver::Setup(
  const DiffusionSystem& system, const TetMesh* mesh, bool patternChanged)
{
  blocked::CheckSystemOnMesh(GetName(), system, mesh);
  const int n = system.NumberOfUnknowns;
  const bool rebuild =
    patternChanged || !Ready_ || Unknowns_ != n || NonZeros_ != system.ColumnIndices.size();
  Ready_ = false;
  if (rebuild)
  {
    const auto start = std::chrono::steady_clock::now();
    BuildHierarchy(system, mesh->GetPoints());
    HierarchyMs_ = Since(start);
    ++Builds_;
  }
  const auto start = std::chrono::steady_clock::now();
  ComputeValues(system);
  ValuesMs_ = Since(start);
  Unknowns_ = n;
  NonZeros_ = system.ColumnIndices.size();
  Ready_ = true;
  ++Setups_;
}

void AggregationMultigridSolver::BuildHierarchy(
  const DiffusionSystem& system, const std::vector<double>& points)
{
  const int nt = Threads(Threads_);
  const int n0 = system.NumberOfUnknowns;
  // Column indices in range and a diagonal in every row (the smoother and the
  // aggregation need both).
  {
    long long badRow = -1;
#pragma omp parallel for num_threads(nt) schedule(static) reduction(max : badRow) if(n0 > ParallelThreshold)
    for (int i = 0; i < n0; ++i)
    {
      bool diagonal = false, ok = system.RowOffsets[i + 1] >= system.RowOffsets[i];
      for (int k = system.RowOffsets[i]; ok && k < system.RowOffsets[i + 1]; ++k)
      {
        const int j = system.ColumnIndices[k];
        ok = j >= 0 && j < n0;
        diagonal = diagonal || j == i;
      }
      if (!ok || !diagonal)
      {
        badRow = std::max<long long>(badRow, i);
      }
    }
    if (badRow >= 0)
    {
      std::ostringstream os;
      os << GetName() << ": row " << badRow
         << " of the system has a column out of range, decreasing offsets or no diagonal entry";
      throw Error(os.str());
    }
  }
  for (int i = 0; i < n0; ++i)
  {
    for (int d = 0; d < 3; ++d)
    {
      if (!std::isfinite(points[3 * static_cast<std::size_t>(i) + d]))
      {
        throw Error(GetName() + ": point " + std::to_string(i) + " has a non-finite coordinate");
      }
    }
  }
  auto& levels = Internal_->Levels;
  levels.clear();
  levels.emplace_back();
  {
    auto& l0 = levels[0];
    l0.Pattern.Size = n0;
    l0.Pattern.Offsets = system.RowOffsets;
    l0.Pattern.Columns = system.ColumnIndices;
    l0.MeshIds.resize(n0);
#pragma omp parallel for num_threads(nt) schedule(static) if(n0 > ParallelThreshold)
    for (int i = 0; i < n0; ++i)
    {
      l0.MeshIds[i] = i;
    }
  }
  const int maxLevels = MaxLevels_ > 0 ? std::min(MaxLevels_, 25) : 25;
  for (int l = 0; static_cast<int>(levels.size()) < maxLevels; ++l)
  {
    Internals::Level& fine = levels[l];
    const CsrPattern& g = fine.Pattern;
    const int n = g.Size;
    if (n <= 1 || (MaxLevels_ <= 0 && n <= CoarsestSize_))
    {
      break;
    }
    // TransCut Sec. 4.1.1: the retained vertices P^{l+1} are an independent
    // set of G^l picked by the hashed random codes (maximal: every dropped
    // vertex has a retained neighbour).
    std::vector<char> retained;
    MultiresHierarchy::IndependentSet(
      g, std::vector<char>(n, 1), l, retained, n > ParallelThreshold ? nt : 1);
    std::vector<int> coarseId(n, -1);
    int nc = 0;
    for (int i = 0; i < n; ++i)
    {
      if (retained[i])
      {
        coarseId[i] = nc++;
      }
    }
    if (nc == n || (MaxLevels_ <= 0 && nc > 0.9 * n))
    {
      break; // coarsening stalls (e.g. isolated vertices)
    }
    // Aggregation: a dropped vertex i joins the retained neighbour j with the
    // largest eq. 16 weight lambda_ij = 1 / |x_i - x_j| (TransCut eq. 16),
    // i.e. the nearest one (ties: the smaller coarse id).
    fine.Aggregate.assign(n, -1);
    const std::vector<int>& meshIds = fine.MeshIds;
#pragma omp parallel for num_threads(nt) schedule(static) if(n > ParallelThreshold)
    for (int i = 0; i < n; ++i)
    {
      if (retained[i])
      {
        fine.Aggregate[i] = coarseId[i];
        continue;
      }
      const double* xi = points.data() + 3 * static_cast<std::size_t>(meshIds[i]);
      double best = std::numeric_limits<double>::infinity();
      int bestId = -1;
      for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
      {
        const int j = g.Columns[k];
        if (!retained[j])
        {
          continue;
        }
        const double* xj = points.data() + 3 * static_cast<std::size_t>(meshIds[j]);
        const double d2 = (xi[0] - xj[0]) * (xi[0] - xj[0]) + (xi[1] - xj[1]) * (xi[1] - xj[1]) +
          (xi[2] - xj[2]) * (xi[2] - xj[2]);
        if (d2 < best || (d2 == best && coarseId[j] < bestId))
        {
          best = d2;
          bestId = coarseId[j];
        }
      }
      fine.Aggregate[i] = bestId; // >= 0: the independent set is maximal
    }
    // Members of each aggregate (counting sort, ascending fine ids).
    fine.MemberOffsets.assign(nc + 1, 0);
    for (int i = 0; i < n; ++i)
    {
      ++fine.MemberOffsets[fine.Aggregate[i] + 1];
    }
    for (int a = 0; a < nc; ++a)
    {
      fine.MemberOffsets[a + 1] += fine.MemberOffsets[a];
    }
    fine.Members.resize(n);
    {
      std::vector<int> fill(fine.MemberOffsets.begin(), fine.MemberOffsets.end() - 1);
      for (int i = 0; i < n; ++i)
      {
        fine.Members[fill[fine.Aggregate[i]]++] = i;
      }
    }
    // Coarse pattern: row a = aggregates adjacent to a member of a (the
    // pattern of P^T A P), per-thread marker arrays, rows sorted.
    Internals::Level coarse;
    coarse.Pattern.Size = nc;
    coarse.Pattern.Offsets.assign(nc + 1, 0);
    coarse.MeshIds.resize(nc);
    std::vector<std::vector<int>> rows(nc);
    const int* agg = fine.Aggregate.data();
#pragma omp parallel num_threads(nt) if(nc > ParallelThreshold)
    {
      std::vector<int> mark(nc, -1);
#pragma omp for schedule(dynamic, 512)
      for (int a = 0; a < nc; ++a)
      {
        std::vector<int>& row = rows[a];
        for (int m = fine.MemberOffsets[a]; m < fine.MemberOffsets[a + 1]; ++m)
        {
          const int i = fine.Members[m];
          if (retained[i])
          {
            coarse.MeshIds[a] = meshIds[i];
          }
          for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
          {
            const int b = agg[g.Columns[k]];
            if (mark[b] != a)
            {
              mark[b] = a;
              row.push_back(b);
            }
          }
        }
        std::sort(row.begin(), row.end());
        coarse.Pattern.Offsets[a + 1] = static_cast<int>(row.size());
      }
    }
    for (int a = 0; a < nc; ++a)
    {
      coarse.Pattern.Offsets[a + 1] += coarse.Pattern.Offsets[a];
    }
    coarse.Pattern.Columns.resize(coarse.Pattern.Offsets.back());
    fine.CoarseSlot.resize(g.Columns.size());
#pragma omp parallel num_threads(nt) if(nc > ParallelThreshold)
    {
      std::vector<int> slot(nc, -1);
#pragma omp for schedule(dynamic, 512)
      for (int a = 0; a < nc; ++a)
      {
        const int begin = coarse.Pattern.Offsets[a];
        std::vector<int>& row = rows[a];
        for (std::size_t q = 0; q < row.size(); ++q)
        {
          coarse.Pattern.Columns[begin + q] = row[q];
          slot[row[q]] = begin + static_cast<int>(q);
        }
        for (int m = fine.MemberOffsets[a]; m < fine.MemberOffsets[a + 1]; ++m)
        {
          const int i = fine.Members[m];
          for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
          {
            fine.CoarseSlot[k] = slot[agg[g.Columns[k]]];
          }
        }
        std::vector<int>().swap(row);
      }
    }
    levels.push_back(std::move(coarse));
  }
  // The coarsest level: symbolic LDL^T analysis once per hierarchy.
  auto& last = levels.back();
  last.Aggregate.clear();
  last.MemberOffsets.clear();
  last.Members.clear();
  last.CoarseSlot.clear();
  const CsrPattern& p = last.Pattern;
  std::vector<double> ones(p.Columns.size(), 1.0);
  Internal_->CoarsestTemplate = ColMatrix(Eigen::Map<const RowMatrix>(
    p.Size, p.Size, static_cast<int>(p.Columns.size()), p.Offsets.data(), p.Columns.data(),
    ones.data()));
  for (int c = 0; c < NC; ++c)
  {
    Internal_->Coarsest[c].analyzePattern(Internal_->CoarsestTemplate);
  }
}

void AggregationMultigridSolver::ComputeValues(const DiffusionSystem& system)
{
  auto& levels = Internal_->Levels;
  const int L = static_cast<int>(levels.size());
  Internal_->VCycleFlops = 0.0;
  const int degree = std::max(1, Degree_);
  std::vector<double> levelFlops(L, 0.0);
  for (int l = 0; l < L; ++l)
  {
    auto& lev = levels[l];
    const CsrPattern& p = lev.Pattern;
    const int n = p.Size;
    const std::size_t nnz = p.Columns.size();
    if (l >= 1)
    {
      // Galerkin P^T A P with piecewise-constant P: coarse (a, b) = sum of the
      // fine a_ij with i in aggregate a, j in aggregate b. Parallel over
      // coarse rows, each summed in a fixed order (deterministic).
      const auto& fine = levels[l - 1];
      const CsrPattern& fp = fine.Pattern;
      lev.Values.assign(3 * nnz, 0.0);
      // Fine values: channel c of non-zero k is f[c][k * fs].
      const double* f[NC];
      std::size_t fs = 3;
      if (l == 1)
      {
        f[0] = system.Values[0].data();
        f[1] = system.Values[1].data();
        f[2] = system.Values[2].data();
        fs = 1;
      }
      else
      {
        f[0] = fine.Values.data();
        f[1] = f[0] + 1;
        f[2] = f[0] + 2;
      }
      double* cv = lev.Values.data();
      const int* slots = fine.CoarseSlot.data();
#pragma omp parallel for schedule(dynamic, 256) if(n > ParallelThreshold)
      for (int a = 0; a < n; ++a)
      {
        for (int m = fine.MemberOffsets[a]; m < fine.MemberOffsets[a + 1]; ++m)
        {
          const int i = fine.Members[m];
          for (int k = fp.Offsets[i]; k < fp.Offsets[i + 1]; ++k)
          {
            double* out = cv + 3 * static_cast<std::size_t>(slots[k]);
            const std::size_t q = static_cast<std::size_t>(k) * fs;
            out[0] += f[0][q];
            out[1] += f[1][q];
            out[2] += f[2][q];
          }
        }
      }
    }
    auto value = [&](std::size_t k, int c)
    { return l == 0 ? system.Values[c][k] : lev.Values[3 * k + c]; };
    // Work vectors (every cycle writes them before reading them).
    for (auto* v : { &lev.B, &lev.X, &lev.R, &lev.D, &lev.T, &lev.Saved, &lev.Sum })
    {
      if (v->size() != 3 * static_cast<long long>(n))
      {
        v->setZero(3 * static_cast<long long>(n));
      }
    }
    if (l == L - 1)
    {
      // Coarsest level: sparse LDL^T per channel (double precision).
      ColMatrix a = Internal_->CoarsestTemplate;
      std::vector<double> vc(nnz);
      for (int c = 0; c < NC; ++c)
      {
        for (std::size_t k = 0; k < nnz; ++k)
        {
          vc[k] = value(k, c);
          if (!std::isfinite(vc[k]))
          {
            std::ostringstream os;
            os << GetName() << ": entry " << k << " (level " << l << ", channel " << c << ") is "
               << vc[k];
            throw Error(os.str());
          }
        }
        a = ColMatrix(Eigen::Map<const RowMatrix>(
          n, n, static_cast<int>(nnz), p.Offsets.data(), p.Columns.data(), vc.data()));
        auto& ldlt = Internal_->Coarsest[c];
        ldlt.factorize(a);
        if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0))
        {
          std::ostringstream os;
          os << GetName() << ": the coarsest-level matrix (level " << l << ", " << n
             << " vertices, channel " << c << ") is not positive definite";
          if (l == 0)
          {
            os << " (the system matrix is not SPD)";
          }
          throw Error(os.str());
        }
        Internal_->CoarsestFactorNonZeros =
          static_cast<std::size_t>(ldlt.matrixL().nestedExpression().nonZeros());
      }
      levelFlops[l] = 2.0 * Internal_->CoarsestFactorNonZeros + 2.0 * n;
      continue;
    }
    // Single-precision values and the l1 diagonal 1 / sum_j |a_ij|, checking
    // that every diagonal entry is positive and every entry finite.
    lev.Single.resize(3 * nnz);
    lev.InverseL1.resize(3 * static_cast<long long>(n));
    long long badRow = -1;
    const double* v[NC];
    std::size_t vs = 3;
    if (l == 0)
    {
      v[0] = system.Values[0].data();
      v[1] = system.Values[1].data();
      v[2] = system.Values[2].data();
      vs = 1;
    }
    else
    {
      v[0] = lev.Values.data();
      v[1] = v[0] + 1;
      v[2] = v[0] + 2;
    }
    float* single = lev.Single.data();
#pragma omp parallel for schedule(static) reduction(max : badRow) if(n > ParallelThreshold)
    for (int i = 0; i < n; ++i)
    {
      double s0 = 0.0, s1 = 0.0, s2 = 0.0;
      bool ok = true;
      for (int k = p.Offsets[i]; k < p.Offsets[i + 1]; ++k)
      {
        const std::size_t q = static_cast<std::size_t>(k) * vs;
        const double a0 = v[0][q], a1 = v[1][q], a2 = v[2][q];
        float* out = single + 3 * static_cast<std::size_t>(k);
        out[0] = static_cast<float>(a0);
        out[1] = static_cast<float>(a1);
        out[2] = static_cast<float>(a2);
        s0 += std::abs(a0);
        s1 += std::abs(a1);
        s2 += std::abs(a2);
        if (p.Columns[k] == i)
        {
          ok = a0 > 0.0 && a1 > 0.0 && a2 > 0.0;
        }
      }
      // A NaN or infinite entry makes its row's sum of |a_ij| non-finite.
      ok = ok && std::isfinite(s0) && std::isfinite(s1) && std::isfinite(s2);
      double* inv = lev.InverseL1.data() + 3 * static_cast<std::size_t>(i);
      inv[0] = s0 > 0.0 ? 1.0 / s0 : 0.0;
      inv[1] = s1 > 0.0 ? 1.0 / s1 : 0.0;
      inv[2] = s2 > 0.0 ? 1.0 / s2 : 0.0;
      if (!ok)
      {
        badRow = std::max<long long>(badRow, i);
      }
    }
    if (badRow >= 0)
    {
      std::ostringstream os;
      os << GetName() << ": row " << badRow << " (level " << l
         << ") has a non-finite entry or a diagonal entry that is not positive (";
      for (int c = 0; c < NC; ++c)
      {
        for (int k = p.Offsets[badRow]; k < p.Offsets[badRow + 1]; ++k)
        {
          if (p.Columns[k] == badRow)
          {
            os << (c ? ", " : "") << "channel " << c << " diagonal " << value(k, c);
          }
        }
      }
      os << "): the matrix is not SPD";
      throw Error(os.str());
    }
    // Multiply-adds per channel of one visit: 2 * degree products with A,
    // restriction and prolongation, ~4 vector operations per Chebyshev step.
    levelFlops[l] = 2.0 * degree * static_cast<double>(nnz) + 2.0 * n + 2.0 * degree * 4.0 * n;
  }
  // Visits of each level per cycle on level 0 (W-cycle: gamma per visit of
  // the finer level, plus gamma - 1 residuals there).
  double visits = 1.0;
  for (int l = 0; l < L; ++l)
  {
    Internal_->VCycleFlops += visits * levelFlops[l];
    const int gamma = l + 1 < L - 1 ? std::max(1, CycleIndex_) : 1;
    if (l + 1 < L)
    {
      Internal_->VCycleFlops += visits * (gamma - 1) *
        (static_cast<double>(levels[l + 1].Pattern.Columns.size()) +
          2.0 * levels[l + 1].Pattern.Size);
    }
    visits *= gamma;
  }
}

void AggregationMultigridSolver::ApplyPreconditioner(
  const Eigen::VectorXd& rhs, Eigen::VectorXd& out) const
{
  auto& levels = Internal_->Levels;
  const int L = static_cast<int>(levels.size());
  const int degree = std::max(1, Degree_);
  const double fraction = std::min(std::max(Fraction_, 1e-3), 0.99);
  const double scale = CorrectionScale_;
  // Chebyshev on D_l1^-1 A over [fraction, 1]: by Gershgorin the spectrum of
  // D_l1^-1 A lies in (0, 1] (|a_ii| + sum_{j != i} |a_ij| = d_i).
  const double theta = 0.5 * (1.0 + fraction), delta = 0.5 * (1.0 - fraction);
  const double sigma = theta / delta;
  auto smooth = [&](const Internals::Level& lev, bool zeroStart)
  {
    const long long m = 3 * static_cast<long long>(lev.Pattern.Size);
    const double* inv = lev.InverseL1.data();
    double* X = lev.X.data();
    double* R = lev.R.data();
    double* D = lev.D.data();
    double* T = lev.T.data();
    const double* B = lev.B.data();
    if (zeroStart)
    {
#pragma omp parallel for schedule(static) if(m > ParallelThreshold)
      for (long long k = 0; k < m; ++k)
      {
        D[k] = inv[k] * B[k] / theta;
        X[k] = D[k];
        R[k] = B[k];
      }
    }
    else
    {
      MultiplyFloat(lev.Pattern, lev.Single.data(), X, T);
#pragma omp parallel for schedule(static) if(m > ParallelThreshold)
      for (long long k = 0; k < m; ++k)
      {
        R[k] = B[k] - T[k];
        D[k] = inv[k] * R[k] / theta;
        X[k] += D[k];
      }
    }
    double rho = 1.0 / sigma;
    for (int step = 2; step <= degree; ++step)
    {
      MultiplyFloat(lev.Pattern, lev.Single.data(), D, T);
      const double rhoNew = 1.0 / (2.0 * sigma - rho);
      const double a = rhoNew * rho, b = 2.0 * rhoNew / delta;
      rho = rhoNew;
#pragma omp parallel for schedule(static) if(m > ParallelThreshold)
      for (long long k = 0; k < m; ++k)
      {
        R[k] -= T[k];
        D[k] = a * D[k] + b * inv[k] * R[k];
        X[k] += D[k];
      }
    }
  };

  // One cycle on level l: X_l ~ A_l^-1 B_l.
  std::function<void(int)> cycle = [&](int l)
  {
    const auto& lev = levels[l];
    if (l == L - 1)
    {
      SolveInterleaved(Internal_->Coarsest.data(), lev.Pattern.Size, lev.B.data(), lev.X.data());
      return;
    }
    // Pre-smoothing from zero, residual, restriction b_c = P^T r (sums over
    // the aggregates).
    smooth(lev, true);
    MultiplyFloat(lev.Pattern, lev.Single.data(), lev.X.data(), lev.T.data());
    const auto& coarse = levels[l + 1];
    const int nc = coarse.Pattern.Size;
    const double* B = lev.B.data();
    const double* T = lev.T.data();
    double* cb = coarse.B.data();
#pragma omp parallel for schedule(static) if(nc > ParallelThreshold)
    for (int a = 0; a < nc; ++a)
    {
      double s0 = 0.0, s1 = 0.0, s2 = 0.0;
      for (int m = lev.MemberOffsets[a]; m < lev.MemberOffsets[a + 1]; ++m)
      {
        // r = b - A x of the member, summed without storing r.
        const std::size_t q = 3 * static_cast<std::size_t>(lev.Members[m]);
        s0 += B[q] - T[q];
        s1 += B[q + 1] - T[q + 1];
        s2 += B[q + 2] - T[q + 2];
      }
      cb[3 * static_cast<std::size_t>(a)] = s0;
      cb[3 * static_cast<std::size_t>(a) + 1] = s1;
      cb[3 * static_cast<std::size_t>(a) + 2] = s2;
    }
    // Coarse problem: one cycle, or (levels below level 0 that are not the
    // coarsest) `gamma` cycles as a stationary iteration from zero (W-cycle
    // for gamma = 2: still a fixed symmetric operator, so CG stays valid).
    const int gamma = l + 1 < L - 1 ? std::max(1, CycleIndex_) : 1;
    if (gamma == 1)
    {
      cycle(l + 1);
    }
    else
    {
      coarse.Saved = coarse.B;
      coarse.Sum.setZero(coarse.B.size());
      for (int g = 0; g < gamma; ++g)
      {
        if (g > 0)
        {
          MultiplyFloat(coarse.Pattern, coarse.Single.data(), coarse.Sum.data(), coarse.T.data());
          coarse.B = coarse.Saved - coarse.T;
        }
        cycle(l + 1);
        coarse.Sum += coarse.X;
      }
      coarse.X = coarse.Sum;
    }
    // Coarse correction x += s P x_c, post-smoothing.
    {
      const int n = lev.Pattern.Size;
      const double* xc = coarse.X.data();
      double* x = lev.X.data();
      const int* agg = lev.Aggregate.data();
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
      for (int i = 0; i < n; ++i)
      {
        const double* c = xc + 3 * static_cast<std::size_t>(agg[i]);
        x[3 * static_cast<std::size_t>(i)] += scale * c[0];
        x[3 * static_cast<std::size_t>(i) + 1] += scale * c[1];
        x[3 * static_cast<std::size_t>(i) + 2] += scale * c[2];
      }
    }
    smooth(lev, false);
  };
  levels[0].B = rhs;
  cycle(0);
  out = levels[0].X;
}

void AggregationMultigridSolver::CheckSystem(const DiffusionSystem& system) const
{
  blocked::CheckSolveMatchesSetup(GetName(), system, Ready_, Unknowns_, NonZeros_);
}

bool AggregationMultigridSolver::Solve(const DiffusionSystem& system,
  std::array<Eigen::VectorXd, NumberOfChannels>& x, bool warmStart,
  std::array<LinearSolveStats, NumberOfChannels>& stats)
{
  CheckSystem(system);
  const int n = system.NumberOfUnknowns;
  Eigen::VectorXd xi = Eigen::VectorXd::Zero(3 * static_cast<long long>(n));
  if (warmStart && x[0].size() == n && x[1].size() == n && x[2].size() == n)
  {
    Interleave(x, xi);
  }
  const double flops =
    static_cast<double>(system.ColumnIndices.size()) + 5.0 * n + Internal_->VCycleFlops;
  const bool done = BlockedPCG(
    system, [this](const Eigen::VectorXd& r, Eigen::VectorXd& z) { ApplyPreconditioner(r, z); },
    xi, RelTol_, MaxIter_, stats, flops, Progress_);
  Deinterleave(xi, x);
  return done;
}

int AggregationMultigridSolver::GetNumberOfLevels() const
{
  return static_cast<int>(Internal_->Levels.size());
}

int AggregationMultigridSolver::GetLevelSize(int l) const
{
  return Internal_->Levels.at(l).Pattern.Size;
}

const std::vector<int>& AggregationMultigridSolver::GetAggregates(int l) const
{
  return Internal_->Levels.at(l).Aggregate;
}

const std::vector<int>& AggregationMultigridSolver::GetMeshIds(int l) const
{
  return Internal_->Levels.at(l).MeshIds;
}

const CsrPattern& AggregationMultigridSolver::GetPattern(int l) const
{
  return Internal_->Levels.at(l).Pattern;
}

double AggregationMultigridSolver::GetOperatorComplexity() const
{
  if (Internal_->Levels.empty())
  {
    return 0.0;
  }
  double total = 0.0;
  for (const auto& lev : Internal_->Levels)
  {
    total += static_cast<double>(lev.Pattern.Columns.size());
  }
  return total / std::max<double>(1.0, Internal_->Levels[0].Pattern.Columns.size());
}

Eigen::SparseMatrix<double, Eigen::RowMajor, int> AggregationMultigridSolver::GetCoarseMatrix(
  int l, int c) const
{
  if (l < 1)
  {
    throw Error(GetName() + ": GetCoarseMatrix needs a level >= 1");
  }
  const auto& lev = Internal_->Levels.at(l);
  const CsrPattern& p = lev.Pattern;
  std::vector<double> v(p.Columns.size());
  for (std::size_t k = 0; k < v.size(); ++k)
  {
    v[k] = lev.Values.at(3 * k + c);
  }
  return Eigen::Map<const RowMatrix>(
    p.Size, p.Size, static_cast<int>(v.size()), p.Offsets.data(), p.Columns.data(), v.data());
}

std::size_t AggregationMultigridSolver::GetMemoryBytes() const
{
  std::size_t bytes = 0;
  for (const auto& lev : Internal_->Levels)
  {
    bytes += (lev.Pattern.Offsets.size() + lev.Pattern.Columns.size() + lev.MeshIds.size() +
               lev.Aggregate.size() + lev.MemberOffsets.size() + lev.Members.size() +
               lev.CoarseSlot.size()) *
        sizeof(int) +
      lev.Values.size() * sizeof(double) + lev.Single.size() * sizeof(float) +
      6 * lev.InverseL1.size() * sizeof(double);
  }
  bytes += NC * Internal_->CoarsestFactorNonZeros * (sizeof(double) + sizeof(int));
  return bytes;
}

} // namespace translucency
