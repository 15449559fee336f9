/**
 * @file   vtkTranslucencyDistributedIrradiance.h
 * @brief  vtkSurfaceIrradiance's distributed path under MPI: no rank gathers
 *         the mesh; only the physical boundary surface is all-gathered
 *         (translucency::GatherBoundarySurface), and each rank computes the
 *         Irradiance of its own piece's points on it
 *         (translucency::ComputeSurfacePointIrradiance).
 *
 * Used when vtkSurfaceIrradiance's plan says "distributed"
 * (vtkTranslucencyDispatch: every rank takes part, a rank with an empty
 * piece too). A build without the Parallel layer (hypre) or VTK's
 * ParallelMPI gathers (vtkTranslucency::CanDistribute).
 *
 * The piece: its owned cells (vtkGhostType DUPLICATECELL cells are left out)
 * must be linear tets; points are identified across ranks by the point
 * GlobalIds when every rank with points has them, else by exactly equal
 * coordinates (as the distributed solve). The result equals the serial
 * filter's to round-off. The uniform light's sampled occlusion rotates each
 * point's samples by its index, as the serial code, taking the index the
 * gathered path's merged mesh would give it: its rank among the global ids
 * (the serial index when the ids grow with the serial order, whatever the
 * partition), or without ids its global row (the rank order; the serial
 * index when one rank holds the whole mesh).
 */
#ifndef vtkTranslucencyDistributedIrradiance_h
#define vtkTranslucencyDistributedIrradiance_h

#include "LightSources.h" // for translucency::LightSource
#include "SurfaceLightKernel.h" // for translucency::BoundarySurface

#include <functional>
#include <memory>
#include <string>
#include <vector>

class vtkUnstructuredGrid;

namespace vtkTranslucencyDistributedIrradiance
{
/// What the last Compute() gathered (the same numbers on every rank).
struct Report
{
  long long SurfaceTriangles = 0; ///< physical boundary triangles gathered
  long long SurfacePoints = 0;    ///< their points
  long long GatheredBytes = 0;    ///< bytes each rank received
  double GatherMilliseconds = 0.0; ///< numbering, face count and gather (this rank)
  double RayMilliseconds = 0.0;    ///< the irradiance of this rank's points
};

/**
 * What Compute() keeps across the executions of one filter (issue 32), as
 * the serial path's IrradianceCache: the gathered physical boundary
 * surface, this rank's points on it, and the uniform light's and each
 * light's terms (translucency::SurfacePointIrradianceCache). Kept while the
 * geometry of every rank's piece (vtkTranslucency::PieceGeometryKey) and its
 * RefractiveIndex (bit for bit) are the same on every rank; so a relight
 * gathers nothing and computes the changed light only.
 */
class State
{
public:
  State();
  ~State();
  State(const State&) = delete;
  State& operator=(const State&) = delete;
  /// What the last Compute() computed (the rest came from the kept terms):
  /// the number of lights, whether the uniform light's term, whether the
  /// surface was gathered.
  int GetNumberOfLightsComputed() const;
  bool GetUniformComputed() const;
  bool GetSurfaceGathered() const;
  /// Forget everything: the next Compute() gathers again.
  void Clear();

  struct Impl;
  std::unique_ptr<Impl> In;
};

/**
 * Collective. The projected irradiance (3 per input point: R, G, B,
 * W/mm^2, 0 inside) of this rank's piece `input` for `lights` (directional,
 * point and spot), the uniform light and shadows as vtkSurfaceIrradiance.
 * `state` (may be null: nothing kept) keeps the gathered surface and the
 * lights' terms across calls. Returns false with `error` (the same on every
 * rank, "" if aborted on some rank) on failure.
 */
bool Compute(vtkUnstructuredGrid* input, const std::vector<translucency::LightSource>& lights,
  double uniformIrradiance, int uniformSamples, bool shadows,
  const std::function<bool()>& abort, std::vector<double>& q, Report& report,
  std::string& error, State* state = nullptr);

/**
 * Collective. The physical boundary surface of the distributed mesh (every
 * rank's boundary triangles that no other rank's tet shares), the same on
 * every rank, as triangles in `surface` (outward; the points in global-row
 * order): the serial mesh's boundary surface, for queries against the whole
 * object's surface from a rank's own piece (Assign's Layers: the depth of a
 * centroid; the interactive pencil beam's ray cast). Needs no RefractiveIndex
 * (surface.TriangleEta is then 1 where the input has none). Needs vtkTranslucency::CanDistribute and
 * more than one process. Returns false with `error` (the same on every rank).
 */
bool GatherSurface(vtkUnstructuredGrid* input, translucency::BoundarySurface& surface,
  std::string& error);
}

#endif
