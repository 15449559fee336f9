/**
 * @file TestMeshes.h
 * @brief Test and benchmark meshes built from scratch (no files, no VTK).
 *
 * BoxMesh: the box [0, lx] x [0, ly] x [0, lz] cut into nx * ny * nz cube
 * cells, each split into the 6 Kuhn tetrahedra around its main diagonal (a
 * conforming mesh: every cell uses the same diagonal direction). With
 * jitter > 0 the interior vertices move by up to jitter * h along each axis
 * (h the cell size) and the vertices inside a box face move within that face,
 * which gives random well-shaped meshes whose boundary is still the box.
 */
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace translucency
{
namespace testing
{

struct MeshData
{
  std::vector<double> Points; ///< 3 per point (mm)
  std::vector<int> Tets;      ///< 4 per tet
  int NumberOfPoints() const { return static_cast<int>(Points.size() / 3); }
  int NumberOfTets() const { return static_cast<int>(Tets.size() / 4); }
};

/// Uniform double in [0, 1) from a 64-bit Mersenne twister (same sequence on
/// every platform, unlike std::uniform_real_distribution).
inline double Uniform01(std::mt19937_64& rng)
{
  return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);
}

inline MeshData BoxMesh(int nx,
  int ny,
  int nz,
  double lx,
  double ly,
  double lz,
  double jitter = 0.0,
  std::uint64_t seed = 1)
{
  MeshData mesh;
  const int px = nx + 1, py = ny + 1, pz = nz + 1;
  const double h[3] = { lx / nx, ly / ny, lz / nz };
  const int n[3] = { nx, ny, nz };
  auto id = [&](int i, int j, int k) { return i + px * (j + py * k); };
  std::mt19937_64 rng(seed);
  mesh.Points.reserve(3 * static_cast<size_t>(px) * py * pz);
  for (int k = 0; k < pz; ++k)
  {
    for (int j = 0; j < py; ++j)
    {
      for (int i = 0; i < px; ++i)
      {
        const int ijk[3] = { i, j, k };
        for (int d = 0; d < 3; ++d)
        {
          double x = ijk[d] * h[d];
          // A vertex may move along axis d unless it lies on a box face
          // normal to d (so the boundary stays the box).
          const bool free = ijk[d] > 0 && ijk[d] < n[d];
          const double r = Uniform01(rng); // drawn always: same sequence for any jitter
          if (jitter > 0.0 && free)
          {
            x += jitter * h[d] * (2.0 * r - 1.0);
          }
          mesh.Points.push_back(x);
        }
      }
    }
  }
  // Kuhn split: one tet per permutation (p0, p1, p2) of the axes, along the
  // path 0 -> e_p0 -> e_p0 + e_p1 -> (1, 1, 1).
  static const int permutations[6][3] = {
    { 0, 1, 2 }, { 0, 2, 1 }, { 1, 0, 2 }, { 1, 2, 0 }, { 2, 0, 1 }, { 2, 1, 0 }
  };
  mesh.Tets.reserve(24 * static_cast<size_t>(nx) * ny * nz);
  for (int k = 0; k < nz; ++k)
  {
    for (int j = 0; j < ny; ++j)
    {
      for (int i = 0; i < nx; ++i)
      {
        for (const auto& p : permutations)
        {
          int corner[3] = { 0, 0, 0 };
          mesh.Tets.push_back(id(i, j, k));
          for (int step = 0; step < 3; ++step)
          {
            corner[p[step]] = 1;
            mesh.Tets.push_back(id(i + corner[0], j + corner[1], k + corner[2]));
          }
        }
      }
    }
  }
  return mesh;
}

/// Cube [0, l]^3 with n cells per side.
inline MeshData CubeMesh(int n, double l, double jitter = 0.0, std::uint64_t seed = 1)
{
  return BoxMesh(n, n, n, l, l, l, jitter, seed);
}

/// Renumber points and tets: new point k is old point pointOrder[k], likewise tets.
inline MeshData Permute(const MeshData& mesh,
  const std::vector<int>& pointOrder,
  const std::vector<int>& tetOrder)
{
  MeshData out;
  std::vector<int> newId(pointOrder.size());
  out.Points.resize(mesh.Points.size());
  for (size_t k = 0; k < pointOrder.size(); ++k)
  {
    newId[pointOrder[k]] = static_cast<int>(k);
    for (int d = 0; d < 3; ++d)
    {
      out.Points[3 * k + d] = mesh.Points[3 * static_cast<size_t>(pointOrder[k]) + d];
    }
  }
  out.Tets.resize(mesh.Tets.size());
  for (size_t k = 0; k < tetOrder.size(); ++k)
  {
    for (int a = 0; a < 4; ++a)
    {
      out.Tets[4 * k + a] = newId[mesh.Tets[4 * static_cast<size_t>(tetOrder[k]) + a]];
    }
  }
  return out;
}

} // namespace testing
} // namespace translucency
