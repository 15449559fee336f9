/**
 * @file TetMesh.h
 * @brief Tetrahedral mesh with the topology every discretisation needs.
 *
 * Owns a copy of the vertex coordinates (mm) and the tetrahedra (4 vertex ids
 * each). SetGeometry() validates the input and builds, once:
 *  - the boundary triangles (faces used by exactly one tet), oriented with
 *    outward normals, with the tet that owns each of them;
 *  - the boundary points and, for each point, V_i (sum of the volumes of the
 *    tets around i, mm^3) and S_i (sum of the areas of the boundary triangles
 *    around i, mm^2) (TransCut, Sec. 3.2: |Upsilon| ~ V_i/4, Voronoi
 *    boundary area ~ S_i/3);
 *  - the vertex adjacency as a CSR pattern including the diagonal, and for
 *    every tet the 16 positions of its local matrix entries in that pattern,
 *    so assembly scatters without searching.
 *
 * Tets with negative signed volume are reoriented (two vertices swapped);
 * degenerate tets (|volume| below 1e-14 times the bounding box diagonal cubed),
 * out-of-range or repeated vertex ids and non-finite coordinates throw
 * translucency::Error naming the tet or point.
 */
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace translucency
{

class TetMesh
{
public:
  TetMesh() = default;

  /**
   * Set coordinates (3 per point, mm) and tets (4 point ids per tet) and
   * build the topology. Throws translucency::Error on invalid input. Points
   * used by no tet are allowed (they get V_i = 0 and an identity matrix row).
   */
  void SetGeometry(std::vector<double> points, std::vector<int> tets);

  /**
   * Move the vertices (3 per point, mm) keeping the topology (deformation).
   * Recomputes volumes, areas and normals; throws if a tet degenerates. A tet
   * that inverts is an error (it is not silently reoriented).
   */
  void UpdatePoints(const std::vector<double>& points);

  /**
   * A number that identifies the current points and tets: a new, process-wide
   * unique value after every SetGeometry() and UpdatePoints() (0 before the
   * first). Copies of a mesh share it. Assemblers key their per-tet caches on it.
   */
  std::uint64_t GetGeometryRevision() const { return GeometryRevision_; }

  int GetNumberOfPoints() const { return static_cast<int>(Points_.size() / 3); }
  int GetNumberOfTets() const { return static_cast<int>(Tets_.size() / 4); }
  const std::vector<double>& GetPoints() const { return Points_; }
  /// Tets as 4 ids each, positively oriented (after any reorientation).
  const std::vector<int>& GetTets() const { return Tets_; }
  const double* GetPoint(int i) const { return &Points_[3 * static_cast<std::size_t>(i)]; }
  const int* GetTet(int t) const { return &Tets_[4 * static_cast<std::size_t>(t)]; }

  /// Positive volume of tet t (mm^3).
  double GetTetVolume(int t) const { return TetVolumes_[t]; }
  const std::vector<double>& GetTetVolumes() const { return TetVolumes_; }

  /// Boundary triangles, 3 point ids each, ordered so that the normal
  /// (p1-p0)x(p2-p0) points out of the mesh.
  const std::vector<int>& GetBoundaryTriangles() const { return BoundaryTriangles_; }
  int GetNumberOfBoundaryTriangles() const
  {
    return static_cast<int>(BoundaryTriangles_.size() / 3);
  }
  /// The tet owning each boundary triangle.
  const std::vector<int>& GetBoundaryTriangleTets() const { return BoundaryTriangleTets_; }
  /// Area of each boundary triangle (mm^2).
  const std::vector<double>& GetBoundaryTriangleAreas() const { return BoundaryTriangleAreas_; }

  /// Sorted ids of the points on the boundary.
  const std::vector<int>& GetBoundaryPoints() const { return BoundaryPoints_; }
  /// The boundary triangles around each boundary point, in increasing id
  /// order: those of GetBoundaryPoints()[k] are
  /// GetBoundaryPointTriangles()[offsets[k], offsets[k+1]) with offsets =
  /// GetBoundaryPointTriangleOffsets(). Lets a per-point sum over the
  /// triangles run in parallel with the bits of the serial triangle loop.
  const std::vector<int>& GetBoundaryPointTriangleOffsets() const
  {
    return BoundaryPointTriangleOffsets_;
  }
  const std::vector<int>& GetBoundaryPointTriangles() const { return BoundaryPointTriangles_; }
  bool IsBoundaryPoint(int i) const { return BoundaryArea_[i] > 0.0; }
  /// V_i: sum of volumes of tets containing point i (mm^3).
  const std::vector<double>& GetVertexVolumes() const { return VertexVolume_; }
  /// S_i: sum of areas of boundary triangles containing point i (mm^2); 0 inside.
  const std::vector<double>& GetBoundaryAreas() const { return BoundaryArea_; }
  /// Area-weighted outward unit normal at each point (3 per point; 0 inside).
  const std::vector<double>& GetPointNormals() const { return PointNormals_; }

  /// CSR pattern of the vertex graph, diagonal included, columns sorted.
  const std::vector<int>& GetRowOffsets() const { return RowOffsets_; }
  const std::vector<int>& GetColumnIndices() const { return ColumnIndices_; }
  int GetNumberOfNonZeros() const { return static_cast<int>(ColumnIndices_.size()); }
  /// For tet t, entry 4*a+b (a, b local vertex numbers 0..3) is the position
  /// in the CSR value array of the entry (row tet[a], column tet[b]).
  const std::vector<int>& GetTetNonZeroPositions() const { return TetNonZeros_; }
  /// Position of the diagonal entry of row i in the CSR value array.
  const std::vector<int>& GetDiagonalPositions() const { return DiagonalPositions_; }
  /// Tets around each point (CSR: offsets then tet ids).
  const std::vector<int>& GetPointTetOffsets() const { return PointTetOffsets_; }
  const std::vector<int>& GetPointTets() const { return PointTets_; } ///< ascending per point

  /**
   * Schedule for a deterministic parallel scatter over tets (used by the
   * assembly). The tets, taken in their id order, are cut into chunks of
   * consecutive tets; the chunks are greedily coloured so that two chunks of
   * the same colour share no vertex. If that needs more than 64 colours (a
   * tet order scattered in space), the tets are taken in Z-order of their
   * centroids instead. Id order streams through the per-tet arrays the
   * scatter reads; put a mesh in spatial order (ComputeSpatialOrder) for a
   * fast assembly. Processing the colours one
   * after the other, the chunks of one colour in parallel and the tets of a
   * chunk in order, every matrix entry receives its contributions in the
   * same order whatever the number of threads.
   */
  struct ScatterSchedule
  {
    /// All tet ids, colour by colour, chunk by chunk.
    std::vector<int> Tets;
    /// Chunk k is Tets[ChunkOffsets[k], ChunkOffsets[k+1]).
    std::vector<int> ChunkOffsets = { 0 };
    /// Colour c is chunks [ColourOffsets[c], ColourOffsets[c+1]).
    std::vector<int> ColourOffsets = { 0 };
    int GetNumberOfColours() const { return static_cast<int>(ColourOffsets.size()) - 1; }
  };
  const ScatterSchedule& GetScatterSchedule() const { return Schedule_; }

  /// Bytes held by the geometry as given (points and tets; vector capacities).
  std::size_t GetGeometryMemoryBytes() const;
  /// Bytes held by everything SetGeometry derives from it: volumes, boundary
  /// lists and measures, normals, the CSR pattern, the point-tet incidence,
  /// the 16 entry positions per tet and the scatter schedule.
  std::size_t GetTopologyMemoryBytes() const;

  /**
   * A cache-friendly order: points sorted along a Morton (Z-order) curve of
   * their coordinates and tets by the Morton code of their centroid.
   * pointOrder[k] is the old id of new point k; likewise tetOrder. Apply the
   * permutation to the geometry and all attached arrays with the caller's
   * own tools (the VTK filters permute their arrays).
   */
  static void ComputeSpatialOrder(const std::vector<double>& points, const std::vector<int>& tets,
    std::vector<int>& pointOrder, std::vector<int>& tetOrder);

private:
  /// Tet volumes; reorients negative tets when allowReorient, else throws.
  void ComputeTetVolumes(bool allowReorient);
  /// Point-tet incidence, boundary triangles, CSR pattern, scatter schedule.
  void BuildTopology();
  /// V_i, boundary triangle areas, S_i, point normals and the boundary
  /// point-triangle incidence.
  void ComputeMeasures();
  /// TetNonZeros_ from the CSR rows (parallel over the points).
  void BuildTetNonZeroPositions();
  void BuildScatterSchedule();

  std::vector<double> Points_;
  std::vector<int> Tets_;
  std::vector<double> TetVolumes_;
  std::vector<int> BoundaryTriangles_;
  std::vector<int> BoundaryTriangleTets_;
  std::vector<double> BoundaryTriangleAreas_;
  std::vector<int> BoundaryPoints_;
  std::vector<int> BoundaryPointTriangleOffsets_;
  std::vector<int> BoundaryPointTriangles_;
  std::vector<double> VertexVolume_;
  std::vector<double> BoundaryArea_;
  std::vector<double> PointNormals_;
  std::vector<int> RowOffsets_;
  std::vector<int> ColumnIndices_;
  std::vector<int> DiagonalPositions_;
  std::vector<int> PointTetOffsets_;
  std::vector<int> PointTets_;
  std::vector<int> TetNonZeros_;
  ScatterSchedule Schedule_;
  std::uint64_t GeometryRevision_ = 0;
};

} // namespace translucency
