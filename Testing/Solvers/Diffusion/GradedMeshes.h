/**
 * @file GradedMeshes.h
 * @brief Graded tet meshes of the diffuse-optics tests (TestDiffuseOptics,
 * TestTimeResolved): fine where the closed-form solutions are compared,
 * coarse towards the far faces.
 */
#pragma once

#include "TestMeshes.h"
#include "TetMesh.h"

#include <cmath>
#include <cstddef>
#include <memory>

namespace translucency
{
namespace testing
{

/// x = l g(u) for u in [-1, 1]: uniform cells of size r / (u0 n / 2) in
/// |x| <= r (the first u0 n / 2 cells from the centre), then growing
/// linearly to the faces at |x| = l (g is C1).
inline double Stretch(double u, double r, double l, double u0)
{
  const double v = std::abs(u);
  const double slope = r / u0;
  const double x = v <= u0 ? slope * v
                           : r + slope * (v - u0) +
      (l - r - slope * (1.0 - u0)) * (v - u0) * (v - u0) / ((1.0 - u0) * (1.0 - u0));
  return u < 0 ? -x : x;
}

/// A cube [-l, l]^3 of n^3 Kuhn-split cells, uniform within |x|,|y|,|z| <= r
/// (a fraction u0 of the cells along each axis), stretched beyond.
inline std::unique_ptr<TetMesh> GradedCube(int n, double r, double l, double u0)
{
  MeshData data = CubeMesh(n, 2.0);
  for (double& x : data.Points)
  {
    x = Stretch(x - 1.0, r, l, u0);
  }
  auto mesh = std::make_unique<TetMesh>();
  mesh->SetGeometry(data.Points, data.Tets);
  return mesh;
}

/// A box [-lx, lx] x [-lx, lx] x [-lz, 0] (the lit face z = 0 on top), cells
/// graded towards the axis x = y = 0 and towards z = 0.
inline std::unique_ptr<TetMesh> GradedSlab(int nxy, int nz, double lx, double lz, double a)
{
  MeshData data = BoxMesh(nxy, nxy, nz, 2.0, 2.0, 1.0);
  for (std::size_t i = 0; i < data.Points.size(); i += 3)
  {
    for (int d = 0; d < 2; ++d)
    {
      const double u = data.Points[i + d] - 1.0;
      data.Points[i + d] = lx * u * (a + (1.0 - a) * std::abs(u));
    }
    const double w = 1.0 - data.Points[i + 2]; // depth in [0, 1]
    data.Points[i + 2] = -lz * w * (a + (1.0 - a) * w);
  }
  auto mesh = std::make_unique<TetMesh>();
  mesh->SetGeometry(data.Points, data.Tets);
  return mesh;
}

} // namespace testing
} // namespace translucency
