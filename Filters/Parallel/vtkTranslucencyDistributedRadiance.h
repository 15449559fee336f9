/**
 * @file   vtkTranslucencyDistributedRadiance.h
 * @brief  vtkOutgoingRadiance's per-piece path under MPI: each rank outputs
 *         the physical boundary faces of its own tets (a face shared with a
 *         tet of another rank is not boundary), no gather.
 *
 * Used when vtkOutgoingRadiance's plan says "per piece"
 * (vtkTranslucencyDispatch: every rank takes part, a rank with an empty
 * piece too). A build without the Parallel layer (hypre) or VTK's
 * ParallelMPI gathers (vtkTranslucency::CanDistribute).
 *
 * The faces are found as by the distributed Surface Irradiance
 * (vtkTranslucency::ExtractPieceFaces, translucency::FindPieceBoundary:
 * points identified by GlobalIds or exact coordinates); a point's normal,
 * S_i and area-weighted refractive index sum the physical faces of every
 * rank around it, so a point on the seam between two ranks' surfaces has
 * the serial values on both.
 */
#ifndef vtkTranslucencyDistributedRadiance_h
#define vtkTranslucencyDistributedRadiance_h

#include <memory>
#include <string>
#include <vector>

class vtkUnstructuredGrid;

namespace vtkTranslucencyDistributedRadiance
{
/// A rank's part of the boundary surface (local point ids of the piece).
struct Surface
{
  std::vector<long long> Triangles; ///< 3 local point ids per physical face of this rank, outward
  std::vector<char> OnBoundary;     ///< per local point: on the physical boundary (any rank's face)
  std::vector<char> Owned;          ///< per local point on the boundary: this rank owns it
  std::vector<double> Normals;      ///< 3 per local point: outward unit normal (serial value)
  std::vector<double> Eta;          ///< per local point: area-weighted refractive index
  long long TotalTriangles = 0;     ///< physical faces over every rank
  long long TotalTets = 0;          ///< owned tets over every rank
};

/**
 * Collective. The piece's part of the physical boundary. Returns false with
 * `error` (the same on every rank) on failure: a cell that is not a linear
 * tet, an invalid RefractiveIndex under a boundary face, an empty mesh on
 * every rank, overlapping pieces without ghost marks.
 */
bool FindSurface(vtkUnstructuredGrid* input, Surface& surface, std::string& error);

/**
 * FindSurface kept across the executions of one filter (issue 32), as the
 * serial path keeps its surface per mesh: the last surface while the
 * geometry and RefractiveIndex of every rank's piece are the same
 * (vtkTranslucency::PieceIdentity, agreed over the ranks); else found again.
 * A relight or a new solve then finds no faces and numbers no points.
 */
class SurfaceCache
{
public:
  SurfaceCache();
  ~SurfaceCache();
  SurfaceCache(const SurfaceCache&) = delete;
  SurfaceCache& operator=(const SurfaceCache&) = delete;
  /// Collective. FindSurface's result for `input`, kept or found now
  /// (`surface` points into this object, valid until the next call);
  /// false with `error` (the same on every rank) as FindSurface.
  bool Find(vtkUnstructuredGrid* input, const Surface*& surface, std::string& error);
  /// Whether the last Find() searched (false: the kept surface).
  bool GetSearched() const { return this->Searched; }
  void Clear();

private:
  struct Impl;
  std::unique_ptr<Impl> In;
  bool Searched = false;
};

/// Collective: on every rank, `local` concatenated over the ranks (rank order).
std::vector<double> AllGather(const std::vector<double>& local);
/// Collective: the maximum over the ranks of each of `values` (in place).
void AllMax(std::vector<double>& values);
}

#endif
