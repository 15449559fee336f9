/**
 * @file RayCaster.h
 * @brief Ray casting against a triangle surface through a bounding volume
 * hierarchy (BVH): shadow and ambient-occlusion rays of the boundary
 * irradiance, and later the visibility of radiosity form factors.
 */
#pragma once

#include <vector>

namespace translucency
{

/**
 * A bounding volume hierarchy over triangles, built once, then queried by
 * any number of threads.
 *
 * Build() sorts the triangles into a binary tree of axis-aligned boxes by the
 * binned surface area heuristic (16 bins on each axis; a median split where
 * the heuristic cannot separate the centroids or the tree gets deep), with at
 * most 4 triangles per leaf. The interior nodes are stored depth-first in one
 * array, each holding the boxes of its two children (single precision,
 * rounded outwards) in one 64-byte cache line, so a traversal step reads one
 * line; the triangles are stored in leaf order, each as a vertex and two edge
 * vectors in double precision.
 *
 * Rays: an origin (mm) and a direction of any non-zero length; the direction
 * is normalised internally (d[k] / std::sqrt(d . d)), so every distance t,
 * tMax and the epsilon are in mm along the ray. A ray hits a triangle at t
 * if Epsilon < t < tMax (both strict). Both faces of a triangle are hit (no
 * back-face culling). Degenerate (zero-area) triangles are never hit. A zero
 * or non-finite direction hits nothing.
 *
 * Intersection: Moller-Trumbore in double precision (inclusive barycentric
 * bounds, so a ray through a shared edge hits at least one of its triangles
 * except for rounding in the last bits: the test is not strictly watertight).
 * Node boxes are padded by 1e-9 of the scene diagonal and the slab test is
 * made conservative for rounding, so the tree never culls a triangle that
 * IntersectTriangle() would hit: the queries give exactly the answer of a
 * loop over all triangles with IntersectTriangle().
 *
 * Thread safety: the const queries keep no state in the object (traversal
 * stack on the caller's stack), so any number of threads may query one
 * RayCaster at the same time, e.g. from an OpenMP loop. Build() and
 * SetEpsilon() must not run concurrently with queries.
 */
class RayCaster
{
public:
  RayCaster() = default;

  /**
   * Build the hierarchy.
   * @param points 3 coordinates per point (mm). Only the points used by a
   *   triangle are read; they must be finite.
   * @param triangles 3 point ids per triangle. Ids are checked.
   * Copies what it needs: the arguments may be freed afterwards. An empty
   * triangle list gives a caster that hits nothing. Throws
   * translucency::Error naming the triangle for an id out of range or a
   * non-finite coordinate, and for array sizes not a multiple of 3. On error
   * the caster is left empty.
   */
  void Build(const std::vector<double>& points, const std::vector<int>& triangles);

  /**
   * Minimum distance t (mm) of a hit: hits with t <= epsilon are ignored,
   * to skip the surface a ray starts on. Default 0 (only hits behind the
   * origin or exactly at it are ignored). Must be >= 0.
   */
  void SetEpsilon(double epsilon);
  double GetEpsilon() const { return Epsilon_; }

  /**
   * True if the ray hits any triangle at a distance t in (epsilon, tMax)
   * (mm). Stops at the first hit found, so it is faster than FirstHit().
   * tMax may be infinity.
   */
  bool Occluded(const double origin[3], const double direction[3], double tMax) const;

  /**
   * The unit direction of a ray that can be cast: false (no hit, for every
   * caster: this one and ShadowCaster's Embree path) when the origin is not
   * finite or the direction is zero or not finite.
   */
  static bool UnitDirection(const double origin[3], const double direction[3], double unit[3]);

  /**
   * Closest hit with t in (epsilon, tMax) (mm). On a hit returns true and
   * sets t (mm along the normalised direction) and triangle (its index in
   * the list given to Build()); otherwise returns false and leaves them
   * unchanged. Among triangles hit at exactly the same t (a ray through a
   * shared edge), which one is returned is unspecified.
   */
  bool FirstHit(const double origin[3], const double direction[3], double tMax, double& t,
    int& triangle) const;

  /**
   * The ray-triangle test the queries use (Moller-Trumbore, double
   * precision; both faces). direction must already be normalised as the
   * queries do it (see the class comment) for the t to agree. On a hit with
   * tMin < t < tMax returns true and sets t; degenerate triangles and rays
   * parallel to the triangle's plane give false.
   */
  static bool IntersectTriangle(const double origin[3], const double direction[3],
    const double a[3], const double b[3], const double c[3], double tMin, double tMax, double& t);

  int GetNumberOfTriangles() const { return static_cast<int>(TriangleIds_.size()); }
  /// Interior nodes of the tree (0 when it is a single leaf or empty).
  int GetNumberOfNodes() const { return static_cast<int>(Nodes_.size()); }
  /// Depth of the tree: nodes on the longest root-to-leaf path, the leaf
  /// included (a single leaf has depth 1; 0 when empty).
  int GetDepth() const { return Depth_; }

  /// Longest root-to-leaf path the traversal stack can hold.
  static constexpr int MaxDepth = 128;

private:
  /// A subtree: interior node Ref if Count == 0, else the leaf of the
  /// triangles [Ref, Ref + Count) in leaf order. Count < 0: empty tree.
  struct Child
  {
    int Ref = 0;
    int Count = -1;
  };

  /// An interior node: the boxes of its two children (min x, y, z then
  /// max x, y, z, mm; padded and rounded outwards to float) and the
  /// children themselves. 64 bytes, one cache line.
  struct alignas(64) Node
  {
    float Bounds[2][6];
    Child Children[2];
  };

  struct BuildState;
  /// Builds the subtree of state.Order[begin, end) into `nodes` (depth-first
  /// order, node indices local to `nodes`); large ranges build their two
  /// halves as OpenMP tasks into separate vectors that are then spliced, so
  /// the tree is the serial one whatever the number of threads.
  static Child BuildSubtree(BuildState& state, std::vector<Node>& nodes, int& maxDepth, int begin,
    int end, int depth, double box[6]);

  /// Shared traversal; AnyHit stops at the first hit.
  template <bool AnyHit>
  bool Traverse(const double origin[3], const double direction[3], double tMax, double& t,
    int& triangle) const;

  std::vector<Node> Nodes_;
  Child Root_;
  double RootBounds_[6] = { 0, 0, 0, 0, 0, 0 }; ///< padded box of everything (mm)
  /// Per triangle in leaf order: vertex a, edge b - a, edge c - a (9 doubles).
  std::vector<double> Triangles_;
  /// Index in the Build() list of each triangle in leaf order.
  std::vector<int> TriangleIds_;
  double Epsilon_ = 0.0;
  int Depth_ = 0;
};

} // namespace translucency
