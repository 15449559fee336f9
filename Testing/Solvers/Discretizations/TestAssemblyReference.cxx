// The DiscreteDivergence assembly (incremental rows included) and the parallel TetMesh
// topology, against independent references written here: a per-tet scatter
// of TransCut eq. 10-14 with the element gradients from an Eigen 3x3 inverse
// (not the shared geometry kernel), a std::map of faces for the boundary, a
// std::set adjacency for the rows; on shuffled (not spatially ordered) random
// meshes with points used by no tet, for 1, 2 and 3 threads.

#include "DiscreteDivergence.h"
#include "Error.h"
#include "FiniteElement.h"
#include "Fresnel.h"
#include "Radiance.h"
#include "TestMeshes.h"
#include "TetMesh.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <vector>

namespace
{

using namespace translucency;
using namespace translucency::testing;

/// A jittered cube with shuffled point and tet ids, randomly flipped tets and
/// `orphans` extra points used by no tet (interleaved with the others).
MeshData ShuffledMesh(int cells, std::uint64_t seed, int orphans)
{
  const MeshData box = CubeMesh(cells, 3.0, 0.25, seed);
  std::mt19937_64 rng(seed + 100);
  const int numPoints = static_cast<int>(box.Points.size() / 3);
  const int numTets = static_cast<int>(box.Tets.size() / 4);
  std::vector<int> pointOrder(numPoints), tetOrder(numTets);
  std::iota(pointOrder.begin(), pointOrder.end(), 0);
  std::iota(tetOrder.begin(), tetOrder.end(), 0);
  std::shuffle(pointOrder.begin(), pointOrder.end(), rng);
  std::shuffle(tetOrder.begin(), tetOrder.end(), rng);
  MeshData out = Permute(box, pointOrder, tetOrder);
  for (size_t t = 0; t < out.Tets.size() / 4; ++t)
  {
    if (rng() % 2)
    {
      std::swap(out.Tets[4 * t + 1], out.Tets[4 * t + 2]); // negative orientation
    }
  }
  // Orphan points: appended, then moved into the middle by a renumbering.
  for (int k = 0; k < orphans; ++k)
  {
    out.Points.push_back(10.0 + k);
    out.Points.push_back(-5.0);
    out.Points.push_back(1.0);
  }
  const int total = numPoints + orphans;
  std::vector<int> order(total);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<int> identity(out.Tets.size() / 4);
  std::iota(identity.begin(), identity.end(), 0);
  return Permute(out, order, identity);
}

OpticalProperties RandomMaterial(int numTets, std::uint64_t seed)
{
  std::mt19937_64 rng(seed);
  OpticalProperties m;
  for (int t = 0; t < numTets; ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      m.AbsorptionCoefficient.push_back(0.01 + 0.5 * Uniform01(rng));
      m.ReducedScatteringCoefficient.push_back(0.2 + 3.0 * Uniform01(rng));
    }
    m.RefractiveIndex.push_back(1.2 + 0.3 * Uniform01(rng));
  }
  return m;
}

std::vector<double> RandomIrradiance(int numPoints, std::uint64_t seed)
{
  std::mt19937_64 rng(seed);
  std::vector<double> q(3 * static_cast<size_t>(numPoints));
  for (double& v : q)
  {
    v = 2.0 * Uniform01(rng);
  }
  return q;
}

/// Independent reference: dense per-entry sums of eq. 10-14 scattered per
/// tet, with grad(beta_a) from the inverse of the 3x3 edge matrix, and the
/// boundary terms from the mesh's S_i with eta_i as area-weighted mean of
/// the eta of the boundary triangles' tets (eq. 11-13).
struct Reference
{
  std::array<std::map<std::pair<int, int>, double>, 3> Entries;
  std::array<std::vector<double>, 3> Rhs;
};

Reference ReferenceAssembly(const TetMesh& mesh, const OpticalProperties& m,
  const std::vector<double>& q)
{
  Reference r;
  const int numPoints = mesh.GetNumberOfPoints();
  for (int c = 0; c < 3; ++c)
  {
    r.Rhs[c].assign(numPoints, 0.0);
  }
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    const int* tv = mesh.GetTet(t);
    Eigen::Matrix3d e;
    for (int k = 0; k < 3; ++k)
    {
      for (int d = 0; d < 3; ++d)
      {
        e(k, d) = mesh.GetPoint(tv[k + 1])[d] - mesh.GetPoint(tv[0])[d];
      }
    }
    const double volume = std::abs(e.determinant()) / 6.0;
    // Rows of e^-T... gradients of beta_1..3 are the columns of e^-1.
    const Eigen::Matrix3d inv = e.inverse();
    Eigen::Vector3d grad[4];
    for (int k = 0; k < 3; ++k)
    {
      grad[k + 1] = inv.col(k);
    }
    grad[0] = -(grad[1] + grad[2] + grad[3]);
    for (int c = 0; c < 3; ++c)
    {
      const double mu = m.AbsorptionCoefficient[3 * t + c];
      const double kappa = 1.0 / (3.0 * (mu + m.ReducedScatteringCoefficient[3 * t + c]));
      for (int a = 0; a < 4; ++a)
      {
        for (int b = 0; b < 4; ++b)
        {
          // 4 x the P1 stiffness (eq. 10, 14), lumped mass on the diagonal (eq. 13).
          double v = 4.0 * kappa * volume * grad[a].dot(grad[b]);
          if (a == b)
          {
            v += volume * mu;
          }
          r.Entries[c][{ tv[a], tv[b] }] += v;
        }
      }
    }
  }
  std::vector<double> etaArea(numPoints, 0.0);
  const auto& tris = mesh.GetBoundaryTriangles();
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    const double area = mesh.GetBoundaryTriangleAreas()[f];
    for (int k = 0; k < 3; ++k)
    {
      etaArea[tris[3 * f + k]] += area * m.RefractiveIndex[mesh.GetBoundaryTriangleTets()[f]];
    }
  }
  for (int i = 0; i < numPoints; ++i)
  {
    const double s = mesh.GetBoundaryAreas()[i];
    if (mesh.GetPointTetOffsets()[i + 1] == mesh.GetPointTetOffsets()[i])
    {
      for (int c = 0; c < 3; ++c)
      {
        r.Entries[c][{ i, i }] = 1.0; // identity row
      }
      continue;
    }
    if (s <= 0.0)
    {
      continue;
    }
    const double eta = etaArea[i] / s;
    const double a = Fresnel::MismatchA(eta), fdr = Fresnel::DiffuseReflectance(eta);
    for (int c = 0; c < 3; ++c)
    {
      r.Entries[c][{ i, i }] += 2.0 * s / (3.0 * a);
      r.Rhs[c][i] = 8.0 * s * q[3 * i + c] / (3.0 * a * (1.0 - fdr));
    }
  }
  return r;
}

void ExpectMatchesReference(const TetMesh& mesh, const DiffusionSystem& system, const Reference& r)
{
  const auto& rows = system.RowOffsets;
  for (int c = 0; c < 3; ++c)
  {
    ASSERT_EQ(system.Values[c].size(), r.Entries[c].size()) << "every reference entry in the pattern";
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      double scale = 0.0;
      for (int k = rows[i]; k < rows[i + 1]; ++k)
      {
        scale = std::max(scale, std::abs(r.Entries[c].at({ i, system.ColumnIndices[k] })));
      }
      for (int k = rows[i]; k < rows[i + 1]; ++k)
      {
        const double expected = r.Entries[c].at({ i, system.ColumnIndices[k] });
        ASSERT_NEAR(system.Values[c][k], expected, 1e-12 * scale)
          << "channel " << c << " row " << i << " column " << system.ColumnIndices[k];
      }
      ASSERT_NEAR(system.RightHandSide[c][i], r.Rhs[c][i], 1e-13 * std::abs(r.Rhs[c][i]))
        << "channel " << c << " row " << i;
    }
  }
}

void ExpectBitIdentical(const DiffusionSystem& a, const DiffusionSystem& b)
{
  ASSERT_EQ(a.ColumnIndices, b.ColumnIndices);
  for (int c = 0; c < 3; ++c)
  {
    ASSERT_EQ(a.Values[c].size(), b.Values[c].size());
    for (size_t k = 0; k < a.Values[c].size(); ++k)
    {
      ASSERT_EQ(a.Values[c][k], b.Values[c][k]) << "channel " << c << " entry " << k;
    }
    ASSERT_EQ(a.RightHandSide[c], b.RightHandSide[c]) << "channel " << c;
  }
}

TEST(DivergenceReference, EqualsIndependentScatterReference)
{
  for (std::uint64_t seed : { 1u, 2u })
  {
    const MeshData data = ShuffledMesh(5, seed, 3);
    TetMesh mesh;
    mesh.SetGeometry(data.Points, data.Tets);
    const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), seed + 10);
    const std::vector<double> q = RandomIrradiance(mesh.GetNumberOfPoints(), seed + 20);
    const Reference r = ReferenceAssembly(mesh, material, q);
    DiscreteDivergence divergence;
    DiffusionSystem system;
    divergence.Assemble(mesh, material, q, system); // fills the geometry cache
    ExpectMatchesReference(mesh, system, r);
    DiffusionSystem again;
    divergence.Assemble(mesh, material, q, again); // from the cache
    ExpectBitIdentical(system, again);
    // M is exactly symmetric (each pair of mirror entries sums the same
    // contributions in the same order).
    for (int c = 0; c < 3; ++c)
    {
      for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
      {
        for (int k = system.RowOffsets[i]; k < system.RowOffsets[i + 1]; ++k)
        {
          const int j = system.ColumnIndices[k];
          const auto begin = system.ColumnIndices.begin() + system.RowOffsets[j];
          const auto end = system.ColumnIndices.begin() + system.RowOffsets[j + 1];
          const auto it = std::lower_bound(begin, end, i);
          ASSERT_TRUE(it != end && *it == i);
          ASSERT_EQ(system.Values[c][k],
            system.Values[c][static_cast<size_t>(it - system.ColumnIndices.begin())])
            << "channel " << c << " entry (" << i << ", " << j << ")";
        }
      }
    }
    // Stiffness rows sum to zero: with mu_a = 0 and no boundary term the
    // diagonal is exactly minus the off-diagonal sum.
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      if (mesh.IsBoundaryPoint(i) || mesh.GetPointTetOffsets()[i + 1] == mesh.GetPointTetOffsets()[i])
      {
        continue;
      }
      double sum = 0.0;
      for (int k = system.RowOffsets[i]; k < system.RowOffsets[i + 1]; ++k)
      {
        sum += system.Values[0][k];
      }
      double mass = 0.0;
      for (int k = mesh.GetPointTetOffsets()[i]; k < mesh.GetPointTetOffsets()[i + 1]; ++k)
      {
        const int t = mesh.GetPointTets()[k];
        mass += mesh.GetTetVolume(t) * material.AbsorptionCoefficient[3 * t];
      }
      EXPECT_NEAR(sum, mass, 1e-12 * std::abs(system.Values[0][mesh.GetDiagonalPositions()[i]]));
    }
  }
}

TEST(DivergenceReference, IdenticalForOneTwoThreeThreadsAndIncrementalRows)
{
  const MeshData data = ShuffledMesh(7, 5, 2);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 6);
  const std::vector<double> q = RandomIrradiance(mesh.GetNumberOfPoints(), 7);
  DiffusionSystem serial;
  {
    DiscreteDivergence divergence;
    divergence.SetNumberOfThreads(1);
    divergence.Assemble(mesh, material, q, serial);
  }
  for (int threads : { 2, 3 })
  {
    DiscreteDivergence divergence;
    divergence.SetNumberOfThreads(threads);
    DiffusionSystem parallel;
    divergence.Assemble(mesh, material, q, parallel);
    ExpectBitIdentical(serial, parallel);
  }
  // Incremental rows after changing 20 % of the tets (enough rows for the
  // parallel path), with and without a valid geometry cache: bit-identical to
  // a full assembly.
  std::mt19937_64 rng(8);
  std::vector<int> changed;
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    if (Uniform01(rng) < 0.2)
    {
      changed.push_back(t);
      material.ReducedScatteringCoefficient[3 * t + 1] *= 1.7;
      material.RefractiveIndex[t] = 1.0 + Uniform01(rng);
    }
  }
  DiffusionSystem full;
  DiscreteDivergence().Assemble(mesh, material, q, full);
  for (int threads : { 1, 2 })
  {
    DiscreteDivergence cached;
    cached.SetNumberOfThreads(threads);
    DiffusionSystem s1;
    cached.Assemble(mesh, RandomMaterial(mesh.GetNumberOfTets(), 6), q, s1);
    ASSERT_TRUE(cached.UpdateTets(mesh, material, q, changed, s1));
    ExpectBitIdentical(full, s1);
    DiscreteDivergence fresh; // no cache: geometry computed per tet
    fresh.SetNumberOfThreads(threads);
    DiffusionSystem s2 = serial;
    ASSERT_TRUE(fresh.UpdateTets(mesh, material, q, changed, s2));
    ExpectBitIdentical(full, s2);
  }
}

TEST(DivergenceReference, InvalidValueIsNamed)
{
  const MeshData data = ShuffledMesh(3, 9, 0);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 10);
  std::vector<double> q = RandomIrradiance(mesh.GetNumberOfPoints(), 11);
  material.ReducedScatteringCoefficient[3 * 17 + 2] = std::nan("");
  DiscreteDivergence divergence;
  DiffusionSystem system;
  try
  {
    divergence.Assemble(mesh, material, q, system);
    FAIL() << "no exception";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("17"), std::string::npos) << e.what();
  }
  material = RandomMaterial(mesh.GetNumberOfTets(), 10);
  q[3 * 5 + 1] = -1.0;
  try
  {
    divergence.Assemble(mesh, material, q, system);
    FAIL() << "no exception";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("point 5"), std::string::npos) << e.what();
  }
  q[3 * 5 + 1] = 1.0;
  divergence.Assemble(mesh, material, q, system); // recovers
}

/// Canonical key of a face.
std::array<int, 3> FaceKey(int a, int b, int c)
{
  std::array<int, 3> k = { a, b, c };
  std::sort(k.begin(), k.end());
  return k;
}

TEST(ParallelTopology, MatchesBruteForceForAnyThreadCount)
{
  const MeshData data = ShuffledMesh(6, 12, 4);
  const int numPoints = static_cast<int>(data.Points.size() / 3);
  const int saved = omp_get_max_threads();
  std::vector<TetMesh> meshes;
  for (int threads : { 1, 2, 3 })
  {
    omp_set_num_threads(threads);
    meshes.emplace_back();
    meshes.back().SetGeometry(data.Points, data.Tets);
  }
  omp_set_num_threads(saved);
  const TetMesh& mesh = meshes[0];
  const int numTets = mesh.GetNumberOfTets();

  // Point -> tet lists: ascending tet ids, each tet once per vertex.
  std::vector<std::vector<int>> pointTets(numPoints);
  for (int t = 0; t < numTets; ++t)
  {
    for (int a = 0; a < 4; ++a)
    {
      pointTets[mesh.GetTet(t)[a]].push_back(t);
    }
  }
  std::vector<int> offsets = { 0 }, flat;
  for (const auto& list : pointTets)
  {
    flat.insert(flat.end(), list.begin(), list.end());
    offsets.push_back(static_cast<int>(flat.size()));
  }
  EXPECT_EQ(mesh.GetPointTetOffsets(), offsets);
  EXPECT_EQ(mesh.GetPointTets(), flat);

  // Rows: std::set adjacency with the diagonal.
  std::vector<std::set<int>> adjacency(numPoints);
  for (int i = 0; i < numPoints; ++i)
  {
    adjacency[i].insert(i);
  }
  for (int t = 0; t < numTets; ++t)
  {
    for (int a = 0; a < 4; ++a)
    {
      for (int b = 0; b < 4; ++b)
      {
        adjacency[mesh.GetTet(t)[a]].insert(mesh.GetTet(t)[b]);
      }
    }
  }
  std::vector<int> rows = { 0 }, columns;
  for (const auto& s : adjacency)
  {
    columns.insert(columns.end(), s.begin(), s.end());
    rows.push_back(static_cast<int>(columns.size()));
  }
  EXPECT_EQ(mesh.GetRowOffsets(), rows);
  EXPECT_EQ(mesh.GetColumnIndices(), columns);
  for (int i = 0; i < numPoints; ++i)
  {
    EXPECT_EQ(columns[mesh.GetDiagonalPositions()[i]], i);
  }

  // Boundary: faces used once, each with its tet; outward = away from the
  // tet's fourth vertex; sorted by (smallest vertex, the two others).
  std::map<std::array<int, 3>, std::vector<int>> faces;
  for (int t = 0; t < numTets; ++t)
  {
    const int* tv = mesh.GetTet(t);
    for (int f = 0; f < 4; ++f)
    {
      faces[FaceKey(tv[(f + 1) % 4], tv[(f + 2) % 4], tv[(f + 3) % 4])].push_back(t);
    }
  }
  std::vector<std::pair<std::array<int, 3>, int>> expected;
  for (const auto& [key, tets] : faces)
  {
    ASSERT_LE(tets.size(), 2u);
    if (tets.size() == 1)
    {
      expected.emplace_back(key, tets[0]);
    }
  }
  const int numBoundary = mesh.GetNumberOfBoundaryTriangles();
  ASSERT_EQ(numBoundary, static_cast<int>(expected.size()));
  const auto& tris = mesh.GetBoundaryTriangles();
  for (int f = 0; f < numBoundary; ++f)
  {
    const int* tri = &tris[3 * f];
    EXPECT_EQ(FaceKey(tri[0], tri[1], tri[2]), expected[f].first) << "triangle " << f;
    const int t = mesh.GetBoundaryTriangleTets()[f];
    EXPECT_EQ(t, expected[f].second);
    const int* tv = mesh.GetTet(t);
    int opposite = -1;
    for (int a = 0; a < 4; ++a)
    {
      if (tv[a] != tri[0] && tv[a] != tri[1] && tv[a] != tri[2])
      {
        opposite = tv[a];
      }
    }
    Eigen::Vector3d p[3], o;
    for (int k = 0; k < 3; ++k)
    {
      p[k] = Eigen::Vector3d(mesh.GetPoint(tri[k]));
    }
    o = Eigen::Vector3d(mesh.GetPoint(opposite));
    EXPECT_LT((p[1] - p[0]).cross(p[2] - p[0]).dot(o - p[0]), 0.0) << "triangle " << f;
  }

  // Scatter positions: entry 4a+b is (row tv[a], column tv[b]).
  const std::vector<int>& positions = mesh.GetTetNonZeroPositions();
  for (int t = 0; t < numTets; ++t)
  {
    const int* tv = mesh.GetTet(t);
    for (int a = 0; a < 4; ++a)
    {
      for (int b = 0; b < 4; ++b)
      {
        const int k = positions[16 * t + 4 * a + b];
        ASSERT_GE(k, rows[tv[a]]);
        ASSERT_LT(k, rows[tv[a] + 1]);
        ASSERT_EQ(columns[k], tv[b]);
      }
    }
  }

  // Every thread count gives the same mesh.
  for (size_t m = 1; m < meshes.size(); ++m)
  {
    EXPECT_EQ(meshes[m].GetTets(), mesh.GetTets());
    EXPECT_EQ(meshes[m].GetPointTets(), mesh.GetPointTets());
    EXPECT_EQ(meshes[m].GetColumnIndices(), mesh.GetColumnIndices());
    EXPECT_EQ(meshes[m].GetDiagonalPositions(), mesh.GetDiagonalPositions());
    EXPECT_EQ(meshes[m].GetBoundaryTriangles(), mesh.GetBoundaryTriangles());
    EXPECT_EQ(meshes[m].GetBoundaryTriangleTets(), mesh.GetBoundaryTriangleTets());
    EXPECT_EQ(meshes[m].GetBoundaryAreas(), mesh.GetBoundaryAreas());
    EXPECT_EQ(meshes[m].GetTetNonZeroPositions(), mesh.GetTetNonZeroPositions());
    EXPECT_EQ(meshes[m].GetScatterSchedule().Tets, mesh.GetScatterSchedule().Tets);
  }
}

TEST(ParallelTopology, CopiesAndPointUpdatesKeepTheSchedule)
{
  const MeshData data = ShuffledMesh(4, 13, 0);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  const TetMesh copy = mesh;
  std::vector<double> moved = data.Points;
  for (double& x : moved)
  {
    x *= 1.5;
  }
  mesh.UpdatePoints(moved); // keeps the schedule of the original points
  TetMesh reference;
  reference.SetGeometry(data.Points, data.Tets);
  EXPECT_EQ(mesh.GetScatterSchedule().Tets, reference.GetScatterSchedule().Tets);
  EXPECT_EQ(copy.GetScatterSchedule().Tets, reference.GetScatterSchedule().Tets);
  EXPECT_EQ(copy.GetTetNonZeroPositions(), reference.GetTetNonZeroPositions());
  // The FEM scatter assembly works on the copy and the moved mesh.
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 14);
  const std::vector<double> q = RandomIrradiance(mesh.GetNumberOfPoints(), 15);
  DiffusionSystem a, b;
  FiniteElement().Assemble(copy, material, q, a);
  FiniteElement().Assemble(reference, material, q, b);
  ExpectBitIdentical(a, b);
  // A mesh without geometry has an empty schedule.
  const TetMesh empty;
  EXPECT_EQ(empty.GetScatterSchedule().GetNumberOfColours(), 0);
  EXPECT_TRUE(empty.GetTetNonZeroPositions().empty());
}

} // namespace
