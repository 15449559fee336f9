/**
 * @file SurfaceIntersections.h
 * @brief A fast test of a triangle surface for self-intersection: an edge
 * crossing a triangle it does not belong to, found through the RayCaster's
 * bounding volume hierarchy.
 */
#pragma once

#include <vector>

namespace translucency
{

/// An edge (a, b) of the surface crossing a triangle that contains neither a nor b.
struct EdgeCrossing
{
  int EdgePoints[2] = { -1, -1 }; ///< point ids of the edge, a < b
  int Triangle = -1;              ///< index of the crossed triangle
  double Point[3] = { 0, 0, 0 };  ///< where the edge crosses it (mm)
};

/**
 * Finds an edge of the triangle surface (points: x, y, z per point, mm;
 * triangles: 3 point ids each, checked) crossing a triangle that does not
 * contain either of its endpoints, which two triangles that intersect
 * transversally always have. Returns true and fills `crossing` with the
 * crossing of the lowest-numbered such edge (edges numbered in sorted
 * (a, b) order, so the answer does not depend on the number of threads).
 *
 * Contacts within 1e-6 of an edge's length of its endpoints are not
 * reported (the triangles around a vertex meet there), nor are coplanar
 * overlaps (rays parallel to a triangle miss it): this is a quick first
 * check, O(E log T), to be followed by an exact one; it finds the surfaces
 * whose edges pierce many triangles, on which an exact pairwise test can
 * take minutes. Coordinates must be finite. OpenMP over the edges.
 * Throws translucency::Error for an id out of range.
 */
bool FindEdgeCrossing(
  const std::vector<double>& points, const std::vector<int>& triangles, EdgeCrossing& crossing);

} // namespace translucency
