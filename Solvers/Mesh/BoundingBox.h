/**
 * @file BoundingBox.h
 * @brief The diagonal of a mesh's bounding box: the length scale of the ray
 * offsets and reaches (shadow rays, Monte Carlo launches, collimated beams).
 */
#pragma once

#include "TetMesh.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace translucency
{

/// Length of the diagonal of the axis-aligned box of the mesh points (mm).
inline double BoundingBoxDiagonal(const TetMesh& mesh)
{
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a)
  {
    lo[a] = std::numeric_limits<double>::infinity();
    hi[a] = -lo[a];
  }
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    const double* x = mesh.GetPoint(i);
    for (int a = 0; a < 3; ++a)
    {
      lo[a] = std::min(lo[a], x[a]);
      hi[a] = std::max(hi[a], x[a]);
    }
  }
  return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
    (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

} // namespace translucency
