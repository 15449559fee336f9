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
#include <memory>
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
 * Shadow rays are cast against the whole surface (a ShadowCaster built only
 * when a ray is needed). OpenMP-parallel over `points`; the result does not
 * depend on the number of threads nor on which other points are asked for.
 */
bool ComputeSurfacePointIrradiance(const BoundarySurface& surface,
  const std::vector<int>& points, const std::vector<double>& rotations,
  const std::vector<LightSource>& lights, double uniformIrradiance, int uniformSamples,
  bool shadows, std::vector<double>& q, const std::function<bool()>& abort = {});

/**
 * ComputeSurfacePointIrradiance kept across the calls of an interactive
 * session on one surface and one set of points (the distributed Surface
 * Irradiance's per-light cache; IrradianceCache is the serial filter's):
 *  - the uniform light's term per point (its occlusion sampling), kept while
 *    its irradiance, samples and the shadow flag stay the same;
 *  - each directional, point or spot light's corner terms (3 values per
 *    triangle around each point: DirectIrradiance() times the visibility of
 *    the point's shadow ray), kept while every field of the light and the
 *    shadow flag stay the same;
 *  - the surface's measures and ray caster.
 * So a change of one light recomputes that light only. SetSurface() forgets
 * everything. The result equals ComputeSurfacePointIrradiance() of the same
 * arguments bit for bit: each corner sums the uniform term, then each
 * light's in the order of `lights`, as the full computation does (a light
 * that does not reach a corner adds 0.0).
 *
 * Memory: 24 bytes per triangle corner of the points and light, 8 per point
 * for the uniform light, the surface and its ray caster (GetMemoryBytes()).
 */
class SurfacePointIrradianceCache
{
public:
  SurfacePointIrradianceCache();
  ~SurfacePointIrradianceCache();
  SurfacePointIrradianceCache(const SurfacePointIrradianceCache&) = delete;
  SurfacePointIrradianceCache& operator=(const SurfacePointIrradianceCache&) = delete;

  /// The surface and the points to compute (indices into surface.Points,
  /// with their uniform-light sample rotations, as ComputeSurfacePointIrradiance).
  /// Forgets every kept term. Throws translucency::Error if a point is not
  /// one of the surface's or the sizes differ.
  void SetSurface(BoundarySurface surface, std::vector<int> points, std::vector<double> rotations);
  /// Whether SetSurface was called since construction or Clear().
  bool HasSurface() const;
  const BoundarySurface& GetSurface() const;

  /**
   * ComputeSurfacePointIrradiance(surface, points, rotations, lights, ...)
   * of the SetSurface arguments, re-using the kept terms. Same errors and
   * abort contract; an aborted call keeps the terms that were complete.
   */
  bool Compute(const std::vector<LightSource>& lights, double uniformIrradiance,
    int uniformSamples, bool shadows, std::vector<double>& q,
    const std::function<bool()>& abort = {});

  ///@{
  /// What the last Compute() computed (the rest came from the cache): the
  /// number of lights, and whether the uniform light's term.
  int GetNumberOfLightsComputed() const;
  bool GetUniformComputed() const;
  ///@}

  /// Forget the surface and every kept term.
  void Clear();
  /// Bytes held (surface, measures, kept terms; about those of the ray caster).
  std::size_t GetMemoryBytes() const;

private:
  struct Impl;
  std::unique_ptr<Impl> Impl_;
};

} // namespace translucency
