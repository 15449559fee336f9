#include "SurfaceIntersections.h"

#include "RayCaster.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>

namespace translucency
{
namespace
{
/// The crossing of edge (a, b) with a triangle containing neither, if any.
bool CrossEdge(const RayCaster& caster, const std::vector<double>& points,
  const std::vector<int>& triangles, int a, int b, EdgeCrossing& crossing)
{
  const double* pa = &points[3 * static_cast<size_t>(a)];
  const double* pb = &points[3 * static_cast<size_t>(b)];
  double dir[3] = { pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2] };
  const double length = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
  if (!(length > 0))
  {
    return false;
  }
  for (double& d : dir)
  {
    d /= length;
  }
  const double margin = 1e-6 * length;
  double start = 0.0; // along the edge, mm
  // A ray from a vertex meets the triangles around that vertex at t ~ 0:
  // step past them (a few per edge at most; the cap only bounds the loop).
  for (int step = 0; step < 64; ++step)
  {
    const double origin[3] = { pa[0] + start * dir[0], pa[1] + start * dir[1],
      pa[2] + start * dir[2] };
    double t;
    int tri;
    if (!caster.FirstHit(origin, dir, length - margin - start, t, tri))
    {
      return false;
    }
    const double along = start + t;
    const int* ids = &triangles[3 * static_cast<size_t>(tri)];
    const bool adjacent = ids[0] == a || ids[1] == a || ids[2] == a || ids[0] == b ||
      ids[1] == b || ids[2] == b;
    // An edge in the triangle's plane cannot pierce it: the ray test's
    // determinant is then round-off (1e-18 for the coplanar pieces of a
    // subdivided triangle) and its "hit" is noise. Coplanar overlaps are
    // left to TetGen's -d pass (vtkTetrahedralizeSurface).
    const double* q0 = &points[3 * static_cast<size_t>(ids[0])];
    const double* q1 = &points[3 * static_cast<size_t>(ids[1])];
    const double* q2 = &points[3 * static_cast<size_t>(ids[2])];
    const double e1[3] = { q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2] };
    const double e2[3] = { q2[0] - q0[0], q2[1] - q0[1], q2[2] - q0[2] };
    const double normal[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
      e1[0] * e2[1] - e1[1] * e2[0] };
    const double normalLength =
      std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    const bool inPlane = std::abs(normal[0] * dir[0] + normal[1] * dir[1] + normal[2] * dir[2]) <=
      1e-9 * normalLength;
    if (!adjacent && !inPlane && along > margin)
    {
      crossing.EdgePoints[0] = a;
      crossing.EdgePoints[1] = b;
      crossing.Triangle = tri;
      for (int k = 0; k < 3; ++k)
      {
        crossing.Point[k] = pa[k] + along * dir[k];
      }
      return true;
    }
    start = std::max(along, start) + 1e-3 * margin;
  }
  return false;
}
}

bool FindEdgeCrossing(
  const std::vector<double>& points, const std::vector<int>& triangles, EdgeCrossing& crossing)
{
  RayCaster caster;
  caster.Build(points, triangles); // checks the ids
  std::vector<std::array<int, 2>> edges;
  edges.reserve(triangles.size());
  for (size_t t = 0; t + 2 < triangles.size(); t += 3)
  {
    for (int e = 0; e < 3; ++e)
    {
      const int p = triangles[t + e], q = triangles[t + (e + 1) % 3];
      edges.push_back({ std::min(p, q), std::max(p, q) });
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  const std::int64_t numEdges = static_cast<std::int64_t>(edges.size());
  std::atomic<std::int64_t> first(numEdges);
#pragma omp parallel for schedule(dynamic, 256)
  for (std::int64_t i = 0; i < numEdges; ++i)
  {
    if (i >= first.load(std::memory_order_relaxed))
    {
      continue;
    }
    EdgeCrossing local;
    if (CrossEdge(caster, points, triangles, edges[i][0], edges[i][1], local))
    {
      std::int64_t current = first.load();
      while (i < current && !first.compare_exchange_weak(current, i))
      {
      }
    }
  }
  const std::int64_t found = first.load();
  if (found == numEdges)
  {
    return false;
  }
  return CrossEdge(caster, points, triangles, edges[found][0], edges[found][1], crossing);
}

} // namespace translucency
