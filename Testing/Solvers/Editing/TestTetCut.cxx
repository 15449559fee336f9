// TetCut (TransCut Sec. 5.1: delete the tets on the removed side, relax the
// cross-section) checked against the invariants of issue 4 after every cut:
// positive volumes, minimum dihedral angle >= the bound (or not worse than
// before for a tet already below it), only removed-side vertices move and
// none crosses the cutting surface, no complete tet of the removed side is
// left, every other tet is kept, ids map back to the input. The dihedral
// angles and volumes are recomputed here with formulas of their own.

#include "Error.h"
#include "TestMeshes.h"
#include "TetCut.h"

#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace
{

using namespace translucency;
using translucency::testing::BoxMesh;
using translucency::testing::MeshData;
using translucency::testing::Uniform01;

constexpr double Pi = 3.14159265358979323846;

/// Smallest dihedral angle (degrees), from the angle between the two other
/// vertices seen from each edge, projected perpendicular to the edge (not the
/// face normals TetCut uses).
double ReferenceMinDihedral(const double* p[4])
{
  static const int edges[6][4] = { { 0, 1, 2, 3 }, { 0, 2, 1, 3 }, { 0, 3, 1, 2 }, { 1, 2, 0, 3 },
    { 1, 3, 0, 2 }, { 2, 3, 0, 1 } };
  double smallest = 180.0;
  for (const auto& e : edges)
  {
    const double* a = p[e[0]];
    const double* b = p[e[1]];
    double axis[3], u[3], v[3];
    double len2 = 0.0;
    for (int d = 0; d < 3; ++d)
    {
      axis[d] = b[d] - a[d];
      len2 += axis[d] * axis[d];
    }
    double du = 0.0, dv = 0.0;
    for (int d = 0; d < 3; ++d)
    {
      u[d] = p[e[2]][d] - a[d];
      v[d] = p[e[3]][d] - a[d];
      du += u[d] * axis[d];
      dv += v[d] * axis[d];
    }
    double uu = 0.0, vv = 0.0, uv = 0.0;
    for (int d = 0; d < 3; ++d)
    {
      u[d] -= du / len2 * axis[d];
      v[d] -= dv / len2 * axis[d];
      uu += u[d] * u[d];
      vv += v[d] * v[d];
      uv += u[d] * v[d];
    }
    const double c = std::max(-1.0, std::min(1.0, uv / std::sqrt(uu * vv)));
    smallest = std::min(smallest, std::acos(c) * 180.0 / Pi);
  }
  return smallest;
}

double Volume(const double* p[4])
{
  const double* a = p[0];
  double u[3], v[3], w[3];
  for (int d = 0; d < 3; ++d)
  {
    u[d] = p[1][d] - a[d];
    v[d] = p[2][d] - a[d];
    w[d] = p[3][d] - a[d];
  }
  // Triple product u . (v x w).
  return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
           u[2] * (v[0] * w[1] - v[1] * w[0])) /
    6.0;
}

/// The box mesh with every tet positively oriented (TetCut's input contract;
/// half of the Kuhn tets come out negative).
MeshData OrientedBox(int nx, int ny, int nz, double jitter, std::uint64_t seed)
{
  MeshData mesh = BoxMesh(nx, ny, nz, nx, ny, nz, jitter, seed);
  for (int t = 0; t < mesh.NumberOfTets(); ++t)
  {
    const double* p[4];
    for (int a = 0; a < 4; ++a)
    {
      p[a] = &mesh.Points[3 * mesh.Tets[4 * t + a]];
    }
    if (Volume(p) < 0.0)
    {
      std::swap(mesh.Tets[4 * t + 2], mesh.Tets[4 * t + 3]);
    }
  }
  return mesh;
}

/// The tets not entirely on the removed side (side > 0 at all four
/// vertices), in input order: what a cut must keep.
std::vector<int> NotRemovedTets(const MeshData& mesh, const std::vector<double>& side)
{
  std::vector<int> kept;
  for (int t = 0; t < mesh.NumberOfTets(); ++t)
  {
    bool removed = true;
    for (int a = 0; a < 4; ++a)
    {
      removed = removed && side[mesh.Tets[4 * t + a]] > 0.0;
    }
    if (!removed)
    {
      kept.push_back(t);
    }
  }
  return kept;
}

/// F at every mesh point (the side values TetCut::Cut takes).
std::vector<double> SideValues(const MeshData& mesh, const TetCut::SideFunction& F)
{
  std::vector<double> side(mesh.NumberOfPoints());
  for (int i = 0; i < mesh.NumberOfPoints(); ++i)
  {
    side[i] = F(&mesh.Points[3 * i]);
  }
  return side;
}

/// Cut `mesh` with F and check every invariant; returns the cut.
TetCut CutAndCheck(const MeshData& mesh, const TetCut::SideFunction& F, double bound,
  int iterations = 10, double rho = 0.1)
{
  const std::vector<double> side = SideValues(mesh, F);
  TetCut cut;
  cut.SetMinimumDihedralAngle(bound);
  cut.SetNumberOfIterations(iterations);
  cut.SetRelaxationFactor(rho);
  cut.Cut(mesh.Points, mesh.Tets, side, F);

  const std::vector<int>& keptTets = cut.GetKeptTets();
  const std::vector<int>& keptPoints = cut.GetKeptPoints();
  const std::vector<double>& points = cut.GetPoints();
  const std::vector<int>& tets = cut.GetTets();
  EXPECT_EQ(tets.size(), 4 * keptTets.size());
  EXPECT_EQ(points.size(), 3 * keptPoints.size());

  // Exactly the tets not entirely on the removed side are kept, in order.
  const std::vector<int> expectedTets = NotRemovedTets(mesh, side);
  EXPECT_EQ(keptTets, expectedTets);
  EXPECT_TRUE(std::is_sorted(keptPoints.begin(), keptPoints.end()));

  // Ids: output tet k is input tet keptTets[k] with the same vertices, in order.
  std::vector<int> used(keptPoints.size(), 0);
  for (size_t k = 0; k < keptTets.size(); ++k)
  {
    for (int a = 0; a < 4; ++a)
    {
      const int local = tets[4 * k + a];
      EXPECT_GE(local, 0);
      EXPECT_LT(local, static_cast<int>(keptPoints.size()));
      if (local < 0 || local >= static_cast<int>(keptPoints.size()))
      {
        return cut;
      }
      EXPECT_EQ(keptPoints[local], mesh.Tets[4 * keptTets[k] + a]) << "tet " << k;
      used[local] = 1;
    }
  }
  // No orphan point.
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0);

  // Moves: only removed-side points move, and none crosses the surface.
  int moved = 0, movable = 0;
  for (size_t i = 0; i < keptPoints.size(); ++i)
  {
    const double* x0 = &mesh.Points[3 * keptPoints[i]];
    const double* x = &points[3 * i];
    const bool hasMoved = x[0] != x0[0] || x[1] != x0[1] || x[2] != x0[2];
    movable += side[keptPoints[i]] > 0.0;
    if (hasMoved)
    {
      ++moved;
      EXPECT_GT(side[keptPoints[i]], 0.0) << "a kept-side point moved: " << keptPoints[i];
      EXPECT_GE(F(x), 0.0) << "point " << keptPoints[i] << " crossed the cutting surface";
    }
  }
  EXPECT_EQ(cut.GetNumberOfMovedVertices(), moved);
  EXPECT_EQ(cut.GetNumberOfMovableVertices(), movable);
  EXPECT_GE(cut.GetNumberOfBlockedVertices(), 0);
  EXPECT_LE(cut.GetNumberOfBlockedVertices(), movable);

  // Geometry: positive volume, min dihedral >= the bound unless it was
  // already lower before (then not lower than before).
  int bad = 0;
  for (size_t k = 0; k < keptTets.size() && bad < 5; ++k)
  {
    const double* p[4];
    const double* p0[4];
    for (int a = 0; a < 4; ++a)
    {
      p[a] = &points[3 * tets[4 * k + a]];
      p0[a] = &mesh.Points[3 * mesh.Tets[4 * keptTets[k] + a]];
    }
    const double volume = Volume(p);
    const double before = ReferenceMinDihedral(p0);
    const double after = ReferenceMinDihedral(p);
    const bool ok = volume > 0.0 && after >= std::min(bound, before) - 1e-9;
    bad += !ok;
    EXPECT_GT(volume, 0.0) << "tet " << keptTets[k];
    EXPECT_GE(after, std::min(bound, before) - 1e-9)
      << "tet " << keptTets[k] << ": min dihedral " << after << " (was " << before << ")";
  }
  return cut;
}

TetCut::SideFunction Plane(const double origin[3], const double normal[3])
{
  const std::array<double, 3> o{ { origin[0], origin[1], origin[2] } };
  const std::array<double, 3> n{ { normal[0], normal[1], normal[2] } };
  return [o, n](const double* x) {
    return (x[0] - o[0]) * n[0] + (x[1] - o[1]) * n[1] + (x[2] - o[2]) * n[2];
  };
}

TEST(TetCut, PlaneCutKeepsTheInvariantsAndRelaxes)
{
  const MeshData mesh = OrientedBox(8, 8, 8, 0.3, 3);
  const double o[3] = { 4.1, 4.0, 3.9 }, n[3] = { 1.0, 0.3, -0.2 };
  const TetCut::SideFunction F = Plane(o, n);
  const TetCut cut = CutAndCheck(mesh, F, 0.5);
  EXPECT_GT(cut.GetKeptTets().size(), 0u);
  EXPECT_LT(cut.GetKeptTets().size(), static_cast<size_t>(mesh.NumberOfTets()));
  EXPECT_GT(cut.GetNumberOfMovedVertices(), 0);
  // The relaxation moves the removed-side vertices towards the plane.
  double before = 0.0, after = 0.0;
  for (size_t i = 0; i < cut.GetKeptPoints().size(); ++i)
  {
    const double f0 = F(&mesh.Points[3 * cut.GetKeptPoints()[i]]);
    if (f0 > 0.0)
    {
      before += f0;
      after += F(&cut.GetPoints()[3 * i]);
    }
  }
  EXPECT_LT(after, before);
}

TEST(TetCut, RandomPlanesAndSpheresKeepTheInvariants)
{
  const MeshData mesh = OrientedBox(7, 6, 5, 0.35, 9);
  std::mt19937_64 rng(21);
  int moved = 0, blocked = 0;
  for (int round = 0; round < 12; ++round)
  {
    SCOPED_TRACE(::testing::Message() << "round " << round);
    const double bound = round % 3 == 0 ? 0.5 : (round % 3 == 1 ? 10.0 : 30.0);
    const double rho = round % 2 == 0 ? 0.1 : 0.6;
    if (round % 2 == 0)
    {
      double o[3], n[3];
      for (int d = 0; d < 3; ++d)
      {
        o[d] = 1.0 + 4.0 * Uniform01(rng);
        n[d] = Uniform01(rng) - 0.5;
      }
      const TetCut cut = CutAndCheck(mesh, Plane(o, n), bound, 10, rho);
      moved += cut.GetNumberOfMovedVertices();
      blocked += cut.GetNumberOfBlockedVertices();
    }
    else
    {
      // Remove a ball (F > 0 inside) or everything outside it.
      const double c[3] = { 7.0 * Uniform01(rng), 6.0 * Uniform01(rng), 5.0 * Uniform01(rng) };
      const double r = 1.5 + 2.0 * Uniform01(rng);
      const double sign = round % 4 == 1 ? 1.0 : -1.0;
      const TetCut cut = CutAndCheck(mesh,
        [c, r, sign](const double* x) {
          const double d = std::sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
            (x[2] - c[2]) * (x[2] - c[2]));
          return sign * (r - d);
        },
        bound, 10, rho);
      moved += cut.GetNumberOfMovedVertices();
      blocked += cut.GetNumberOfBlockedVertices();
    }
  }
  // The checks above are not vacuous: vertices moved, and some were blocked.
  EXPECT_GT(moved, 50);
  EXPECT_GT(blocked, 0);
}

// Classification and compaction run on OpenMP threads: the output (kept
// tets and points, renumbered tets, relaxed coordinates, counts) is the
// same for 1 and 2 threads, and the kept tets are exactly the tets with a
// vertex on the kept side (F <= 0), in input order.
TEST(TetCut, ParallelEqualsSerial)
{
  const MeshData mesh = OrientedBox(12, 11, 10, 0.3, 17);
  const double o[3] = { 6.1, 5.3, 4.9 }, n[3] = { 0.7, -0.4, 0.3 };
  const TetCut::SideFunction F = Plane(o, n);
  const std::vector<double> side = SideValues(mesh, F);
  const std::vector<int> expectedTets = NotRemovedTets(mesh, side);
  const int saved = omp_get_max_threads();
  TetCut cuts[2];
  for (int k = 0; k < 2; ++k)
  {
    omp_set_num_threads(k + 1);
    cuts[k].Cut(mesh.Points, mesh.Tets, side, F);
  }
  omp_set_num_threads(saved);
  EXPECT_EQ(cuts[0].GetKeptTets(), expectedTets);
  EXPECT_EQ(cuts[1].GetKeptTets(), expectedTets);
  EXPECT_EQ(cuts[0].GetKeptPoints(), cuts[1].GetKeptPoints());
  EXPECT_EQ(cuts[0].GetTets(), cuts[1].GetTets());
  EXPECT_EQ(cuts[0].GetPoints(), cuts[1].GetPoints());
  EXPECT_EQ(cuts[0].GetNumberOfMovedVertices(), cuts[1].GetNumberOfMovedVertices());
  EXPECT_GT(cuts[1].GetNumberOfMovedVertices(), 0);
}

TEST(TetCut, NoRelaxationMovesNothing)
{
  const MeshData mesh = OrientedBox(5, 5, 5, 0.2, 4);
  const double o[3] = { 2.6, 2.5, 2.5 }, n[3] = { 0.0, 0.0, 1.0 };
  const TetCut cut = CutAndCheck(mesh, Plane(o, n), 0.5, 0);
  EXPECT_EQ(cut.GetNumberOfMovedVertices(), 0);
  EXPECT_EQ(cut.GetNumberOfSweeps(), 0);
}

TEST(TetCut, CutAwayEverythingOrNothing)
{
  const MeshData mesh = OrientedBox(3, 3, 3, 0.2, 5);
  const TetCut all = CutAndCheck(mesh, [](const double*) { return 1.0; }, 0.5);
  EXPECT_TRUE(all.GetKeptTets().empty());
  EXPECT_TRUE(all.GetKeptPoints().empty());
  const TetCut none = CutAndCheck(mesh, [](const double*) { return -1.0; }, 0.5);
  EXPECT_EQ(none.GetKeptTets().size(), static_cast<size_t>(mesh.NumberOfTets()));
  EXPECT_EQ(none.GetPoints(), mesh.Points);
}

TEST(TetCut, SignedVolumeAndDihedralOfAReferenceTet)
{
  // The corner tet of the unit cube: volume 1/6; dihedral angles 90 degrees at
  // the three edges through the origin, acos(1/sqrt(3)) = 54.7 degrees at the others.
  const double a[3] = { 0, 0, 0 }, b[3] = { 1, 0, 0 }, c[3] = { 0, 1, 0 }, d[3] = { 0, 0, 1 };
  EXPECT_NEAR(TetCut::SignedVolume(a, b, c, d), 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(TetCut::SignedVolume(b, a, c, d), -1.0 / 6.0, 1e-15);
  EXPECT_NEAR(TetCut::MinimumDihedralAngle(a, b, c, d), std::acos(1.0 / std::sqrt(3.0)) * 180.0 / Pi,
    1e-10);
}

TEST(TetCut, BadInputThrows)
{
  const MeshData mesh = OrientedBox(2, 2, 2, 0.0, 1);
  const auto F = [](const double* x) { return x[0] - 1.0; };
  std::vector<double> side(mesh.NumberOfPoints(), 0.0);
  TetCut cut;
  std::vector<double> shortSide(side.begin(), side.end() - 1);
  EXPECT_THROW(cut.Cut(mesh.Points, mesh.Tets, shortSide, F), Error);
  std::vector<int> tets = mesh.Tets;
  tets[5] = mesh.NumberOfPoints();
  try
  {
    cut.Cut(mesh.Points, tets, side, F);
    FAIL() << "an out-of-range point id must throw";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("tet 1"), std::string::npos) << e.what();
  }
  cut.SetRelaxationFactor(1.5);
  EXPECT_THROW(cut.Cut(mesh.Points, mesh.Tets, side, F), Error);
}

} // namespace
