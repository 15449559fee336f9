/**
 * @file RadiosityScene.h
 * @brief The scene of translucent radiosity (TranslucentRadiosity,
 * Sec. 3): several objects, translucent tet meshes and opaque diffuse
 * surfaces, cut into patches (triangles), with one ray caster over all of
 * them for shadows and form-factor visibility.
 */
#pragma once

#include "ResourceLimits.h"

#include "LightSources.h"
#include "OpticalProperties.h"
#include "RayCaster.h"

#include <memory>
#include <string>
#include <vector>

namespace translucency
{

class TetMesh;

/**
 * One object of a radiosity scene.
 *
 * Opaque diffuse surface: Points (3 per point, mm), Triangles (3 point ids
 * each) and Albedo (3 values R, G, B per triangle, in [0, 1]). Patches are
 * one-sided: the lit side is the one the normal (p1 - p0) x (p2 - p0) points
 * to; light arriving at the back of a patch is absorbed.
 *
 * Translucent object: Mesh (a tet mesh, shared, not copied) and Material (one
 * coefficient set per tet). Its patches are the mesh's boundary triangles,
 * lit from outside (outward normals).
 */
struct RadiosityObject
{
  std::string Name;
  bool Translucent = false;
  std::vector<double> Points;
  std::vector<int> Triangles;
  std::vector<double> Albedo;
  std::shared_ptr<const TetMesh> Mesh;
  OpticalProperties Material;
};

/**
 * All patches of all objects in one list: object k owns the patches
 * [GetPatchOffset(k), GetPatchOffset(k + 1)), in the order of its triangles
 * (opaque) or of TetMesh::GetBoundaryTriangles() (translucent).
 *
 * Vectors "per patch" hold 3 values per patch (R, G, B), patch-major.
 */
class RadiosityScene
{
public:
  /**
   * Add an opaque diffuse surface. Throws translucency::Error naming the
   * object and the triangle for an albedo outside [0, 1] or not finite, a
   * point id out of range, a non-finite coordinate, a zero-area triangle or
   * wrong array sizes. Returns the object index.
   */
  int AddOpaque(const std::string& name, std::vector<double> points, std::vector<int> triangles,
    std::vector<double> albedo);

  /**
   * Add a translucent tet mesh. The material is validated (named object,
   * tet, channel, value); an empty material is the error "translucent object
   * without coefficients". Returns the object index.
   */
  int AddTranslucent(
    const std::string& name, std::shared_ptr<const TetMesh> mesh, OpticalProperties material);

  /**
   * Replace the material of translucent object k (translucency change; the
   * patches and the geometry are unchanged). Validated like AddTranslucent().
   */
  void SetMaterial(int k, OpticalProperties material);

  /**
   * Replace the albedo of opaque object k (3 per triangle, checked like
   * AddOpaque()); geometry and patches are unchanged.
   */
  void SetAlbedo(int k, std::vector<double> albedo);

  /**
   * Gather the patches and (buildRayCaster) build the ray caster. Call after
   * the last Add*. Without the ray caster (call BuildRayCaster() later) the
   * patches can be compared with another scene's cheaply.
   */
  void Build(bool buildRayCaster = true);
  /// Build the BVH over the patches (after Build(false)).
  void BuildRayCaster() { Caster_.Build(Points_, Triangles_); }

  int GetNumberOfObjects() const { return static_cast<int>(Objects_.size()); }
  const RadiosityObject& GetObject(int k) const { return Objects_[k]; }
  int GetNumberOfPatches() const { return static_cast<int>(PatchObject_.size()); }
  int GetPatchOffset(int k) const { return PatchOffsets_[k]; }
  /// Object index of each patch.
  const std::vector<int>& GetPatchObject() const { return PatchObject_; }
  /// All patch vertices (3 per point, mm) and patches (3 ids each, into these points).
  const std::vector<double>& GetPoints() const { return Points_; }
  const std::vector<int>& GetTriangles() const { return Triangles_; }
  /// Per patch: centroid (3, mm), unit normal (3), area (mm^2).
  const std::vector<double>& GetCentroids() const { return Centroids_; }
  const std::vector<double>& GetNormals() const { return Normals_; }
  const std::vector<double>& GetAreas() const { return Areas_; }
  /// Refractive index per patch (1 for opaque patches).
  const std::vector<double>& GetPatchEta() const { return PatchEta_; }
  /// Diagonal of the bounding box of the scene (mm).
  double GetDiagonal() const { return Diagonal_; }
  /// Distance (mm) rays start off a surface: 1e-6 times the diagonal.
  double GetRayOffset() const { return 1e-6 * Diagonal_; }
  /// BVH over all patches; FirstHit() returns patch ids.
  const RayCaster& GetRayCaster() const { return Caster_; }

  /**
   * Throw translucency::Error if a point or spot light lies inside a closed
   * object (a translucent mesh, or an opaque surface whose every edge is
   * shared by exactly two of its triangles) on the back side of its
   * surface: an odd number of crossings of a ray from the light with the
   * object's triangles, the nearest one seen from behind. (A light inside a
   * closed room whose walls face inwards is fine.) Also validates the
   * lights (power, direction, cone; uniform lights are not accepted).
   */
  void CheckLights(const std::vector<LightSource>& lights) const;

  /**
   * Direct light at every patch centroid, with shadows (a ray towards the
   * light through the whole scene) when `shadows` is set.
   * @param incident irradiance arriving on each patch (W/mm^2, per patch)
   * @param transmitted for translucent patches the part transmitted into the
   *   medium, with the Fresnel transmittance at the angle of incidence
   *   (DirectIrradiance()); for opaque patches equal to incident.
   * OpenMP-parallel over patches; the result does not depend on the thread
   * count. Calls CheckLights() first.
   */
  void ComputeDirectIrradiance(const std::vector<LightSource>& lights, bool shadows,
    std::vector<double>& incident, std::vector<double>& transmitted) const;

  /**
   * Closed axis-aligned box surface [lo, hi] as triangles, each face cut into
   * a grid of squares of side about `cellSize` (mm; at least 1 per face),
   * each square into 2 triangles. inward: normals point into the box (the
   * walls of a room), else outward (a block). skipFace (-1 for none) leaves
   * one face out: 0/1 = x min/max, 2/3 = y min/max, 4/5 = z min/max (an open
   * box). faceIds (optional) receives the face number of each triangle.
   *
   * Memory: the patch count is computed before anything is allocated; at
   * ~1 KB per patch (geometry, BVH, form-factor rows, radiosity vectors)
   * above `memoryLimit` (default GetDefaultMemoryLimit(), 8 GiB) an Error
   * states the patches, the bytes and the override.
   */
  static void BoxSurface(const double lo[3], const double hi[3], double cellSize, bool inward,
    int skipFace, std::vector<double>& points, std::vector<int>& triangles,
    std::vector<int>* faceIds = nullptr, std::size_t memoryLimit = GetDefaultMemoryLimit());

private:
  void ValidateMaterial(const RadiosityObject& object) const;

  std::vector<RadiosityObject> Objects_;
  std::vector<int> PatchOffsets_{ 0 };
  std::vector<int> PatchObject_;
  std::vector<double> Points_;
  std::vector<int> Triangles_;
  std::vector<double> Centroids_;
  std::vector<double> Normals_;
  std::vector<double> Areas_;
  std::vector<double> PatchEta_;
  /// Closed objects (every edge shared by two triangles of the object).
  std::vector<bool> Closed_;
  double Diagonal_ = 0.0;
  RayCaster Caster_;
};

} // namespace translucency
