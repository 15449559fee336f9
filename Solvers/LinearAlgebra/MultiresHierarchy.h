/**
 * @file MultiresHierarchy.h
 * @brief The TransCut multiresolution graph hierarchy (TransCut,
 * Sec. 4.1-4.2): progressively coarser vertex graphs G^l = (P^l, E^l) of a
 * tet mesh, the interpolation of eq. 16 between consecutive levels, and the
 * coarse operators built from it (the paper's eq. 17, "substitute eq. 16
 * into eq. 15", and the Galerkin product P^T A P of the multigrid solver).
 *
 * Everything is built on OpenMP threads and is deterministic: the result
 * does not depend on the number of threads (every parallel loop writes only
 * its own entries and reads the state of the previous round).
 */
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace translucency
{

class TetMesh;

/// A square sparse pattern in CSR form (columns sorted within a row).
struct CsrPattern
{
  int Size = 0;
  std::vector<int> Offsets; ///< Size + 1
  std::vector<int> Columns;
  int GetNumberOfNonZeros() const { return static_cast<int>(Columns.size()); }
};

class MultiresHierarchy
{
public:
  /// One level l of the hierarchy.
  struct Level
  {
    /// G^l: the vertex graph of this level (diagonal included, sorted rows).
    CsrPattern Graph;
    /// Level-0 (mesh) id of each vertex of this level (positions come from there).
    std::vector<int> MeshIds;
    /// Level l -> l + 1 (empty on the coarsest level): the id of each vertex
    /// at level l + 1, or -1 if it was dropped (i in P^l - P^{l+1}).
    std::vector<int> CoarseIds;
    /// Interpolation eq. 16 as an N_l x N_{l+1} CSR matrix P: one entry 1
    /// for a retained vertex, lambda_ij / lambda_i for a dropped one.
    std::vector<int> InterpolationOffsets;
    std::vector<int> InterpolationColumns;
    std::vector<double> InterpolationWeights;
    /// Vertices picked by the first independent-set pass (before the graph
    /// enhancement of Sec. 4.1.3), for tests: 1 = picked.
    std::vector<char> FirstPicks;
    /// Graph-enhancement rounds needed (Sec. 4.1.3).
    int EnhancementRounds = 0;
  };

  ///@{
  /// Number of levels including level 0; 0 (default) = automatic: coarsen
  /// until a level has at most GetCoarsestSize() vertices, or coarsening
  /// stalls (a level keeps more than 90 % of the vertices), at most 25 levels.
  void SetMaxLevels(int n) { MaxLevels_ = n; }
  int GetMaxLevels() const { return MaxLevels_; }
  void SetCoarsestSize(int n) { CoarsestSize_ = n; }
  int GetCoarsestSize() const { return CoarsestSize_; }
  ///@}

  /// OpenMP threads for the build (0 = OpenMP's default, 1 = serial).
  void SetNumberOfThreads(int n) { Threads_ = n; }

  /// Build from a tet mesh: G^0 is its vertex graph (TetMesh CSR pattern).
  void Build(const TetMesh& mesh);

  /**
   * Build from a vertex graph (CSR, diagonal included or not, must be
   * symmetric) and positions (3 per vertex, mm). Throws translucency::Error
   * on an inconsistent graph, non-finite positions or two adjacent vertices
   * at the same position (eq. 16 weights 1/|x_i - x_j| undefined).
   */
  void Build(const std::vector<double>& points, const std::vector<int>& offsets,
    const std::vector<int>& columns);

  int GetNumberOfLevels() const { return static_cast<int>(Levels_.size()); }
  const Level& GetLevel(int l) const { return Levels_[l]; }
  std::size_t GetMemoryBytes() const;

  /// Hash-based random code of vertex i at a level (Sec. 4.1.1): a 32-bit
  /// hash of (i, level) in the high 32 bits, i in the low 32 bits.
  static std::uint64_t Code(int i, int level);

  /**
   * The parallel independent-set procedure of Sec. 4.1.1 on the candidate
   * set Q (inQ[i] = 1): in rounds, every i in Q whose code is smaller than
   * the codes of all its neighbours in Q is picked (picked[i] = 1), then the
   * picks and their neighbours leave Q; until Q is empty. Rows of `graph`
   * may contain the diagonal.
   */
  static void IndependentSet(const CsrPattern& graph, std::vector<char> inQ, int level,
    std::vector<char>& picked, int threads);

private:
  void BuildLevels(const std::vector<double>& points, CsrPattern graph0);

  int MaxLevels_ = 0;
  int CoarsestSize_ = 1000;
  int Threads_ = 0;
  std::vector<Level> Levels_;
};

/**
 * A coarse operator A^{l+1} = R A^l P with the interpolation P of one level
 * and R either the injection onto the retained rows (the paper's eq. 17:
 * b^{l+1}_i = b^l_i, rows of retained vertices) or P^T (Galerkin). The
 * pattern and the list of contributions are built once per hierarchy
 * (Build); Compute() then only recomputes values (for three channels at
 * once, interleaved: value 3 k + c is channel c of non-zero k).
 */
class CoarseOperator
{
public:
  enum class Kind
  {
    Injection, ///< TransCut eq. 17 (non-symmetric)
    Galerkin,  ///< P^T A P (symmetric if A is)
    /// P^T A P restricted to the hierarchy's coarse graph G^{l+1} (Sec.
    /// 4.1.2): every entry (a, b) outside it is dropped and |a_ab| added to
    /// the diagonal a_aa (so the result stays SPD if A is: the change is a
    /// sum of positive semi-definite rank-one terms).
    SparseGalerkin
  };

  /// Pattern of R A P, where A has pattern `fine` (that of level l);
  /// `coarseGraph` is G^{l+1} (used by SparseGalerkin only).
  void Build(const MultiresHierarchy::Level& level, const CsrPattern& fine,
    const CsrPattern& coarseGraph, Kind kind, int threads);

  /**
   * Coarse values from fine values, three channels at once: channel c of
   * fine non-zero k is fine[c][k * fineStride]; the result has 3 values per
   * coarse non-zero (interleaved, coarse[3 k + c]). Deterministic.
   */
  void Compute(const std::array<const double*, 3>& fine, int fineStride, double* coarse,
    int threads) const;

  const CsrPattern& GetPattern() const { return Pattern_; }
  std::size_t GetMemoryBytes() const;

private:
  const MultiresHierarchy::Level* Level_ = nullptr;
  const CsrPattern* Fine_ = nullptr;
  Kind Kind_ = Kind::Injection;
  CsrPattern Pattern_;
  /// Level-l id of each coarse vertex (injection rows).
  std::vector<int> FineIds_;
  /// Galerkin: P^T as CSR (coarse rows; fine row ids and weights).
  std::vector<int> TransposeOffsets_;
  std::vector<int> TransposeRows_;
  std::vector<double> TransposeWeights_;
};

} // namespace translucency
