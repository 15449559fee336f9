#include "MultiresHierarchy.h"

#include "Error.h"
#include "TetMesh.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace translucency
{

namespace
{

int Threads(int requested)
{
  return requested > 0 ? requested : omp_get_max_threads();
}

/// Tiny Encryption Algorithm, 8 rounds: a cryptographic-style hash of two
/// 32-bit words (the GPU white-noise generator family of the paper's [30]).
std::uint32_t Tea(std::uint32_t v0, std::uint32_t v1)
{
  std::uint32_t sum = 0;
  const std::uint32_t delta = 0x9e3779b9u;
  for (int round = 0; round < 8; ++round)
  {
    sum += delta;
    v0 += ((v1 << 4) + 0xa341316cu) ^ (v1 + sum) ^ ((v1 >> 5) + 0xc8013ea4u);
    v1 += ((v0 << 4) + 0xad90777du) ^ (v0 + sum) ^ ((v0 >> 5) + 0x7e95761eu);
  }
  return v0;
}

/// Turn per-row column lists into a CSR pattern.
void ToCsr(std::vector<std::vector<int>>& rows, CsrPattern& out)
{
  out.Size = static_cast<int>(rows.size());
  out.Offsets.assign(rows.size() + 1, 0);
  for (std::size_t i = 0; i < rows.size(); ++i)
  {
    out.Offsets[i + 1] = out.Offsets[i] + static_cast<int>(rows[i].size());
  }
  out.Columns.resize(out.Offsets.back());
  const long long n = static_cast<long long>(rows.size());
#pragma omp parallel for schedule(static)
  for (long long i = 0; i < n; ++i)
  {
    std::copy(rows[i].begin(), rows[i].end(), out.Columns.begin() + out.Offsets[i]);
    std::vector<int>().swap(rows[i]);
  }
}


/// BuildLevels, Sec. 4.1.3 (graph enhancement): mark both ends of every
/// edge of dropped vertices i, j with N(i) ∩ N(j) ∩ P^{l+1} empty, select
/// an independent set among the marked vertices, add it to P^{l+1};
/// repeat until nothing is marked. Returns the number of rounds.
int EnhanceRetained(const CsrPattern& g, int l, int nt, std::vector<char>& retained)
{
  const int n = g.Size;
  int rounds = 0;
  for (;;)
  {
    std::vector<char> marked(n, 0);
    long long count = 0;
#pragma omp parallel for num_threads(nt) schedule(dynamic, 1024) reduction(+ : count)
    for (int i = 0; i < n; ++i)
    {
      if (retained[i])
      {
        continue;
      }
      const int* ni = &g.Columns[g.Offsets[i]];
      const int* niEnd = &g.Columns[0] + g.Offsets[i + 1];
      for (const int* pj = ni; pj != niEnd && !marked[i]; ++pj)
      {
        const int j = *pj;
        if (j == i || retained[j])
        {
          continue;
        }
        bool shared = false;
        for (const int* pk = ni; pk != niEnd && !shared; ++pk)
        {
          const int k = *pk;
          shared = retained[k] &&
            std::binary_search(&g.Columns[g.Offsets[j]], &g.Columns[0] + g.Offsets[j + 1], k);
        }
        if (!shared)
        {
          marked[i] = 1; // j marks itself in its own iteration (symmetric test)
          ++count;
        }
      }
    }
    if (count == 0)
    {
      break;
    }
    ++rounds;
    std::vector<char> extra;
    MultiresHierarchy::IndependentSet(g, std::move(marked), l + 1000 * rounds, extra, nt);
    for (int i = 0; i < n; ++i)
    {
      retained[i] = retained[i] || extra[i];
    }
  }
  return rounds;
}

/// BuildLevels, eq. 16: P row i = 1 at i if retained, else lambda_ij /
/// lambda_i over R(i) = N(i) ∩ P^{l+1}, lambda_ij = 1 / |x_i - x_j|.
void BuildInterpolation(const std::vector<double>& points, const std::vector<char>& retained,
  int l, int nt, MultiresHierarchy::Level& fine)
{
  const CsrPattern& g = fine.Graph;
  const int n = g.Size;
  auto distance = [&points](int a, int b)
  {
    double d2 = 0.0;
    for (int d = 0; d < 3; ++d)
    {
      const double t = points[3 * static_cast<std::size_t>(a) + d] -
        points[3 * static_cast<std::size_t>(b) + d];
      d2 += t * t;
    }
    return std::sqrt(d2);
  };
  fine.InterpolationOffsets.assign(n + 1, 0);
  for (int i = 0; i < n; ++i)
  {
    int count = 1;
    if (!retained[i])
    {
      count = 0;
      for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
      {
        count += retained[g.Columns[k]] ? 1 : 0;
      }
      if (count == 0)
      {
        throw Error("MultiresHierarchy: internal error, dropped vertex " + std::to_string(i) +
          " of level " + std::to_string(l) + " has no retained neighbour");
      }
    }
    fine.InterpolationOffsets[i + 1] = fine.InterpolationOffsets[i] + count;
  }
  fine.InterpolationColumns.resize(fine.InterpolationOffsets.back());
  fine.InterpolationWeights.resize(fine.InterpolationOffsets.back());
  std::vector<int> badVertex(nt, -1);
#pragma omp parallel for num_threads(nt) schedule(static)
  for (int i = 0; i < n; ++i)
  {
    int p = fine.InterpolationOffsets[i];
    if (retained[i])
    {
      fine.InterpolationColumns[p] = fine.CoarseIds[i];
      fine.InterpolationWeights[p] = 1.0;
      continue;
    }
    double sum = 0.0;
    for (int k = g.Offsets[i]; k < g.Offsets[i + 1]; ++k)
    {
      const int j = g.Columns[k];
      if (retained[j])
      {
        const double length = distance(fine.MeshIds[i], fine.MeshIds[j]);
        const double lambda = length > 0.0 ? 1.0 / length : 0.0;
        if (!(length > 0.0))
        {
          badVertex[omp_get_thread_num()] = fine.MeshIds[i];
        }
        fine.InterpolationColumns[p] = fine.CoarseIds[j];
        fine.InterpolationWeights[p] = lambda;
        sum += lambda;
        ++p;
      }
    }
    for (int q = fine.InterpolationOffsets[i]; q < p; ++q)
    {
      fine.InterpolationWeights[q] /= sum;
    }
  }
  for (int b : badVertex)
  {
    if (b >= 0)
    {
      throw Error("MultiresHierarchy: point " + std::to_string(b) +
        " has a neighbour at the same position (eq. 16 weight 1/|x_i - x_j| undefined)");
    }
  }
}

/// BuildLevels, Sec. 4.1.2-4.1.3: E^{l+1} joins two retained vertices that
/// are both one-ring neighbours of a dropped vertex, or neighbours at level
/// l. Built row by row (row a of the coarse graph collects its retained
/// neighbours and the retained neighbours of its dropped neighbours), each
/// row sorted and deduplicated: the same edge set as sorting and
/// deduplicating the list of all added edges.
MultiresHierarchy::Level CoarseLevel(
  const MultiresHierarchy::Level& fine, const std::vector<char>& retained, int nc, int nt)
{
  using Level = MultiresHierarchy::Level;
  const CsrPattern& g = fine.Graph;
  const int n = g.Size;
  Level coarse;
  coarse.MeshIds.resize(nc);
  std::vector<int> fineOf(nc);
  for (int i = 0; i < n; ++i)
  {
    if (retained[i])
    {
      fineOf[fine.CoarseIds[i]] = i;
      coarse.MeshIds[fine.CoarseIds[i]] = fine.MeshIds[i];
    }
  }
  std::vector<std::vector<int>> rows(nc);
#pragma omp parallel for num_threads(nt) schedule(dynamic, 256)
  for (int a = 0; a < nc; ++a)
  {
    const int f = fineOf[a];
    std::vector<int>& row = rows[a];
    for (int k = g.Offsets[f]; k < g.Offsets[f + 1]; ++k)
    {
      const int j = g.Columns[k];
      if (retained[j])
      {
        row.push_back(fine.CoarseIds[j]);
      }
      else
      {
        for (int p = fine.InterpolationOffsets[j]; p < fine.InterpolationOffsets[j + 1]; ++p)
        {
          row.push_back(fine.InterpolationColumns[p]);
        }
      }
    }
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
  }
  ToCsr(rows, coarse.Graph);
  return coarse;
}

} // namespace

std::uint64_t MultiresHierarchy::Code(int i, int level)
{
  // Sec. 4.1.1: the random number in the high bits, the index in the low
  // bits, so codes are unique and the order is random. (64 bits instead of
  // the paper's 32 so that any number of vertices fits with 32 random bits.)
  const std::uint32_t random =
    Tea(static_cast<std::uint32_t>(i), 0x5bd1e995u + static_cast<std::uint32_t>(level));
  return (static_cast<std::uint64_t>(random) << 32) | static_cast<std::uint32_t>(i);
}

void MultiresHierarchy::IndependentSet(const CsrPattern& graph, std::vector<char> inQ, int level,
  std::vector<char>& picked, int threads)
{
  const int n = graph.Size;
  picked.assign(n, 0);
  std::vector<int> active;
  for (int i = 0; i < n; ++i)
  {
    if (inQ[i])
    {
      active.push_back(i);
    }
  }
  std::vector<char> pickNow(n, 0);
  const int nt = Threads(threads);
  // The codes of this level, hashed once (Sec. 4.1.1).
  std::vector<std::uint64_t> codes(n);
#pragma omp parallel for num_threads(nt) schedule(static)
  for (int i = 0; i < n; ++i)
  {
    codes[i] = Code(i, level);
  }
  while (!active.empty())
  {
    const long long m = static_cast<long long>(active.size());
    // Sec. 4.1.1: i joins P^{l+1} if h_i is smaller than the codes of all of
    // Gamma(i) = N^l(i) ∩ Q^{l+1}. Decisions read Q of the previous round
    // only, so threads agree and two picks of one round are never adjacent.
#pragma omp parallel for num_threads(nt) schedule(static)
    for (long long a = 0; a < m; ++a)
    {
      const int i = active[a];
      const std::uint64_t hi = codes[i];
      bool smallest = true;
      for (int k = graph.Offsets[i]; k < graph.Offsets[i + 1] && smallest; ++k)
      {
        const int j = graph.Columns[k];
        if (j != i && inQ[j] && codes[j] < hi)
        {
          smallest = false;
        }
      }
      pickNow[i] = smallest ? 1 : 0;
    }
    // Remove the picks and their neighbours Gamma(i) from Q.
    std::vector<char> leave(m, 0);
#pragma omp parallel for num_threads(nt) schedule(static)
    for (long long a = 0; a < m; ++a)
    {
      const int i = active[a];
      bool out = pickNow[i] != 0;
      for (int k = graph.Offsets[i]; k < graph.Offsets[i + 1] && !out; ++k)
      {
        out = pickNow[graph.Columns[k]] != 0;
      }
      leave[a] = out ? 1 : 0;
    }
    std::vector<int> next;
    next.reserve(active.size());
    for (long long a = 0; a < m; ++a)
    {
      const int i = active[a];
      if (pickNow[i])
      {
        picked[i] = 1;
      }
      if (leave[a])
      {
        inQ[i] = 0;
      }
      else
      {
        next.push_back(i);
      }
    }
    for (long long a = 0; a < m; ++a)
    {
      pickNow[active[a]] = 0;
    }
    active.swap(next);
  }
}

void MultiresHierarchy::Build(const TetMesh& mesh)
{
  CsrPattern graph;
  graph.Size = mesh.GetNumberOfPoints();
  graph.Offsets = mesh.GetRowOffsets();
  graph.Columns = mesh.GetColumnIndices();
  BuildLevels(mesh.GetPoints(), std::move(graph));
}

void MultiresHierarchy::Build(
  const std::vector<double>& points, const std::vector<int>& offsets, const std::vector<int>& columns)
{
  const long long n = static_cast<long long>(offsets.size()) - 1;
  if (n < 0 || points.size() != 3 * static_cast<std::size_t>(n) || offsets.front() != 0 ||
    static_cast<std::size_t>(offsets.back()) != columns.size())
  {
    std::ostringstream os;
    os << "MultiresHierarchy: inconsistent graph (" << offsets.size() << " row offsets, "
       << columns.size() << " columns, " << points.size() << " coordinates)";
    throw Error(os.str());
  }
  // Rows sorted, with the diagonal, as the rest of the build expects.
  CsrPattern graph;
  graph.Size = static_cast<int>(n);
  std::vector<std::vector<int>> rows(n);
  for (long long i = 0; i < n; ++i)
  {
    if (offsets[i + 1] < offsets[i])
    {
      throw Error("MultiresHierarchy: row offsets decrease at row " + std::to_string(i));
    }
    rows[i].push_back(static_cast<int>(i));
    for (int k = offsets[i]; k < offsets[i + 1]; ++k)
    {
      if (columns[k] < 0 || columns[k] >= n)
      {
        std::ostringstream os;
        os << "MultiresHierarchy: column " << columns[k] << " of row " << i
           << " is out of range (" << n << " vertices)";
        throw Error(os.str());
      }
      rows[i].push_back(columns[k]);
    }
    std::sort(rows[i].begin(), rows[i].end());
    rows[i].erase(std::unique(rows[i].begin(), rows[i].end()), rows[i].end());
  }
  for (long long i = 0; i < n; ++i)
  {
    for (int j : rows[i])
    {
      if (!std::binary_search(rows[j].begin(), rows[j].end(), static_cast<int>(i)))
      {
        std::ostringstream os;
        os << "MultiresHierarchy: the graph is not symmetric (edge " << i << "-" << j
           << " has no reverse)";
        throw Error(os.str());
      }
    }
  }
  ToCsr(rows, graph);
  BuildLevels(points, std::move(graph));
}

void MultiresHierarchy::BuildLevels(const std::vector<double>& points, CsrPattern graph0)
{
  const int nt = Threads(Threads_);
  const int n0 = graph0.Size;
  for (int i = 0; i < n0; ++i)
  {
    for (int d = 0; d < 3; ++d)
    {
      if (!std::isfinite(points[3 * static_cast<std::size_t>(i) + d]))
      {
        throw Error(
          "MultiresHierarchy: point " + std::to_string(i) + " has a non-finite coordinate");
      }
    }
  }
  Levels_.clear();
  Levels_.emplace_back();
  Levels_[0].Graph = std::move(graph0);
  Levels_[0].MeshIds.resize(n0);
  for (int i = 0; i < n0; ++i)
  {
    Levels_[0].MeshIds[i] = i;
  }
  const int maxLevels = MaxLevels_ > 0 ? std::min(MaxLevels_, 25) : 25;

  for (int l = 0; static_cast<int>(Levels_.size()) < maxLevels; ++l)
  {
    Level& fine = Levels_[l];
    const CsrPattern& g = fine.Graph;
    const int n = g.Size;
    if (n <= 1 || (MaxLevels_ <= 0 && n <= CoarsestSize_))
    {
      break;
    }
    // Sec. 4.1.1: independent set of P^l, Q^{l+1} = P^l.
    std::vector<char> retained;
    IndependentSet(g, std::vector<char>(n, 1), l, retained, nt);
    fine.FirstPicks = retained;

    // Sec. 4.1.3: mark both ends of every edge of dropped vertices i, j with
    // N(i) ∩ N(j) ∩ P^{l+1} empty, select an independent set among the
    // marked vertices, add it to P^{l+1}; repeat until nothing is marked.
    fine.EnhancementRounds = EnhanceRetained(g, l, nt, retained);

    // Coarse ids in the order of the fine ids (keeps the spatial order).
    fine.CoarseIds.assign(n, -1);
    int nc = 0;
    for (int i = 0; i < n; ++i)
    {
      if (retained[i])
      {
        fine.CoarseIds[i] = nc++;
      }
    }
    if (MaxLevels_ <= 0 && nc > 0.9 * n)
    {
      // Coarsening stalls (e.g. isolated vertices): stop here.
      fine.CoarseIds.clear();
      fine.FirstPicks.clear();
      break;
    }

    // Eq. 16: P row i = 1 at i if retained, else lambda_ij / lambda_i over
    // R(i) = N(i) ∩ P^{l+1}, lambda_ij = 1 / |x_i - x_j|.
    BuildInterpolation(points, retained, l, nt, fine);

    Levels_.push_back(CoarseLevel(fine, retained, nc, nt));
  }
  // The coarsest level has no interpolation.
  Levels_.back().CoarseIds.clear();
  Levels_.back().FirstPicks.clear();
  Levels_.back().InterpolationOffsets.clear();
  Levels_.back().InterpolationColumns.clear();
  Levels_.back().InterpolationWeights.clear();
}

std::size_t MultiresHierarchy::GetMemoryBytes() const
{
  std::size_t bytes = 0;
  for (const Level& level : Levels_)
  {
    bytes += (level.Graph.Offsets.size() + level.Graph.Columns.size() + level.MeshIds.size() +
               level.CoarseIds.size() + level.InterpolationOffsets.size() +
               level.InterpolationColumns.size()) *
        sizeof(int) +
      level.InterpolationWeights.size() * sizeof(double) + level.FirstPicks.size();
  }
  return bytes;
}

// ---------------------------------------------------------------------------

void CoarseOperator::Build(const MultiresHierarchy::Level& level, const CsrPattern& fine,
  const CsrPattern& coarseGraph, Kind kind, int threads)
{
  const int coarseSize = coarseGraph.Size;
  Level_ = &level;
  Fine_ = &fine;
  Kind_ = kind;
  const int nt = Threads(threads);
  const int n = fine.Size;
  if (static_cast<int>(level.CoarseIds.size()) != n)
  {
    throw Error("CoarseOperator: the fine pattern does not match the hierarchy level");
  }
  FineIds_.assign(coarseSize, -1);
  for (int i = 0; i < n; ++i)
  {
    if (level.CoarseIds[i] >= 0)
    {
      FineIds_[level.CoarseIds[i]] = i;
    }
  }
  const auto& po = level.InterpolationOffsets;
  const auto& pc = level.InterpolationColumns;
  if (kind != Kind::Injection)
  {
    // P^T in CSR.
    TransposeOffsets_.assign(coarseSize + 1, 0);
    for (int c : pc)
    {
      ++TransposeOffsets_[c + 1];
    }
    for (int a = 0; a < coarseSize; ++a)
    {
      TransposeOffsets_[a + 1] += TransposeOffsets_[a];
    }
    TransposeRows_.resize(pc.size());
    TransposeWeights_.resize(pc.size());
    std::vector<int> fill(TransposeOffsets_.begin(), TransposeOffsets_.end() - 1);
    for (int i = 0; i < n; ++i)
    {
      for (int p = po[i]; p < po[i + 1]; ++p)
      {
        const int slot = fill[pc[p]]++;
        TransposeRows_[slot] = i;
        TransposeWeights_[slot] = level.InterpolationWeights[p];
      }
    }
  }
  if (kind == Kind::SparseGalerkin)
  {
    Pattern_ = coarseGraph;
    return;
  }
  std::vector<std::vector<int>> rows(coarseSize);
#pragma omp parallel num_threads(nt)
  {
    // Per-thread marker: deduplicate while collecting, sort the row after.
    std::vector<char> seen(coarseSize, 0);
#pragma omp for schedule(dynamic, 256)
    for (int a = 0; a < coarseSize; ++a)
    {
      std::vector<int>& row = rows[a];
      auto addFineRow = [&](int i)
      {
        for (int k = fine.Offsets[i]; k < fine.Offsets[i + 1]; ++k)
        {
          const int j = fine.Columns[k];
          for (int p = po[j]; p < po[j + 1]; ++p)
          {
            if (!seen[pc[p]])
            {
              seen[pc[p]] = 1;
              row.push_back(pc[p]);
            }
          }
        }
      };
      if (kind == Kind::Injection)
      {
        addFineRow(FineIds_[a]);
      }
      else
      {
        for (int t = TransposeOffsets_[a]; t < TransposeOffsets_[a + 1]; ++t)
        {
          addFineRow(TransposeRows_[t]);
        }
      }
      for (int b : row)
      {
        seen[b] = 0;
      }
      std::sort(row.begin(), row.end());
    }
  }
  ToCsr(rows, Pattern_);
}

void CoarseOperator::Compute(
  const std::array<const double*, 3>& fineValues, int stride, double* coarse, int threads) const
{
  const int nt = Threads(threads);
  const int nc = Pattern_.Size;
  const CsrPattern& fine = *Fine_;
  const auto& po = Level_->InterpolationOffsets;
  const auto& pc = Level_->InterpolationColumns;
  const auto& pw = Level_->InterpolationWeights;
#pragma omp parallel num_threads(nt)
  {
    // position[b] >= 0: slot of column b in the coarse row; <= -2: scratch
    // slot -(position + 2) of an entry outside the pattern (SparseGalerkin).
    std::vector<int> position(nc, -1);
    std::vector<double> scratch;
    std::vector<int> scratchColumns;
#pragma omp for schedule(dynamic, 256)
    for (int a = 0; a < nc; ++a)
    {
      const int begin = Pattern_.Offsets[a], end = Pattern_.Offsets[a + 1];
      for (int q = begin; q < end; ++q)
      {
        position[Pattern_.Columns[q]] = q;
        coarse[3 * static_cast<std::size_t>(q)] = 0.0;
        coarse[3 * static_cast<std::size_t>(q) + 1] = 0.0;
        coarse[3 * static_cast<std::size_t>(q) + 2] = 0.0;
      }
      // Eq. 17 (injection) / Galerkin: row a of R A P, accumulated in a
      // fixed order (deterministic whatever the thread count).
      auto addFineRow = [&](int i, double scale)
      {
        for (int k = fine.Offsets[i]; k < fine.Offsets[i + 1]; ++k)
        {
          const int j = fine.Columns[k];
          const std::size_t s = static_cast<std::size_t>(k) * stride;
          const double v0 = scale * fineValues[0][s];
          const double v1 = scale * fineValues[1][s];
          const double v2 = scale * fineValues[2][s];
          for (int p = po[j]; p < po[j + 1]; ++p)
          {
            int& slot = position[pc[p]];
            double* out;
            if (slot >= 0)
            {
              out = coarse + 3 * static_cast<std::size_t>(slot);
            }
            else
            {
              if (slot == -1)
              {
                slot = -2 - static_cast<int>(scratchColumns.size());
                scratchColumns.push_back(pc[p]);
                scratch.insert(scratch.end(), { 0.0, 0.0, 0.0 });
              }
              out = scratch.data() + 3 * static_cast<std::size_t>(-2 - slot);
            }
            const double w = pw[p];
            out[0] += v0 * w;
            out[1] += v1 * w;
            out[2] += v2 * w;
          }
        }
      };
      if (Kind_ == Kind::Injection)
      {
        addFineRow(FineIds_[a], 1.0);
      }
      else
      {
        for (int t = TransposeOffsets_[a]; t < TransposeOffsets_[a + 1]; ++t)
        {
          addFineRow(TransposeRows_[t], TransposeWeights_[t]);
        }
      }
      if (!scratchColumns.empty())
      {
        // SparseGalerkin: entries outside G^{l+1} go to the diagonal as |a_ab|.
        double* diagonal = coarse + 3 * static_cast<std::size_t>(position[a]);
        for (std::size_t e = 0; e < scratchColumns.size(); ++e)
        {
          for (int c = 0; c < 3; ++c)
          {
            diagonal[c] += std::abs(scratch[3 * e + c]);
          }
          position[scratchColumns[e]] = -1;
        }
        scratch.clear();
        scratchColumns.clear();
      }
      for (int q = begin; q < end; ++q)
      {
        position[Pattern_.Columns[q]] = -1;
      }
    }
  }
}

std::size_t CoarseOperator::GetMemoryBytes() const
{
  return (Pattern_.Offsets.size() + Pattern_.Columns.size() + FineIds_.size() +
           TransposeOffsets_.size() + TransposeRows_.size()) *
    sizeof(int) +
    TransposeWeights_.size() * sizeof(double);
}

} // namespace translucency
