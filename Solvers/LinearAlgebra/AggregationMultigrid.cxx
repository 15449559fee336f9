#include "AggregationMultigrid.h"

#include "BlockedKernels.h"
#include "Error.h"
#include "TetMesh.h"
#include "Timer.h"

#include <Eigen/SparseCholesky>

#include <omp.h>

#include <algorithm>
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

int Threads(int requested)
{
  return requested > 0 ? requested : omp_get_max_threads();
}

/// Row i of a level's smoother data from its double values (channel c of
/// non-zero k is v[c][k * vs]): the single-precision copy of the row
/// (interleaved, 3 per non-zero) and the l1 diagonal 1 / sum_j |a_ij| per
/// channel. Returns false if the row has a non-finite entry or a diagonal
/// entry that is not positive.
bool SmootherRow(
  const CsrPattern& p, const double* const* v, std::size_t vs, int i, float* single, float* inverse)
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
  float* inv = inverse + 3 * static_cast<std::size_t>(i);
  inv[0] = s0 > 0.0 ? static_cast<float>(1.0 / s0) : 0.0f;
  inv[1] = s1 > 0.0 ? static_cast<float>(1.0 / s1) : 0.0f;
  inv[2] = s2 > 0.0 ? static_cast<float>(1.0 / s2) : 0.0f;
  return ok;
}

/// The error of a row that SmootherRow rejected (row `row` of level `l`).
[[noreturn]] void ThrowNotSpd(const std::string& name, const CsrPattern& p, int l, int row,
  const double* const* v, std::size_t vs)
{
  std::ostringstream os;
  os << name << ": row " << row << " (level " << l
     << ") has a non-finite entry or a diagonal entry that is not positive (";
  for (int c = 0; c < NC; ++c)
  {
    for (int k = p.Offsets[row]; k < p.Offsets[row + 1]; ++k)
    {
      if (p.Columns[k] == row)
      {
        os << (c ? ", " : "") << "channel " << c << " diagonal " << v[c][static_cast<std::size_t>(k) * vs];
      }
    }
  }
  os << "): the matrix is not SPD";
  throw Error(os.str());
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
    std::vector<float> InverseL1;
    /// Work vectors of the cycle, single precision, interleaved: right-hand
    /// side B (levels >= 1; level 0 reads CG's residual), iterate X, output
    /// buffer Y of the fused post-smoothing (swapped with X), residual R;
    /// D, T only for smoother degrees >= 2; Saved, Sum for the W-cycle.
    mutable std::vector<float> B, X, Y, R, D, T, Saved, Sum;
  };
  std::vector<Level> Levels;
  /// BuildHierarchy: the aggregates of level `fine` (each dropped vertex
  /// joins its nearest retained neighbour, coarse ids `coarseId`) and their
  /// members.
  static void BuildAggregates(Level& fine, const std::vector<char>& retained,
    const std::vector<int>& coarseId, int nc, const std::vector<double>& points, int nt);
  /// BuildHierarchy: the pattern of the coarse level (P^T A P) and the slot
  /// of each fine non-zero in it.
  static Level CoarsePattern(Level& fine, const std::vector<char>& retained, int nc, int nt);
  /// ComputeValues: the Galerkin values of level l >= 1 (interleaved).
  static void GalerkinValues(const DiffusionSystem& system, int l, std::vector<Level>& levels);
  std::array<Eigen::SimplicialLDLT<ColMatrix>, NC> Coarsest;
  ColMatrix CoarsestTemplate; ///< pattern of the coarsest level (values rewritten)
  std::size_t CoarsestFactorNonZeros = 0;
  double VCycleFlops = 0.0; ///< multiply-adds per channel of one V-cycle
  mutable blocked::FusedPCGWorkspace Work; ///< CG vectors, kept between solves
  SolutionRecycler Recycler; ///< earlier solutions (SetRecycledSolutions)
  /// Level-0 rows changed by row updates since the last full values set-up
  /// (1 = changed), and their count.
  std::vector<char> StaleRows;
  int StaleCount = 0;

  // The cycle (single-precision vectors; see ApplyPreconditioner).
  struct Cycle;
  /// Visit of level l: out ~ A_l^-1 b (one cycle); returns b.out per
  /// channel if `dot` (chunked, deterministic), else zeros.
  template <typename TB, typename TO>
  std::array<double, NC> Visit(int l, const TB* b, TO* out, bool dot, const Cycle& cy) const;
  /// X = Chebyshev smoothing of A x = b from x = 0.
  template <typename TB>
  void PreSmooth(const Level& lev, const TB* b, const Cycle& cy) const;
  /// out = Chebyshev smoothing from X (fused single pass for degree 1).
  template <typename TB, typename TO>
  std::array<double, NC> PostSmooth(
    const Level& lev, const TB* b, TO* out, bool dot, const Cycle& cy) const;
  /// Chebyshev steps 2..degree on X, R, D.
  void ChebyshevSteps(const Level& lev, const Cycle& cy) const;
  /// out = b - A x (single-precision values of level `lev`; b == nullptr: A x).
  template <typename TB>
  void Residual(const Level& lev, const TB* b, const float* x, float* out) const;
};

AggregationMultigridSolver::AggregationMultigridSolver()
  : Internal_(new Internals)
{
}

AggregationMultigridSolver::~AggregationMultigridSolver() = default;

void AggregationMultigridSolver::CheckSetup(
  const DiffusionSystem& system, const TetMesh* mesh) const
{
  blocked::CheckSystemOnMesh(GetName(), system, mesh);
}

void AggregationMultigridSolver::SetupStructure(const DiffusionSystem& system, const TetMesh* mesh)
{
  Internal_->Recycler.Clear();
  const auto start = Clock::now();
  BuildHierarchy(system, mesh->GetPoints());
  HierarchyMs_ = MillisecondsSince(start);
  ++Builds_;
}

void AggregationMultigridSolver::SetupValues(const DiffusionSystem& system, const TetMesh*)
{
  Internal_->Recycler.Clear();
  const auto start = Clock::now();
  ComputeValues(system);
  ValuesMs_ = MillisecondsSince(start);
  ++Setups_;
}

void AggregationMultigridSolver::SetupRows(
  const DiffusionSystem& system, const TetMesh* mesh, const std::vector<int>& rows)
{
  Internal_->Recycler.Clear();
  const auto start = Clock::now();
  auto& levels = Internal_->Levels;
  const int n = system.NumberOfUnknowns;
  auto& stale = Internal_->StaleRows;
  if (levels.size() < 2 || stale.size() != static_cast<std::size_t>(n))
  {
    SetupValues(system, mesh); // one level: the direct solve needs new values
    return;
  }
  // Distinct new rows (the marker is cleared again below).
  std::vector<int> fresh;
  fresh.reserve(rows.size());
  std::vector<char> seen(n, 0);
  for (const int i : rows)
  {
    if (!seen[i])
    {
      seen[i] = 1;
      fresh.push_back(i);
    }
  }
  int newlyStale = 0;
  for (const int i : fresh)
  {
    newlyStale += stale[i] ? 0 : 1;
  }
  if (Internal_->StaleCount + newlyStale > CoarseRefreshFraction_ * n)
  {
    SetupValues(system, mesh);
    return;
  }
  auto& l0 = levels[0];
  const double* v[NC] = { system.Values[0].data(), system.Values[1].data(),
    system.Values[2].data() };
  const int m = static_cast<int>(fresh.size());
  long long badRow = -1;
#pragma omp parallel for num_threads(Threads(Threads_)) schedule(static) reduction(max : badRow) if(m > ParallelThreshold)
  for (int k = 0; k < m; ++k)
  {
    const int i = fresh[k];
    if (!SmootherRow(l0.Pattern, v, 1, i, l0.Single.data(), l0.InverseL1.data()))
    {
      badRow = std::max<long long>(badRow, i);
    }
  }
  if (badRow >= 0)
  {
    // The rows before the bad one are refreshed; the solver is not ready
    // (LinearSolver::SetupChangedRows) until the next Setup.
    ThrowNotSpd(GetName(), l0.Pattern, 0, static_cast<int>(badRow), v, 1);
  }
  for (const int i : fresh)
  {
    Internal_->StaleCount += stale[i] ? 0 : 1;
    stale[i] = 1;
  }
  ValuesMs_ = MillisecondsSince(start);
  ++RowSetups_;
}

void AggregationMultigridSolver::SetupSharedHierarchy(
  const AggregationMultigridSolver& donor, const DiffusionSystem& system, const TetMesh* mesh)
{
  CheckSetup(system, mesh);
  Ready_ = false; // a set-up that throws leaves the solver not ready
  const auto& from = donor.Internal_->Levels;
  if (&donor == this)
  {
    throw Error(GetName() + ": SetupSharedHierarchy needs another solver as the donor");
  }
  if (!donor.Ready_ || from.empty())
  {
    throw Error(GetName() + ": SetupSharedHierarchy: the donor has no successful Setup");
  }
  const CsrPattern& p = from[0].Pattern;
  if (p.Size != system.NumberOfUnknowns || p.Offsets != system.RowOffsets ||
    p.Columns != system.ColumnIndices)
  {
    throw Error(GetName() +
      ": SetupSharedHierarchy: the system's pattern is not the donor's (a shared hierarchy "
      "needs the same unknowns and non-zeros)");
  }
  Internal_->Recycler.Clear();
  const auto start = Clock::now();
  // The structure of every level (what BuildHierarchy makes); the values,
  // smoother data and work vectors are this solver's (SetupValues).
  auto& levels = Internal_->Levels;
  levels.assign(from.size(), Internals::Level());
  for (std::size_t l = 0; l < from.size(); ++l)
  {
    levels[l].Pattern = from[l].Pattern;
    levels[l].MeshIds = from[l].MeshIds;
    levels[l].Aggregate = from[l].Aggregate;
    levels[l].MemberOffsets = from[l].MemberOffsets;
    levels[l].Members = from[l].Members;
    levels[l].CoarseSlot = from[l].CoarseSlot;
  }
  // The coarsest level's symbolic LDL^T analysis (Eigen's solvers are not
  // copyable; the level is small).
  Internal_->CoarsestTemplate = donor.Internal_->CoarsestTemplate;
  for (int c = 0; c < NC; ++c)
  {
    Internal_->Coarsest[c].analyzePattern(Internal_->CoarsestTemplate);
  }
  HierarchyMs_ = MillisecondsSince(start);
  ++SharedSetups_;
  SetupValues(system, mesh);
  Unknowns_ = system.NumberOfUnknowns;
  NonZeros_ = system.ColumnIndices.size();
  Ready_ = true;
}

int AggregationMultigridSolver::GetNumberOfStaleRows() const
{
  return Internal_->StaleCount;
}


void AggregationMultigridSolver::Internals::BuildAggregates(Level& fine, const std::vector<char>& retained,
  const std::vector<int>& coarseId, int nc, const std::vector<double>& points, int nt)
{
  const CsrPattern& g = fine.Pattern;
  const int n = g.Size;
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
}

AggregationMultigridSolver::Internals::Level AggregationMultigridSolver::Internals::CoarsePattern(
  Level& fine, const std::vector<char>& retained, int nc, int nt)
{
  const CsrPattern& g = fine.Pattern;
  const std::vector<int>& meshIds = fine.MeshIds;
  // Coarse pattern: row a = aggregates adjacent to a member of a (the
  // pattern of P^T A P), per-thread marker arrays, rows sorted.
  Level coarse;
  coarse.Pattern.Size = nc;
  coarse.Pattern.Offsets.assign(nc + 1, 0);
  coarse.MeshIds.resize(nc);
  // Rows are gathered into one buffer per thread (no allocation per row):
  // row a is rowBuffer[rowThread[a]][rowStart[a] ...] (Offsets[a + 1] long).
  const int* agg = fine.Aggregate.data();
  const int rowThreads = nc > ParallelThreshold ? nt : 1;
  std::vector<std::vector<int>> rowBuffer(rowThreads);
  std::vector<int> rowStart(nc), rowThread(nc);
#pragma omp parallel num_threads(rowThreads)
  {
    const int tid = omp_get_thread_num();
    std::vector<int>& buffer = rowBuffer[tid];
    buffer.reserve(g.Columns.size() / rowThreads / 4 + 16);
    std::vector<int> mark(nc, -1);
#pragma omp for schedule(dynamic, 512)
    for (int a = 0; a < nc; ++a)
    {
      const std::size_t start = buffer.size();
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
            buffer.push_back(b);
          }
        }
      }
      std::sort(buffer.begin() + start, buffer.end());
      rowStart[a] = static_cast<int>(start);
      rowThread[a] = tid;
      coarse.Pattern.Offsets[a + 1] = static_cast<int>(buffer.size() - start);
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
      const int length = coarse.Pattern.Offsets[a + 1] - begin;
      const int* row = rowBuffer[rowThread[a]].data() + rowStart[a];
      for (int q = 0; q < length; ++q)
      {
        coarse.Pattern.Columns[begin + q] = row[q];
        slot[row[q]] = begin + q;
      }
      for (int m = fine.MemberOffsets[a]; m < fine.MemberOffsets[a + 1]; ++m)
      {
        const int i = fine.Members[m];
        for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
        {
          fine.CoarseSlot[k] = slot[agg[g.Columns[k]]];
        }
      }
    }
  }
  return coarse;
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
    Internals::BuildAggregates(fine, retained, coarseId, nc, points, nt);
    levels.push_back(Internals::CoarsePattern(fine, retained, nc, nt));
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

/// ComputeValues: level l >= 1's values by Galerkin P^T A P with
/// piecewise-constant P: coarse (a, b) = sum of the fine a_ij with i in
/// aggregate a, j in aggregate b. Parallel over coarse rows, each summed in
/// a fixed order (deterministic). Level 1 reads the system's values.
void AggregationMultigridSolver::Internals::GalerkinValues(
  const DiffusionSystem& system, int l, std::vector<Level>& levels)
{
  auto& lev = levels[l];
  const int n = lev.Pattern.Size;
  const std::size_t nnz = lev.Pattern.Columns.size();
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

void AggregationMultigridSolver::ComputeValues(const DiffusionSystem& system)
{
  auto& levels = Internal_->Levels;
  Internal_->StaleRows.assign(system.NumberOfUnknowns, 0);
  Internal_->StaleCount = 0;
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
      Internals::GalerkinValues(system, l, levels);
    }
    auto value = [&](std::size_t k, int c)
    { return l == 0 ? system.Values[c][k] : lev.Values[3 * k + c]; };
    // Work vectors (every cycle writes them before reading them; D and T
    // are sized by the cycle if the smoother degree is >= 2).
    for (auto* v : { &lev.B, &lev.X, &lev.Y, &lev.R, &lev.Saved, &lev.Sum })
    {
      v->resize(3 * static_cast<std::size_t>(n));
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
    lev.InverseL1.resize(3 * static_cast<std::size_t>(n));
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
    float* inverse = lev.InverseL1.data();
#pragma omp parallel for schedule(static) reduction(max : badRow) if(n > ParallelThreshold)
    for (int i = 0; i < n; ++i)
    {
      if (!SmootherRow(p, v, vs, i, single, inverse))
      {
        badRow = std::max<long long>(badRow, i);
      }
    }
    if (badRow >= 0)
    {
      ThrowNotSpd(GetName(), p, l, static_cast<int>(badRow), v, vs);
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

/// Constants of one cycle (from the solver's options at the time of the call).
struct AggregationMultigridSolver::Internals::Cycle
{
  int Degree;
  /// Chebyshev interval [fraction, 1] of D_l1^-1 A: centre, half-width.
  double Theta, Delta;
  double Scale;
  int CycleIndex;
};

template <typename TB>
void AggregationMultigridSolver::Internals::PreSmooth(
  const Level& lev, const TB* b, const Cycle& cy) const
{
  const long long m = 3 * static_cast<long long>(lev.Pattern.Size);
  const float* inv = lev.InverseL1.data();
  float* X = lev.X.data();
  const double w = 1.0 / cy.Theta;
  // First Chebyshev step from zero: x = D^-1 b / theta (no residual needed).
#pragma omp parallel for schedule(static) if(m > 3 * ParallelThreshold)
  for (long long k = 0; k < m; ++k)
  {
    X[k] = static_cast<float>(w * inv[k] * static_cast<double>(b[k]));
  }
  if (cy.Degree >= 2)
  {
    // R = b, D = X; then the Chebyshev recurrence.
    lev.R.resize(m);
    lev.D.resize(m);
    float* R = lev.R.data();
    float* D = lev.D.data();
#pragma omp parallel for schedule(static) if(m > 3 * ParallelThreshold)
    for (long long k = 0; k < m; ++k)
    {
      R[k] = static_cast<float>(b[k]);
      D[k] = X[k];
    }
    ChebyshevSteps(lev, cy);
  }
}

void AggregationMultigridSolver::Internals::ChebyshevSteps(const Level& lev, const Cycle& cy) const
{
  const int n = lev.Pattern.Size;
  const long long m = 3 * static_cast<long long>(n);
  const float* inv = lev.InverseL1.data();
  float* X = lev.X.data();
  float* R = lev.R.data();
  float* D = lev.D.data();
  lev.T.resize(m);
  float* T = lev.T.data();
  const double sigma = cy.Theta / cy.Delta;
  double rho = 1.0 / sigma;
  for (int step = 2; step <= cy.Degree; ++step)
  {
    Residual(lev, static_cast<const float*>(nullptr), D, T); // T = A D
    const double rhoNew = 1.0 / (2.0 * sigma - rho);
    const double a = rhoNew * rho, bc = 2.0 * rhoNew / cy.Delta;
    rho = rhoNew;
#pragma omp parallel for schedule(static) if(m > 3 * ParallelThreshold)
    for (long long k = 0; k < m; ++k)
    {
      const double r = static_cast<double>(R[k]) - T[k];
      const double d = a * D[k] + bc * inv[k] * r;
      R[k] = static_cast<float>(r);
      D[k] = static_cast<float>(d);
      X[k] = static_cast<float>(X[k] + d);
    }
  }
}

template <typename TB>
void AggregationMultigridSolver::Internals::Residual(
  const Level& lev, const TB* b, const float* x, float* out) const
{
  const int n = lev.Pattern.Size;
  const int* ro = lev.Pattern.Offsets.data();
  const int* ci = lev.Pattern.Columns.data();
  const float* v = lev.Single.data();
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
  for (int i = 0; i < n; ++i)
  {
    double ax[3];
    FloatRow(ro, ci, v, x, i, ax);
    const std::size_t q = 3 * static_cast<std::size_t>(i);
    for (int c = 0; c < NC; ++c)
    {
      // b == nullptr: out = A x.
      out[q + c] = static_cast<float>(b ? static_cast<double>(b[q + c]) - ax[c] : ax[c]);
    }
  }
}

template <typename TB, typename TO>
std::array<double, NC> AggregationMultigridSolver::Internals::PostSmooth(
  const Level& lev, const TB* b, TO* out, bool dot, const Cycle& cy) const
{
  const int n = lev.Pattern.Size;
  const float* inv = lev.InverseL1.data();
  const double w = 1.0 / cy.Theta;
  float* X = lev.X.data();
  if (cy.Degree == 1)
  {
    // One fused pass: out = x + D^-1 (b - A x) / theta, row by row (x is only
    // read, so no residual or update vectors are stored), and b.out.
    const int* ro = lev.Pattern.Offsets.data();
    const int* ci = lev.Pattern.Columns.data();
    const float* v = lev.Single.data();
    return ChunkedSums<NC>(n,
      [&](long long begin, long long end, double* sums)
      {
        double s[NC] = { 0.0, 0.0, 0.0 };
        for (long long i = begin; i < end; ++i)
        {
          double ax[3];
          FloatRow(ro, ci, v, static_cast<const float*>(X), static_cast<int>(i), ax);
          const std::size_t q = 3 * static_cast<std::size_t>(i);
          for (int c = 0; c < NC; ++c)
          {
            const double bi = static_cast<double>(b[q + c]);
            const TO o =
              static_cast<TO>(static_cast<double>(X[q + c]) + w * inv[q + c] * (bi - ax[c]));
            out[q + c] = o;
            s[c] += bi * static_cast<double>(o);
          }
        }
        if (dot)
        {
          for (int c = 0; c < NC; ++c)
          {
            sums[c] += s[c];
          }
        }
      });
  }
  // Degree >= 2: R = b - A X, D = D^-1 R / theta, X += D, the recurrence,
  // then out = X.
  const long long m = 3 * static_cast<long long>(n);
  lev.R.resize(m);
  lev.D.resize(m);
  float* R = lev.R.data();
  float* D = lev.D.data();
  Residual(lev, b, X, R);
#pragma omp parallel for schedule(static) if(m > 3 * ParallelThreshold)
  for (long long k = 0; k < m; ++k)
  {
    const double d = w * inv[k] * static_cast<double>(R[k]);
    D[k] = static_cast<float>(d);
    X[k] = static_cast<float>(X[k] + d);
  }
  ChebyshevSteps(lev, cy);
  return ChunkedSums<NC>(n,
    [&](long long begin, long long end, double* sums)
    {
      double s[NC] = { 0.0, 0.0, 0.0 };
      for (long long k = 3 * begin; k < 3 * end; ++k)
      {
        out[k] = static_cast<TO>(X[k]);
        s[k % 3] += static_cast<double>(b[k]) * static_cast<double>(X[k]);
      }
      if (dot)
      {
        for (int c = 0; c < NC; ++c)
        {
          sums[c] += s[c];
        }
      }
    });
}

template <typename TB, typename TO>
std::array<double, NC> AggregationMultigridSolver::Internals::Visit(
  int l, const TB* b, TO* out, bool dot, const Cycle& cy) const
{
  const int L = static_cast<int>(Levels.size());
  const Level& lev = Levels[l];
  if (l == L - 1)
  {
    SolveInterleaved(Coarsest.data(), lev.Pattern.Size, b, out);
    // A one-level hierarchy (a tiny system) is solved directly; CG still
    // needs b.out.
    std::array<double, NC> sums{};
    if (dot)
    {
      const long long m = 3 * static_cast<long long>(lev.Pattern.Size);
      for (long long k = 0; k < m; ++k)
      {
        sums[k % 3] += static_cast<double>(b[k]) * static_cast<double>(out[k]);
      }
    }
    return sums;
  }
  // Pre-smoothing from zero, residual, restriction b_c = P^T r (sums over
  // the aggregates).
  PreSmooth(lev, b, cy);
  Residual(lev, b, static_cast<const float*>(lev.X.data()), lev.R.data());
  const Level& coarse = Levels[l + 1];
  {
    const int nc = coarse.Pattern.Size;
    const float* R = lev.R.data();
    float* cb = coarse.B.data();
#pragma omp parallel for schedule(static) if(nc > ParallelThreshold)
    for (int a = 0; a < nc; ++a)
    {
      double s0 = 0.0, s1 = 0.0, s2 = 0.0;
      for (int m = lev.MemberOffsets[a]; m < lev.MemberOffsets[a + 1]; ++m)
      {
        const std::size_t q = 3 * static_cast<std::size_t>(lev.Members[m]);
        s0 += R[q];
        s1 += R[q + 1];
        s2 += R[q + 2];
      }
      cb[3 * static_cast<std::size_t>(a)] = static_cast<float>(s0);
      cb[3 * static_cast<std::size_t>(a) + 1] = static_cast<float>(s1);
      cb[3 * static_cast<std::size_t>(a) + 2] = static_cast<float>(s2);
    }
  }
  // Coarse problem: one cycle, or (levels below level 0 that are not the
  // coarsest) `gamma` cycles as a stationary iteration from zero (W-cycle
  // for gamma = 2: still a fixed symmetric operator, so CG stays valid):
  // x_c = sum of the corrections, each from the residual b_c - A_c x_c.
  const int gamma = l + 1 < L - 1 ? std::max(1, cy.CycleIndex) : 1;
  auto visitCoarse = [&]()
  {
    Visit(l + 1, static_cast<const float*>(coarse.B.data()), coarse.Y.data(), false, cy);
    coarse.X.swap(coarse.Y);
  };
  for (int g = 0; g < gamma; ++g)
  {
    if (g > 0)
    {
      Residual(coarse, static_cast<const float*>(coarse.Saved.data()),
        static_cast<const float*>(coarse.Sum.data()), coarse.B.data());
    }
    visitCoarse();
    if (g > 0)
    {
      float* xc = coarse.X.data();
      const float* sum = coarse.Sum.data();
      const long long mc = static_cast<long long>(coarse.X.size());
#pragma omp parallel for schedule(static) if(mc > 3 * ParallelThreshold)
      for (long long k = 0; k < mc; ++k)
      {
        xc[k] += sum[k];
      }
    }
    if (g == 0 && gamma > 1)
    {
      coarse.Saved.swap(coarse.B); // keep b_c
    }
    if (g + 1 < gamma)
    {
      coarse.Sum.swap(coarse.X);
    }
  }
  // Coarse correction x += s P x_c, post-smoothing into out.
  {
    const int n = lev.Pattern.Size;
    const float* xc = coarse.X.data();
    float* x = lev.X.data();
    const int* agg = lev.Aggregate.data();
    const double scale = cy.Scale;
#pragma omp parallel for schedule(static) if(n > ParallelThreshold)
    for (int i = 0; i < n; ++i)
    {
      const float* c = xc + 3 * static_cast<std::size_t>(agg[i]);
      float* xi = x + 3 * static_cast<std::size_t>(i);
      xi[0] = static_cast<float>(xi[0] + scale * c[0]);
      xi[1] = static_cast<float>(xi[1] + scale * c[1]);
      xi[2] = static_cast<float>(xi[2] + scale * c[2]);
    }
  }
  return PostSmooth(lev, b, out, dot, cy);
}

std::array<double, NC> AggregationMultigridSolver::Precondition(const double* r, double* z) const
{
  Internals::Cycle cy;
  cy.Degree = std::max(1, Degree_);
  const double fraction = std::min(std::max(Fraction_, 1e-3), 0.99);
  // Chebyshev on D_l1^-1 A over [fraction, 1]: by Gershgorin the spectrum of
  // D_l1^-1 A lies in (0, 1] (|a_ii| + sum_{j != i} |a_ij| = d_i).
  cy.Theta = 0.5 * (1.0 + fraction);
  cy.Delta = 0.5 * (1.0 - fraction);
  cy.Scale = CorrectionScale_;
  cy.CycleIndex = CycleIndex_;
  return Internal_->Visit(0, r, z, true, cy);
}

void AggregationMultigridSolver::ApplyPreconditioner(
  const Eigen::VectorXd& rhs, Eigen::VectorXd& out) const
{
  out.resize(rhs.size());
  Precondition(rhs.data(), out.data());
}

void AggregationMultigridSolver::ApplyPreconditioner(const double* r, double* z) const
{
  if (!Ready_ || Internal_->Levels.empty())
  {
    throw Error(GetName() + ": ApplyPreconditioner() before a successful Setup()");
  }
  Precondition(r, z);
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
  const double flops =
    static_cast<double>(system.ColumnIndices.size()) + 5.0 * n + Internal_->VCycleFlops;
  const float* single = UsesSinglePrecisionProduct() ? Internal_->Levels[0].Single.data() : nullptr;
  // Recycled solutions in single precision only with the single-precision
  // products (their floor); in double precision always.
  SolutionRecycler* recycler = (single || Internal_->Recycler.GetDoublePrecision()) &&
      Internal_->Recycler.GetCapacity() > 0
    ? &Internal_->Recycler
    : nullptr;
  blocked::ChangeRule change;
  change.Rows = &ChangeRows_;
  change.Tol = ChangeTol_;
  if (change.IsOn())
  {
    change.Check(n, GetName());
  }
  return FusedBlockedPCG(
    system, single, [this](const double* r, double* z) { return Precondition(r, z); }, x,
    warmStart, RelTol_, MaxIter_, stats, flops, Progress_, Internal_->Work, recycler, MinIter_,
    &change);
}

void AggregationMultigridSolver::SetRecycledSolutions(int k)
{
  Internal_->Recycler.SetCapacity(k);
}

int AggregationMultigridSolver::GetRecycledSolutions() const
{
  return Internal_->Recycler.GetCapacity();
}

void AggregationMultigridSolver::ClearRecycledSolutions()
{
  Internal_->Recycler.Clear();
}

void AggregationMultigridSolver::SetRecycleInDoublePrecision(bool on)
{
  Internal_->Recycler.SetDoublePrecision(on);
}

bool AggregationMultigridSolver::GetRecycleInDoublePrecision() const
{
  return Internal_->Recycler.GetDoublePrecision();
}

bool AggregationMultigridSolver::UsesSinglePrecisionProduct() const
{
  return RelTol_ >= SingleProductTol_ && !Internal_->Levels.empty() &&
    !Internal_->Levels[0].Single.empty();
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

const std::vector<int>& AggregationMultigridSolver::GetMemberOffsets(int l) const
{
  return Internal_->Levels.at(l).MemberOffsets;
}

const std::vector<int>& AggregationMultigridSolver::GetMembers(int l) const
{
  return Internal_->Levels.at(l).Members;
}

const std::vector<int>& AggregationMultigridSolver::GetCoarseSlots(int l) const
{
  return Internal_->Levels.at(l).CoarseSlot;
}

void AggregationMultigridSolver::BuildStructure(
  const DiffusionSystem& system, const std::vector<double>& points)
{
  const int n = system.NumberOfUnknowns;
  if (n < 0 || system.RowOffsets.size() != static_cast<std::size_t>(n) + 1 ||
    system.RowOffsets.front() != 0 ||
    system.ColumnIndices.size() != static_cast<std::size_t>(system.RowOffsets.back()))
  {
    throw Error(GetName() + ": BuildStructure() needs NumberOfUnknowns + 1 row offsets from 0 "
      "and as many column indices as the last offset");
  }
  if (points.size() != 3 * static_cast<std::size_t>(n))
  {
    throw Error(GetName() + ": BuildStructure() needs 3 coordinates per unknown (" +
      std::to_string(3 * static_cast<long long>(n)) + "), got " + std::to_string(points.size()));
  }
  Ready_ = false;
  Internal_->Recycler.Clear();
  const auto start = Clock::now();
  BuildHierarchy(system, points);
  HierarchyMs_ = MillisecondsSince(start);
  ++Builds_;
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
      lev.Values.size() * sizeof(double) +
      (lev.Single.size() + lev.InverseL1.size() + lev.B.size() + lev.X.size() + lev.Y.size() +
        lev.R.size() + lev.D.size() + lev.T.size() + lev.Saved.size() + lev.Sum.size()) *
        sizeof(float);
  }
  const auto& w = Internal_->Work;
  bytes += (w.R.size() + w.Z.size() + w.P.size() + w.Q.size()) * sizeof(double);
  bytes += NC * Internal_->CoarsestFactorNonZeros * (sizeof(double) + sizeof(int));
  bytes += Internal_->Recycler.GetMemoryBytes();
  return bytes;
}

} // namespace translucency
