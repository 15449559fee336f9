#include "AimedPencilBeam.h"

#include "Error.h"
#include "RayCaster.h"
#include "TetMesh.h"

#include <cmath>
#include <limits>
#include <sstream>

namespace translucency
{

namespace
{
std::string Format(const std::array<double, 3>& x)
{
  std::ostringstream out;
  out << "(" << x[0] << ", " << x[1] << ", " << x[2] << ")";
  return out.str();
}
}

PencilBeam AimPencilBeam(const TetMesh& mesh, const std::array<double, 3>& start,
  const std::array<double, 3>& towards, const std::array<double, NumberOfChannels>& power,
  const std::string& label)
{
  return AimPencilBeam(mesh.GetPoints(), mesh.GetBoundaryTriangles(), SurfaceTolerance(mesh),
    start, towards, power, label);
}

PencilBeam AimPencilBeam(const std::vector<double>& points, const std::vector<int>& triangles,
  double tolerance, const std::array<double, 3>& start, const std::array<double, 3>& towards,
  const std::array<double, NumberOfChannels>& power, const std::string& label)
{
  const std::string where =
    label + ": from Point 1 " + Format(start) + " towards Point 2 " + Format(towards);
  double direction[3];
  double length2 = 0.0;
  bool finite = true;
  for (int d = 0; d < 3; ++d)
  {
    direction[d] = towards[d] - start[d];
    length2 += direction[d] * direction[d];
    finite = finite && std::isfinite(start[d]) && std::isfinite(towards[d]);
  }
  if (!finite || !std::isfinite(length2))
  {
    throw Error(where + ": the coordinates must be finite");
  }
  if (length2 == 0.0)
  {
    throw Error(where + ": the two points are the same, so the beam has no direction "
                        "(move Point 2 to where the beam should point)");
  }
  // Cast from `backOff` mm behind Point 1, so that a Point 1 on the surface
  // (ParaView places it on the data bounds: the face of a box) or within the
  // surface tolerance of it is its own entry point.
  const double length = std::sqrt(length2);
  const double backOff = tolerance;
  RayCaster caster;
  caster.Build(points, triangles);
  double t = 0.0;
  int triangle = -1;
  double origin[3];
  for (int d = 0; d < 3; ++d)
  {
    origin[d] = start[d] - backOff * direction[d] / length;
  }
  if (!caster.FirstHit(origin, direction, std::numeric_limits<double>::infinity(), t, triangle))
  {
    throw Error(where + ": the beam misses the object (move Point 1 or Point 2 so that the "
                        "line from Point 1 through Point 2 crosses the surface)");
  }
  // Outward normal (p1 - p0) x (p2 - p0) of the hit triangle: an entering
  // beam travels against it.
  const int* ids = &triangles[3 * static_cast<std::size_t>(triangle)];
  const double* p0 = &points[3 * static_cast<std::size_t>(ids[0])];
  const double* p1 = &points[3 * static_cast<std::size_t>(ids[1])];
  const double* p2 = &points[3 * static_cast<std::size_t>(ids[2])];
  const double e1[3] = { p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2] };
  const double e2[3] = { p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2] };
  const double normal[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
    e1[0] * e2[1] - e1[1] * e2[0] };
  const double cosine = normal[0] * direction[0] + normal[1] * direction[1] +
    normal[2] * direction[2];
  if (cosine >= 0.0)
  {
    throw Error(where + ": Point 1 is inside the object (the line leaves the surface first); "
                        "place Point 1 outside, where the beam starts");
  }
  PencilBeam beam;
  for (int d = 0; d < 3; ++d)
  {
    beam.Position[d] = origin[d] + t * direction[d] / length; // t is along the unit direction
    beam.Direction[d] = direction[d];
  }
  beam.Power = power;
  beam.Label = label;
  return beam;
}

} // namespace translucency
