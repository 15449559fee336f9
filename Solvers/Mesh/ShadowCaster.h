/**
 * @file ShadowCaster.h
 * @brief Any-hit (shadow, occlusion) rays against a triangle surface, for
 * the visibility of the boundary irradiance's lights: through Embree
 * (Intel's ray-tracing kernels, Debian libembree-dev) when the build has
 * it, else through RayCaster.
 *
 * Why Embree here: the uniform light's occlusion sampling (32 rays per
 * boundary point) was 57 % of Surface Irradiance's CPU time at 1M tets in
 * RayCaster's scalar any-hit traversal; Embree's wide-node SIMD traversal is
 * the library made for that job (Documentation/Performance.md, "ParaView
 * pipeline"). RayCaster stays the caster of the queries that need its exact
 * double-precision contract (closest hits, the radiosity form factors, the
 * grid solver's and the cut's geometry).
 *
 * Semantics: a ray with an origin (mm) and a direction of any non-zero length
 * (normalised here) is occluded when it hits a triangle (either face) at a
 * distance t (mm) with 0 < t < tMax. With Embree the test runs in single
 * precision on coordinates taken relative to the centre of the surface's
 * box, with Embree's robust (watertight) traversal: a ray that grazes a
 * triangle's edge or starts within about 1e-7 of the box's size from a
 * triangle may be answered differently from RayCaster's double-precision
 * test. The callers offset their origins by 1e-5 of the box's diagonal
 * from the surface, so that only grazing rays can differ
 * (TestShadowCaster measures how many).
 *
 * Thread safety: Occluded() may be called by any number of threads at once;
 * Build() must not run concurrently with queries.
 */
#pragma once

#include "RayCaster.h"

#include <cstddef>
#include <memory>
#include <vector>

namespace translucency
{

class ShadowCaster
{
public:
  ShadowCaster();
  ~ShadowCaster();
  ShadowCaster(const ShadowCaster&) = delete;
  ShadowCaster& operator=(const ShadowCaster&) = delete;

  /**
   * Build the acceleration structure over `triangles` (3 point ids each) of
   * `points` (3 coordinates each, mm). Copies what it needs. Throws
   * translucency::Error for an id out of range, a non-finite coordinate,
   * sizes not a multiple of 3 (as RayCaster::Build) or an error of Embree.
   * An empty list gives a caster that hits nothing.
   */
  void Build(const std::vector<double>& points, const std::vector<int>& triangles);

  /// True if the ray hits a triangle at a distance t (mm) in (0, tMax);
  /// tMax may be infinity. A zero or non-finite direction hits nothing.
  bool Occluded(const double origin[3], const double direction[3], double tMax) const;

  /// Whether this build answers through Embree (else RayCaster).
  static bool UsesEmbree();

  /// About the bytes held (the triangles and the tree).
  std::size_t GetMemoryBytes() const;

private:
  struct EmbreeScene;
  std::unique_ptr<EmbreeScene> Embree_;
  RayCaster Fallback_;
  std::size_t Triangles_ = 0;
};

} // namespace translucency
