/**
 * @file SurfaceLightKernel.h
 * @brief The projected boundary irradiance (ComputeProjectedIrradiance) at
 * chosen points of a plain triangle surface: the object's physical boundary
 * without its tets. The distributed Surface Irradiance (issue 18,
 * Documentation/Parallel.md) gathers that surface on every MPI rank and
 * evaluates its own boundary points with this; the serial filter keeps
 * ComputeProjectedIrradiance on the TetMesh.
 *
 * The arithmetic is the serial one term by term (triangle area vectors,
 * point normals and areas summed in triangle order, the point's shadow ray
 * per light, the uniform light's HemisphereDirection() samples, the
 * area-weighted projection of the corner values), so a surface whose
 * triangles are the TetMesh's boundary triangles gives the serial values up
 * to the order of the sums over a point's triangles (round-off).
 */
#pragma once

#include "LightSources.h"

#include <cstddef>
#include <functional>
#include <vector>

namespace translucency
{

/// An object's boundary surface, enough for its irradiance.
struct BoundarySurface
{
  /// Surface points, 3 coordinates each (mm).
  std::vector<double> Points;
  /// 3 point indices per triangle, (p1 - p0) x (p2 - p0) pointing out of the object.
  std::vector<int> Triangles;
  /// Refractive index of the tet under each triangle (finite, > 0).
  std::vector<double> TriangleEta;
  /// Diagonal of the bounding box of every mesh point (mm), interior points
  /// included: the scale of the shadow rays' offset (1e-5 of it) and reach
  /// (twice it), as in ComputeBoundaryIrradiance().
  double Diagonal = 0.0;

  std::size_t GetNumberOfPoints() const { return Points.size() / 3; }
  std::size_t GetNumberOfTriangles() const { return Triangles.size() / 3; }
  /// Bytes held by the three arrays.
  std::size_t GetMemoryBytes() const;
};

/**
 * The `Irradiance` of ComputeProjectedIrradiance() at surface points
 * `points` (indices into surface.Points), 3 values (R, G, B, W/mm^2) per
 * entry in `q`; 0 at a point with no triangle of positive area (not a
 * boundary point of the serial mesh).
 *
 * @param rotations the uniform light's sample rotation, in [0, 1), per entry
 *   of `points` (the serial code uses UniformSampleRotation() of the point)
 * @param lights, uniformIrradiance, uniformSamples, shadows, abort as in
 *   ComputeBoundaryIrradiance(); the ray budget counts the surface's points.
 * @return false if aborted. Throws translucency::Error on invalid input.
 *
 * Shadow rays are cast against the whole surface (a RayCaster built only
 * when a ray is needed). OpenMP-parallel over `points`; the result does not
 * depend on the number of threads nor on which other points are asked for.
 */
bool ComputeSurfacePointIrradiance(const BoundarySurface& surface,
  const std::vector<int>& points, const std::vector<double>& rotations,
  const std::vector<LightSource>& lights, double uniformIrradiance, int uniformSamples,
  bool shadows, std::vector<double>& q, const std::function<bool()>& abort = {});

} // namespace translucency
