/**
 * @file   vtkTranslucencyPieceFaces.h
 * @brief  The boundary faces of an MPI rank's own tets and the keys of its
 *         points, the input of the distributed boundary (Surface Irradiance,
 *         Outgoing Radiance; translucency::GatherBoundarySurface,
 *         translucency::FindPieceBoundary). Private header; only in builds
 *         with the distributed path (TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE).
 */
#ifndef vtkTranslucencyPieceFaces_h
#define vtkTranslucencyPieceFaces_h

#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
#include "DistributedNumbering.h" // for translucency::PointKey

#include <string>
#include <vector>

class vtkUnstructuredGrid;

namespace vtkTranslucency
{
/// A piece's points and the boundary triangles of its owned tets.
struct PieceFaces
{
  std::vector<double> Points;      ///< 3 per point of the piece (mm)
  std::vector<char> Used;          ///< per point: 1 if an owned tet has it
  std::vector<int> Triangles;      ///< 3 local point ids each, outward (TetMesh order)
  std::vector<int> TriangleTets;   ///< per triangle: its cell in the piece
  std::vector<double> TriangleEta; ///< per triangle: RefractiveIndex of its tet
  long long OwnedTets = 0;         ///< cells not flagged DUPLICATECELL
};

/**
 * Not collective. The owned tets of `input` (may be null or empty; cells
 * flagged vtkGhostType DUPLICATECELL left out; the cached topology when the
 * piece has no ghost cells) and their boundary triangles. Throws
 * translucency::Error for a cell that is not a linear tet or a missing
 * RefractiveIndex. `readEta` false: TriangleEta is 1 (for callers that need
 * only the geometry, e.g. the depths of Assign's Layers before any
 * RefractiveIndex exists).
 */
void ExtractPieceFaces(vtkUnstructuredGrid* input, PieceFaces& faces, bool readEta = true);

/**
 * Collective. The key of every point of `input` (`points`: its
 * coordinates): the point GlobalIds when every rank with points has them,
 * else the exact coordinates. Returns true if the keys are ids. `keys` is
 * left empty when `skip` (a local error already found; the call still takes
 * part in the collective).
 */
bool MakePointKeys(MPI_Comm comm, vtkUnstructuredGrid* input, const std::vector<double>& points,
  bool skip, std::vector<translucency::PointKey>& keys);

/**
 * Not collective. The identity of the geometry of a piece across
 * executions, for the per-mesh caches of the distributed paths (issue 32):
 * the objects and modification times of its points, their data, its cells,
 * its ghost array and its point GlobalIds, and its sizes (as
 * AcquireTetMesh's key; a new VTK object has a newer modification time, so
 * a re-used address does not match). "" for no input.
 */
std::string PieceGeometryKey(vtkUnstructuredGrid* input);

/// Collective: `same` on every rank (an MPI_MIN of the flags).
bool SameOnEveryRank(MPI_Comm comm, bool same);

/**
 * What the per-mesh caches of the distributed paths are keyed on: the
 * piece's geometry (PieceGeometryKey) and its RefractiveIndex per cell, bit
 * for bit (empty when the piece has no cells or no readable index: such a
 * piece matches only while it stays so).
 */
struct PieceIdentity
{
  std::string Geometry;
  std::vector<double> Eta;
  bool HasEta = false;
  /// Not collective: the identity of `input` now.
  static PieceIdentity Of(vtkUnstructuredGrid* input);
  bool operator==(const PieceIdentity& other) const;
};
}
#endif

#endif
