/**
 * @file DiscreteDivergence.h
 * @brief The TransCut discrete-divergence discretisation (paper Sec. 3,
 * eq. 4-14): unknowns at the mesh vertices, cot-weight edge coefficients,
 * lumped absorption and lumped Robin boundary term.
 */
#pragma once

#include "Discretization.h"
#include "TetGeometry.h"

namespace translucency
{

class DiscreteDivergence : public Discretization
{
public:
  std::string GetName() const override { return "divergence"; }

  /**
   * Assemble M (eq. 13-14) and b (eq. 12) for the three channels. Parallel
   * over tets with OpenMP. The result is bit-identical for any thread count
   * (tets are processed in vertex-disjoint colour classes, so every entry
   * sums its contributions in the same order).
   */
  void Assemble(const TetMesh& mesh, const OpticalProperties& material,
    const std::vector<double>& irradiance, DiffusionSystem& system) override;

  /**
   * Incremental update after the material of some tets changed (painting,
   * TransCut Sec. 5.2: "we only update the rows corresponding to the vertices
   * of tetrahedra that are affected"). `system` must come from Assemble() on
   * the same mesh (same topology and points); `material` is the whole new
   * material and `irradiance` the one used for that assembly. Only the matrix
   * rows and right-hand-side entries of the vertices of `changedTets` (tet
   * ids, duplicates allowed) are rebuilt: each such row is cleared and
   * re-summed from all tets around its vertex, in the order of the full
   * assembly (the scatter schedule), then its boundary term is added again,
   * so the result is bit-identical to Assemble() with the new material.
   * Serial: cost ~ the tets around the touched vertices plus one pass over
   * the tet ids and the boundary triangles. Throws translucency::Error on a
   * system that does not match the mesh, an out-of-range tet id or an invalid
   * value of a changed tet (named). Returns true (it is implemented).
   */
  bool UpdateTets(const TetMesh& mesh, const OpticalProperties& material,
    const std::vector<double>& irradiance, const std::vector<int>& changedTets,
    DiffusionSystem& system) const override;

  /// The boundary rows' load of TransCut eq. 12 for a new irradiance, as in
  /// Assemble() (interior rows are 0): O(boundary points), OpenMP-parallel.
  bool UpdateRightHandSide(const TetMesh& mesh, const OpticalProperties& material,
    const std::vector<double>& irradiance, DiffusionSystem& system) const override;

  /// The lumped mass of TransCut eq. 13 (V_t per vertex of tet t, 4 x V_t/4).
  bool AddMass(const TetMesh& mesh, const std::vector<double>& coefficient,
    std::array<std::vector<double>, NumberOfChannels>& values) const override;

  /// Unknowns are the vertex fluences: a copy.
  void ToPointFluence(const TetMesh& mesh, const DiffusionSystem& system,
    const std::array<Eigen::VectorXd, NumberOfChannels>& solution,
    std::vector<double>& fluence) const override;

  /// Bytes of the per-tet geometry cache (7 doubles per tet once filled).
  std::size_t GetCacheMemoryBytes() const { return GeometryCache_.GetMemoryBytes(); }

  /// OpenMP threads for assembly (0 = OpenMP default). Default 0.
  void SetNumberOfThreads(int n) override { NumberOfThreads_ = n; }
  int GetNumberOfThreads() const { return NumberOfThreads_; }

private:
  int NumberOfThreads_ = 0;
  /// V_t and g_ab per tet, reused while the mesh geometry is the same
  /// (7 doubles per tet: 56 MB at 1M tets).
  TetGeometryCache GeometryCache_;
};

} // namespace translucency
