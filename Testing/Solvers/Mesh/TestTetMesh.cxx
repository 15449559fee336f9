// TetMesh: topology and measures of structured box meshes, where every count
// and measure is known in closed form, and the input checks.

#include "Error.h"
#include "Radiance.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TetMesh.h"

#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <set>
#include <string>

namespace
{

using namespace translucency;
using namespace translucency::testing;

TetMesh Build(const MeshData& data)
{
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  return mesh;
}

class BoxMeshTest : public ::testing::TestWithParam<double> // jitter
{
};

TEST_P(BoxMeshTest, CountsAndMeasures)
{
  const int nx = 3, ny = 4, nz = 5;
  const double lx = 2.0, ly = 3.0, lz = 1.5;
  const MeshData data = BoxMesh(nx, ny, nz, lx, ly, lz, GetParam(), 7);
  const TetMesh mesh = Build(data);
  ASSERT_EQ(mesh.GetNumberOfPoints(), (nx + 1) * (ny + 1) * (nz + 1));
  ASSERT_EQ(mesh.GetNumberOfTets(), 6 * nx * ny * nz);

  // Two triangles per boundary cell face.
  EXPECT_EQ(mesh.GetNumberOfBoundaryTriangles(), 4 * (nx * ny + ny * nz + nx * nz));
  // Boundary points: all grid points but the interior ones.
  EXPECT_EQ(static_cast<int>(mesh.GetBoundaryPoints().size()),
    mesh.GetNumberOfPoints() - (nx - 1) * (ny - 1) * (nz - 1));

  const double volume = lx * ly * lz;
  const double area = 2.0 * (lx * ly + ly * lz + lx * lz);
  const double tetVolumes =
    std::accumulate(mesh.GetTetVolumes().begin(), mesh.GetTetVolumes().end(), 0.0);
  EXPECT_NEAR(tetVolumes, volume, 1e-12 * volume);
  const double sumV =
    std::accumulate(mesh.GetVertexVolumes().begin(), mesh.GetVertexVolumes().end(), 0.0);
  EXPECT_NEAR(sumV, 4.0 * volume, 1e-12 * volume); // each tet counted by its 4 vertices
  const double sumS =
    std::accumulate(mesh.GetBoundaryAreas().begin(), mesh.GetBoundaryAreas().end(), 0.0);
  EXPECT_NEAR(sumS, 3.0 * area, 1e-12 * area); // each triangle counted by its 3 vertices
  const double triangleAreas = std::accumulate(
    mesh.GetBoundaryTriangleAreas().begin(), mesh.GetBoundaryTriangleAreas().end(), 0.0);
  EXPECT_NEAR(triangleAreas, area, 1e-12 * area);

  // Volumes positive (Kuhn tets of odd permutations came in negative).
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    ASSERT_GT(mesh.GetTetVolume(t), 0.0);
  }

  // Boundary triangles lie on a box face and their normal points out of it.
  const double centre[3] = { 0.5 * lx, 0.5 * ly, 0.5 * lz };
  const double size[3] = { lx, ly, lz };
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    const int* tri = &mesh.GetBoundaryTriangles()[3 * f];
    const double* p0 = mesh.GetPoint(tri[0]);
    const double* p1 = mesh.GetPoint(tri[1]);
    const double* p2 = mesh.GetPoint(tri[2]);
    const double e1[3] = { p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2] };
    const double e2[3] = { p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2] };
    const double n[3] = {
      e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]
    };
    const int axis = static_cast<int>(
      std::max_element(n, n + 3, [](double a, double b) { return std::abs(a) < std::abs(b); }) - n);
    // The triangle lies in the plane x_axis = 0 or x_axis = size[axis].
    const double side = p0[axis] > centre[axis] ? 1.0 : -1.0;
    for (const double* p : { p0, p1, p2 })
    {
      ASSERT_NEAR(p[axis], side > 0 ? size[axis] : 0.0, 1e-12);
    }
    EXPECT_GT(n[axis] * side, 0.0) << "triangle " << f << " points inwards";
    // The owning tet contains the triangle.
    const int* tv = mesh.GetTet(mesh.GetBoundaryTriangleTets()[f]);
    for (int m = 0; m < 3; ++m)
    {
      EXPECT_TRUE(std::find(tv, tv + 4, tri[m]) != tv + 4);
    }
  }

  // Point normals: the normalised sum over the box faces at the point of
  // (area of the point's triangles on that face) x (face normal). Inside a
  // face that is the face normal; at edges and corners the Kuhn diagonals
  // give the faces different areas around the point.
  std::vector<std::array<double, 3>> faceArea(mesh.GetNumberOfPoints(), { 0.0, 0.0, 0.0 });
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    const int* tri = &mesh.GetBoundaryTriangles()[3 * f];
    const double* p0 = mesh.GetPoint(tri[0]);
    const double* p1 = mesh.GetPoint(tri[1]);
    const double* p2 = mesh.GetPoint(tri[2]);
    int axis = 0;
    for (int d = 0; d < 3; ++d)
    {
      if (p0[d] == p1[d] && p0[d] == p2[d])
      {
        axis = d; // the coordinate shared by the three vertices
      }
    }
    const double sign = p0[axis] > centre[axis] ? 1.0 : -1.0;
    // Area from the two in-plane coordinates.
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double a =
      0.5 * std::abs((p1[u] - p0[u]) * (p2[v] - p0[v]) - (p1[v] - p0[v]) * (p2[u] - p0[u]));
    for (int m = 0; m < 3; ++m)
    {
      faceArea[tri[m]][axis] += sign * a;
    }
  }
  for (int i : mesh.GetBoundaryPoints())
  {
    const double* n = &mesh.GetPointNormals()[3 * i];
    const std::array<double, 3>& e = faceArea[i];
    const double length = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    for (int d = 0; d < 3; ++d)
    {
      EXPECT_NEAR(n[d], e[d] / length, 1e-12) << "point " << i;
    }
  }
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    if (!mesh.IsBoundaryPoint(i))
    {
      EXPECT_EQ(mesh.GetBoundaryAreas()[i], 0.0);
      EXPECT_EQ(mesh.GetPointNormals()[3 * i], 0.0);
    }
  }
}

TEST_P(BoxMeshTest, SparsityPattern)
{
  const MeshData data = BoxMesh(4, 3, 3, 1.0, 1.0, 1.0, GetParam(), 3);
  const TetMesh mesh = Build(data);
  const int n = mesh.GetNumberOfPoints();
  const std::vector<int>& rows = mesh.GetRowOffsets();
  const std::vector<int>& cols = mesh.GetColumnIndices();
  ASSERT_EQ(static_cast<int>(rows.size()), n + 1);
  ASSERT_EQ(rows.back(), mesh.GetNumberOfNonZeros());

  // Reference adjacency from the tets.
  std::vector<std::set<int>> adjacency(n);
  for (int i = 0; i < n; ++i)
  {
    adjacency[i].insert(i);
  }
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    const int* tv = mesh.GetTet(t);
    for (int a = 0; a < 4; ++a)
    {
      for (int b = 0; b < 4; ++b)
      {
        adjacency[tv[a]].insert(tv[b]);
      }
    }
  }
  for (int i = 0; i < n; ++i)
  {
    const std::vector<int> row(cols.begin() + rows[i], cols.begin() + rows[i + 1]);
    EXPECT_EQ(row, std::vector<int>(adjacency[i].begin(), adjacency[i].end())) << "row " << i;
    EXPECT_EQ(cols[mesh.GetDiagonalPositions()[i]], i);
    EXPECT_GE(mesh.GetDiagonalPositions()[i], rows[i]);
    EXPECT_LT(mesh.GetDiagonalPositions()[i], rows[i + 1]);
  }
  // A Kuhn interior vertex has 14 neighbours.
  const int interior = 1 + 5 * (1 + 4 * 1); // grid point (1, 1, 1)
  EXPECT_EQ(rows[interior + 1] - rows[interior], 15);

  // Tet entry positions point at (row tet[a], column tet[b]).
  const std::vector<int>& positions = mesh.GetTetNonZeroPositions();
  ASSERT_EQ(positions.size(), 16u * mesh.GetNumberOfTets());
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    const int* tv = mesh.GetTet(t);
    for (int a = 0; a < 4; ++a)
    {
      for (int b = 0; b < 4; ++b)
      {
        const int p = positions[16 * t + 4 * a + b];
        ASSERT_GE(p, rows[tv[a]]);
        ASSERT_LT(p, rows[tv[a] + 1]);
        ASSERT_EQ(cols[p], tv[b]);
      }
    }
  }

  // Point -> tet incidence.
  const std::vector<int>& offsets = mesh.GetPointTetOffsets();
  size_t total = 0;
  for (int i = 0; i < n; ++i)
  {
    for (int k = offsets[i]; k < offsets[i + 1]; ++k)
    {
      const int* tv = mesh.GetTet(mesh.GetPointTets()[k]);
      EXPECT_TRUE(std::find(tv, tv + 4, i) != tv + 4);
    }
    total += offsets[i + 1] - offsets[i];
  }
  EXPECT_EQ(total, 4u * mesh.GetNumberOfTets());
}

namespace
{
/// Number of colours, and whether two chunks of one colour share a point.
int CheckColours(const TetMesh& mesh, bool& disjoint)
{
  const TetMesh::ScatterSchedule& s = mesh.GetScatterSchedule();
  disjoint = true;
  std::vector<int> owner(mesh.GetNumberOfPoints());
  for (int c = 0; c < s.GetNumberOfColours(); ++c)
  {
    std::fill(owner.begin(), owner.end(), -1);
    for (int k = s.ColourOffsets[c]; k < s.ColourOffsets[c + 1]; ++k)
    {
      for (int m = s.ChunkOffsets[k]; m < s.ChunkOffsets[k + 1]; ++m)
      {
        const int* tv = mesh.GetTet(s.Tets[m]);
        for (int a = 0; a < 4; ++a)
        {
          disjoint = disjoint && (owner[tv[a]] == -1 || owner[tv[a]] == k);
          owner[tv[a]] = k;
        }
      }
    }
  }
  return s.GetNumberOfColours();
}
} // namespace

TEST_P(BoxMeshTest, ScatterScheduleColoursAreVertexDisjoint)
{
  const MeshData data = BoxMesh(12, 10, 9, 1.0, 1.0, 1.0, GetParam(), 5);
  const TetMesh mesh = Build(data);
  const TetMesh::ScatterSchedule& s = mesh.GetScatterSchedule();
  std::vector<int> all = s.Tets;
  std::sort(all.begin(), all.end());
  std::vector<int> expected(mesh.GetNumberOfTets());
  std::iota(expected.begin(), expected.end(), 0);
  ASSERT_EQ(all, expected); // every tet exactly once
  bool disjoint = false;
  EXPECT_GT(CheckColours(mesh, disjoint), 1);
  EXPECT_TRUE(disjoint);
}

// Each boundary point lists exactly the boundary triangles that have it, in
// increasing id order; the refractive index summed over those lists in
// parallel has the bits of the serial loop over the triangles.
TEST_P(BoxMeshTest, BoundaryPointTrianglesAndRefractiveIndex)
{
  const MeshData data = BoxMesh(7, 5, 6, 2.0, 1.0, 1.5, GetParam(), 3);
  const TetMesh mesh = Build(data);
  const std::vector<int>& points = mesh.GetBoundaryPoints();
  const std::vector<int>& offsets = mesh.GetBoundaryPointTriangleOffsets();
  const std::vector<int>& list = mesh.GetBoundaryPointTriangles();
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  ASSERT_EQ(offsets.size(), points.size() + 1);
  std::vector<std::vector<int>> expected(mesh.GetNumberOfPoints());
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    for (int m = 0; m < 3; ++m)
    {
      expected[triangles[3 * f + m]].push_back(f);
    }
  }
  for (size_t k = 0; k < points.size(); ++k)
  {
    const std::vector<int> got(list.begin() + offsets[k], list.begin() + offsets[k + 1]);
    EXPECT_EQ(got, expected[points[k]]) << "boundary point " << points[k];
  }

  // Serial reference: eta_i = sum_f S_f eta_t(f) / S_i over the triangles.
  std::mt19937_64 rng(11);
  std::vector<double> tetEta(mesh.GetNumberOfTets());
  for (double& e : tetEta)
  {
    e = 1.0 + Uniform01(rng);
  }
  std::vector<double> reference(mesh.GetNumberOfPoints(), 0.0);
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    for (int m = 0; m < 3; ++m)
    {
      reference[triangles[3 * f + m]] +=
        mesh.GetBoundaryTriangleAreas()[f] * tetEta[mesh.GetBoundaryTriangleTets()[f]];
    }
  }
  const std::vector<double> eta = BoundaryPointRefractiveIndex(mesh, tetEta);
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    const double want = mesh.IsBoundaryPoint(i) ? reference[i] / mesh.GetBoundaryAreas()[i] : 0.0;
    ASSERT_EQ(eta[i], want) << "point " << i;
  }
}

INSTANTIATE_TEST_SUITE_P(Jitter, BoxMeshTest, ::testing::Values(0.0, 0.2));


// The scatter walks a spatially ordered mesh in its own tet order (the
// per-tet arrays are indexed by tet id), also after a cut, which keeps the
// order but changes the bounding box and so the Morton curve; a mesh whose
// tet order is scattered in space falls back to the Morton curve.
TEST(TetMesh, ScatterScheduleFollowsTheTetOrderOfASpatiallyOrderedMesh)
{
  const MeshData box = BoxMesh(24, 20, 18, 3.0, 2.0, 2.0, 0.2, 12);
  std::vector<int> pointOrder, tetOrder;
  TetMesh::ComputeSpatialOrder(box.Points, box.Tets, pointOrder, tetOrder);
  const MeshData ordered = translucency::testing::Permute(box, pointOrder, tetOrder);
  // Keep the tets with a vertex left of x = 1.1 (as TetCut does: order kept,
  // points renumbered in order).
  MeshData cut;
  std::vector<int> newId(ordered.NumberOfPoints(), -1);
  for (int t = 0; t < ordered.NumberOfTets(); ++t)
  {
    const int* tv = &ordered.Tets[4 * static_cast<size_t>(t)];
    bool keep = false;
    for (int a = 0; a < 4; ++a)
    {
      keep = keep || ordered.Points[3 * static_cast<size_t>(tv[a])] < 1.1;
    }
    if (keep)
    {
      for (int a = 0; a < 4; ++a)
      {
        newId[tv[a]] = 0;
      }
    }
  }
  int next = 0;
  for (int i = 0; i < ordered.NumberOfPoints(); ++i)
  {
    if (newId[i] == 0)
    {
      newId[i] = next++;
      cut.Points.insert(cut.Points.end(), &ordered.Points[3 * static_cast<size_t>(i)],
        &ordered.Points[3 * static_cast<size_t>(i)] + 3);
    }
  }
  for (int t = 0; t < ordered.NumberOfTets(); ++t)
  {
    const int* tv = &ordered.Tets[4 * static_cast<size_t>(t)];
    if (newId[tv[0]] >= 0 && newId[tv[1]] >= 0 && newId[tv[2]] >= 0 && newId[tv[3]] >= 0)
    {
      for (int a = 0; a < 4; ++a)
      {
        cut.Tets.push_back(newId[tv[a]]);
      }
    }
  }
  ASSERT_LT(cut.NumberOfTets(), ordered.NumberOfTets());
  ASSERT_GT(cut.NumberOfTets(), ordered.NumberOfTets() / 4);
  for (const MeshData* data : std::array<const MeshData*, 2>{ &ordered, &cut })
  {
    const TetMesh mesh = Build(*data);
    const TetMesh::ScatterSchedule& s = mesh.GetScatterSchedule();
    bool disjoint = false;
    const int colours = CheckColours(mesh, disjoint);
    EXPECT_TRUE(disjoint);
    EXPECT_GT(colours, 1);
    EXPECT_LE(colours, 64);
    // Every chunk is a run of consecutive tet ids.
    for (size_t k = 0; k + 1 < s.ChunkOffsets.size(); ++k)
    {
      for (int m = s.ChunkOffsets[k] + 1; m < s.ChunkOffsets[k + 1]; ++m)
      {
        ASSERT_EQ(s.Tets[m], s.Tets[m - 1] + 1) << "chunk " << k;
      }
    }
  }

  // The same box with its tets shuffled: chunks of consecutive ids would
  // touch the whole box and all conflict (one colour per chunk); the
  // schedule takes the Morton curve instead.
  MeshData shuffled = ordered;
  std::vector<int> perm(ordered.NumberOfTets());
  std::iota(perm.begin(), perm.end(), 0);
  std::mt19937 rng(5);
  std::shuffle(perm.begin(), perm.end(), rng);
  for (size_t t = 0; t < perm.size(); ++t)
  {
    std::copy_n(&ordered.Tets[4 * static_cast<size_t>(perm[t])], 4, &shuffled.Tets[4 * t]);
  }
  const TetMesh mesh = Build(shuffled);
  const int numChunks = static_cast<int>(mesh.GetScatterSchedule().ChunkOffsets.size()) - 1;
  ASSERT_GT(numChunks, 64); // enough chunks for the in-order colouring to exceed 64
  bool disjoint = false;
  const int colours = CheckColours(mesh, disjoint);
  EXPECT_TRUE(disjoint);
  EXPECT_LE(colours, 64);
  std::vector<int> all = mesh.GetScatterSchedule().Tets;
  std::sort(all.begin(), all.end());
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    ASSERT_EQ(all[t], t);
  }
}

TEST(TetMesh, UpdatePointsRescalesMeasures)
{
  const MeshData data = BoxMesh(3, 3, 3, 1.0, 1.0, 1.0, 0.2, 9);
  TetMesh mesh = Build(data);
  const std::vector<double> volumes = mesh.GetTetVolumes();
  const std::vector<double> areas = mesh.GetBoundaryAreas();
  std::vector<double> scaled = data.Points;
  for (double& x : scaled)
  {
    x *= 2.0;
  }
  mesh.UpdatePoints(scaled);
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    EXPECT_NEAR(mesh.GetTetVolume(t), 8.0 * volumes[t], 1e-12);
  }
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    EXPECT_NEAR(mesh.GetBoundaryAreas()[i], 4.0 * areas[i], 1e-12);
  }
  // Inverting a tet by a point move is an error; the mesh keeps its points.
  std::vector<double> mirrored = scaled;
  for (size_t k = 0; k < mirrored.size(); k += 3)
  {
    mirrored[k] = -mirrored[k];
  }
  const std::string message = ErrorMessage([&] { mesh.UpdatePoints(mirrored); });
  EXPECT_TRUE(Contains(message, "tet 0 is inverted")) << message;
  EXPECT_EQ(mesh.GetPoints(), scaled);
}

TEST(TetMesh, PointsUsedByNoTetAreAllowed)
{
  MeshData data = BoxMesh(1, 1, 1, 1.0, 1.0, 1.0);
  data.Points.insert(data.Points.end(), { 5.0, 5.0, 5.0 });
  const TetMesh mesh = Build(data);
  const int orphan = mesh.GetNumberOfPoints() - 1;
  EXPECT_FALSE(mesh.IsBoundaryPoint(orphan));
  EXPECT_EQ(mesh.GetVertexVolumes()[orphan], 0.0);
  EXPECT_EQ(mesh.GetRowOffsets()[orphan + 1] - mesh.GetRowOffsets()[orphan], 1);
}

TEST(TetMesh, PointsWithoutTets)
{
  TetMesh mesh;
  mesh.SetGeometry({ 0, 0, 0, 1, 2, 3 }, {});
  EXPECT_EQ(mesh.GetNumberOfPoints(), 2);
  EXPECT_EQ(mesh.GetNumberOfTets(), 0);
  EXPECT_EQ(mesh.GetNumberOfBoundaryTriangles(), 0);
  EXPECT_EQ(mesh.GetRowOffsets(), (std::vector<int>{ 0, 1, 2 }));
  EXPECT_EQ(mesh.GetScatterSchedule().GetNumberOfColours(), 0);
  mesh.SetGeometry({}, {});
  EXPECT_EQ(mesh.GetNumberOfPoints(), 0);
}

TEST(TetMesh, SpatialOrderIsAPermutationAndIdempotent)
{
  const MeshData data = BoxMesh(6, 5, 4, 3.0, 2.0, 1.0, 0.2, 11);
  std::vector<int> pointOrder, tetOrder;
  TetMesh::ComputeSpatialOrder(data.Points, data.Tets, pointOrder, tetOrder);
  std::vector<int> sortedPoints = pointOrder, sortedTets = tetOrder;
  std::sort(sortedPoints.begin(), sortedPoints.end());
  std::sort(sortedTets.begin(), sortedTets.end());
  for (int k = 0; k < data.NumberOfPoints(); ++k)
  {
    ASSERT_EQ(sortedPoints[k], k);
  }
  for (int k = 0; k < data.NumberOfTets(); ++k)
  {
    ASSERT_EQ(sortedTets[k], k);
  }
  // The reordered mesh is in spatial order already.
  const MeshData ordered = translucency::testing::Permute(data, pointOrder, tetOrder);
  std::vector<int> pointOrder2, tetOrder2;
  TetMesh::ComputeSpatialOrder(ordered.Points, ordered.Tets, pointOrder2, tetOrder2);
  for (int k = 0; k < data.NumberOfPoints(); ++k)
  {
    ASSERT_EQ(pointOrder2[k], k);
  }
  for (int k = 0; k < data.NumberOfTets(); ++k)
  {
    ASSERT_EQ(tetOrder2[k], k);
  }
}

TEST(TetMesh, BuildIsIndependentOfThreadCount)
{
  // Serial twin of the parallel loops of SetGeometry and ComputeSpatialOrder.
  const MeshData data = BoxMesh(14, 12, 11, 3.0, 2.0, 2.0, 0.25, 13);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  TetMesh serial = Build(data);
  std::vector<int> pointOrder1, tetOrder1;
  TetMesh::ComputeSpatialOrder(data.Points, data.Tets, pointOrder1, tetOrder1);
  omp_set_num_threads(2);
  TetMesh parallel = Build(data);
  std::vector<int> pointOrder2, tetOrder2;
  TetMesh::ComputeSpatialOrder(data.Points, data.Tets, pointOrder2, tetOrder2);
  omp_set_num_threads(saved);
  EXPECT_EQ(serial.GetTets(), parallel.GetTets());
  EXPECT_EQ(serial.GetTetVolumes(), parallel.GetTetVolumes());
  EXPECT_EQ(serial.GetBoundaryTriangles(), parallel.GetBoundaryTriangles());
  EXPECT_EQ(serial.GetBoundaryTriangleTets(), parallel.GetBoundaryTriangleTets());
  EXPECT_EQ(serial.GetBoundaryPoints(), parallel.GetBoundaryPoints());
  EXPECT_EQ(serial.GetVertexVolumes(), parallel.GetVertexVolumes());
  EXPECT_EQ(serial.GetBoundaryAreas(), parallel.GetBoundaryAreas());
  EXPECT_EQ(serial.GetPointNormals(), parallel.GetPointNormals());
  EXPECT_EQ(serial.GetRowOffsets(), parallel.GetRowOffsets());
  EXPECT_EQ(serial.GetColumnIndices(), parallel.GetColumnIndices());
  EXPECT_EQ(serial.GetTetNonZeroPositions(), parallel.GetTetNonZeroPositions());
  EXPECT_EQ(serial.GetDiagonalPositions(), parallel.GetDiagonalPositions());
  EXPECT_EQ(serial.GetPointTets(), parallel.GetPointTets());
  EXPECT_EQ(serial.GetScatterSchedule().Tets, parallel.GetScatterSchedule().Tets);
  EXPECT_EQ(serial.GetScatterSchedule().ChunkOffsets, parallel.GetScatterSchedule().ChunkOffsets);
  EXPECT_EQ(
    serial.GetScatterSchedule().ColourOffsets, parallel.GetScatterSchedule().ColourOffsets);
  EXPECT_EQ(pointOrder1, pointOrder2);
  EXPECT_EQ(tetOrder1, tetOrder2);
}

// ---- input checks: every message names the culprit ----

TEST(TetMeshErrors, VertexIdOutOfRange)
{
  MeshData data = BoxMesh(2, 2, 2, 1.0, 1.0, 1.0);
  data.Tets[4 * 17 + 2] = 1200;
  const std::string message = ErrorMessage([&] { Build(data); });
  EXPECT_TRUE(Contains(message, "tet 17")) << message;
  EXPECT_TRUE(Contains(message, "1200")) << message;
  EXPECT_TRUE(Contains(message, "27 points")) << message;
  data.Tets[4 * 17 + 2] = -1;
  EXPECT_TRUE(Contains(ErrorMessage([&] { Build(data); }), "tet 17"));
}

TEST(TetMeshErrors, RepeatedVertexId)
{
  MeshData data = BoxMesh(2, 2, 2, 1.0, 1.0, 1.0);
  data.Tets[4 * 5 + 3] = data.Tets[4 * 5 + 0];
  const std::string message = ErrorMessage([&] { Build(data); });
  EXPECT_TRUE(Contains(message, "tet 5 repeats")) << message;
}

TEST(TetMeshErrors, DegenerateTet)
{
  MeshData data = BoxMesh(1, 1, 1, 1.0, 1.0, 1.0);
  // Tet 6 = (0, 1, 8, 9) below the cube, with point 9 on the line through
  // points 0 = (0, 0, 0) and 1 = (1, 0, 0): volume 0.
  data.Points.insert(data.Points.end(), { 0.5, 0.5, -1.0, 0.25, 0.0, 0.0 });
  data.Tets.insert(data.Tets.end(), { 0, 1, 8, 9 });
  const std::string message = ErrorMessage([&] { Build(data); });
  EXPECT_TRUE(Contains(message, "tet 6 is degenerate")) << message;
  EXPECT_TRUE(Contains(message, "vertices 0, 1, 8, 9")) << message;
}

TEST(TetMeshErrors, NonFiniteCoordinate)
{
  MeshData data = BoxMesh(2, 2, 2, 1.0, 1.0, 1.0);
  data.Points[3 * 13 + 1] = std::numeric_limits<double>::quiet_NaN();
  std::string message = ErrorMessage([&] { Build(data); });
  EXPECT_TRUE(Contains(message, "point 13")) << message;
  data.Points[3 * 13 + 1] = std::numeric_limits<double>::infinity();
  message = ErrorMessage([&] { Build(data); });
  EXPECT_TRUE(Contains(message, "point 13")) << message;
}

TEST(TetMeshErrors, FaceSharedByThreeTets)
{
  // Three tets on the triangle (0, 1, 2): apexes above, below and further above.
  const MeshData data{ { 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.2, 1, 0.2, 0.2, -1, 0.3, 0.3, 2 },
    { 0, 1, 2, 3, 0, 1, 2, 4, 0, 1, 2, 5 } };
  const std::string message = ErrorMessage([&] { Build(data); });
  EXPECT_TRUE(Contains(message, "face (0, 1, 2) is shared by 3 tets")) << message;
  EXPECT_TRUE(Contains(message, "tet 0, tet 1, tet 2")) << message;
}

TEST(TetMeshErrors, WrongArraySizes)
{
  EXPECT_TRUE(Contains(ErrorMessage([] { TetMesh().SetGeometry({ 0, 0 }, {}); }), "3 (x, y, z)"));
  EXPECT_TRUE(Contains(ErrorMessage(
                         [] {
                           TetMesh().SetGeometry({ 0, 0, 0 }, { 0, 0, 0 });
                         }),
    "4 per tet"));
}

TEST(TetMeshErrors, FailedSetGeometryKeepsThePreviousMesh)
{
  const MeshData good = BoxMesh(2, 2, 2, 1.0, 1.0, 1.0);
  TetMesh mesh = Build(good);
  MeshData bad = good;
  bad.Tets[3] = 999;
  EXPECT_THROW(mesh.SetGeometry(bad.Points, bad.Tets), Error);
  EXPECT_EQ(mesh.GetNumberOfTets(), good.NumberOfTets());
  EXPECT_EQ(mesh.GetNumberOfBoundaryTriangles(), 48);
}

} // namespace
