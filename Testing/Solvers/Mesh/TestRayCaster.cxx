// RayCaster against brute force (every triangle tested with the same
// ray-triangle function), on a sphere, a random triangle soup and a closed
// box seen from inside; input validation; the parallel queries against the
// serial ones. Then ComputeBoundaryIrradiance, which casts the shadow rays:
// shadows of one box on another, the unoccluded uniform light, and its
// OpenMP loop against one thread. Last, FindEdgeCrossing (the quick
// self-intersection check built on the caster).

#include "Error.h"
#include "Fresnel.h"
#include "LightSources.h"
#include "RayCaster.h"
#include "SurfaceIntersections.h"
#include "TestMeshes.h"
#include "TetMesh.h"

#include <map>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace
{

using namespace translucency;
using translucency::testing::Uniform01;

constexpr double Pi = 3.14159265358979323846;
constexpr double Inf = std::numeric_limits<double>::infinity();

struct Surface
{
  std::vector<double> Points; ///< 3 per point
  std::vector<int> Triangles; ///< 3 per triangle
  int NumberOfTriangles() const { return static_cast<int>(Triangles.size() / 3); }
};

struct Ray
{
  double Origin[3];
  double Direction[3]; ///< any length
  double TMax;
};

/// Latitude-longitude sphere: nLat rings of nLon quads (2 triangles each)
/// between the poles, fans at the poles: 2 nLon (nLat - 1) triangles,
/// normals outwards.
Surface UVSphere(int nLat, int nLon, double radius, const double center[3])
{
  Surface s;
  auto add = [&](double x, double y, double z)
  {
    s.Points.push_back(center[0] + radius * x);
    s.Points.push_back(center[1] + radius * y);
    s.Points.push_back(center[2] + radius * z);
  };
  add(0, 0, 1); // north pole: 0
  for (int i = 1; i < nLat; ++i)
  {
    const double theta = Pi * i / nLat;
    for (int j = 0; j < nLon; ++j)
    {
      const double phi = 2 * Pi * j / nLon;
      add(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    }
  }
  add(0, 0, -1); // south pole
  const int south = 1 + (nLat - 1) * nLon;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * nLon + (j % nLon); };
  auto tri = [&](int a, int b, int c) { s.Triangles.insert(s.Triangles.end(), { a, b, c }); };
  for (int j = 0; j < nLon; ++j)
  {
    tri(0, ring(1, j), ring(1, j + 1));
    for (int i = 1; i + 1 < nLat; ++i)
    {
      tri(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1));
      tri(ring(i, j), ring(i + 1, j + 1), ring(i, j + 1));
    }
    tri(south, ring(nLat - 1, j + 1), ring(nLat - 1, j));
  }
  return s;
}

/// n random triangles of size ~0.2 in [0, 1]^3, some of them degenerate
/// (a repeated vertex, or three collinear points).
Surface TriangleSoup(int n, std::mt19937_64& rng)
{
  Surface s;
  for (int f = 0; f < n; ++f)
  {
    double c[3];
    for (double& v : c)
    {
      v = Uniform01(rng);
    }
    const int base = static_cast<int>(s.Points.size() / 3);
    for (int v = 0; v < 3; ++v)
    {
      for (int k = 0; k < 3; ++k)
      {
        s.Points.push_back(c[k] + 0.1 * (2 * Uniform01(rng) - 1));
      }
    }
    if (f % 97 == 0)
    {
      s.Triangles.insert(s.Triangles.end(), { base, base + 1, base + 1 }); // repeated vertex
    }
    else if (f % 89 == 0)
    {
      for (int k = 0; k < 3; ++k) // third vertex on the line of the first two
      {
        s.Points[3 * (base + 2) + k] =
          0.5 * (s.Points[3 * base + k] + s.Points[3 * (base + 1) + k]);
      }
      s.Triangles.insert(s.Triangles.end(), { base, base + 1, base + 2 });
    }
    else
    {
      s.Triangles.insert(s.Triangles.end(), { base, base + 1, base + 2 });
    }
  }
  return s;
}

/// Closed surface of the box [0, size[0]] x [0, size[1]] x [0, size[2]],
/// each face an n x n grid of quads split in 2 triangles (grid points are
/// repeated along the box edges: the triangles of different faces share no
/// point ids, only positions).
Surface BoxSurface(const double size[3], int n)
{
  Surface s;
  for (int axis = 0; axis < 3; ++axis)
  {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side)
    {
      const int base = static_cast<int>(s.Points.size() / 3);
      for (int j = 0; j <= n; ++j)
      {
        for (int i = 0; i <= n; ++i)
        {
          double x[3];
          x[axis] = side * size[axis];
          x[a] = size[a] * i / n;
          x[b] = size[b] * j / n;
          s.Points.insert(s.Points.end(), { x[0], x[1], x[2] });
        }
      }
      auto id = [&](int i, int j) { return base + i + (n + 1) * j; };
      for (int j = 0; j < n; ++j)
      {
        for (int i = 0; i < n; ++i)
        {
          s.Triangles.insert(s.Triangles.end(), { id(i, j), id(i + 1, j), id(i + 1, j + 1) });
          s.Triangles.insert(s.Triangles.end(), { id(i, j), id(i + 1, j + 1), id(i, j + 1) });
        }
      }
    }
  }
  return s;
}

/// Uniform random unit vector; with probability 1/5 one or two components
/// are zeroed (axis-parallel rays exercise the slab test's zero division).
void RandomDirection(std::mt19937_64& rng, double d[3])
{
  const double z = 2 * Uniform01(rng) - 1, phi = 2 * Pi * Uniform01(rng);
  const double r = std::sqrt(std::max(0.0, 1 - z * z));
  d[0] = r * std::cos(phi);
  d[1] = r * std::sin(phi);
  d[2] = z;
  const double u = Uniform01(rng);
  if (u < 0.1)
  {
    d[static_cast<int>(3 * Uniform01(rng))] = 0.0;
  }
  else if (u < 0.2)
  {
    const int keep = static_cast<int>(3 * Uniform01(rng));
    for (int k = 0; k < 3; ++k)
    {
      if (k != keep)
      {
        d[k] = 0.0;
      }
    }
    d[keep] = d[keep] < 0 ? -1.0 : 1.0;
  }
}

/// Rays from uniform origins in [lo, hi]^3; half of them aimed at a uniform
/// point of the middle half of that box (where the test surfaces are), the
/// others in uniform directions. Directions are scaled by a random length in
/// [0.1, 10]; tMax is infinite for half of the rays and uniform in
/// [0, maxReach] otherwise.
std::vector<Ray> RandomRays(int n, double lo, double hi, double maxReach, std::mt19937_64& rng)
{
  std::vector<Ray> rays(n);
  for (Ray& ray : rays)
  {
    for (double& v : ray.Origin)
    {
      v = lo + (hi - lo) * Uniform01(rng);
    }
    RandomDirection(rng, ray.Direction);
    if (Uniform01(rng) < 0.5)
    {
      for (int k = 0; k < 3; ++k)
      {
        ray.Direction[k] = lo + (hi - lo) * (0.25 + 0.5 * Uniform01(rng)) - ray.Origin[k];
      }
    }
    const double scale = 0.1 + 9.9 * Uniform01(rng);
    for (double& v : ray.Direction)
    {
      v *= scale;
    }
    ray.TMax = Uniform01(rng) < 0.5 ? Inf : maxReach * Uniform01(rng);
  }
  return rays;
}

/// The normalisation the RayCaster documents: d[k] / sqrt(d . d).
void Normalise(const double in[3], double out[3])
{
  const double len = std::sqrt(in[0] * in[0] + in[1] * in[1] + in[2] * in[2]);
  for (int k = 0; k < 3; ++k)
  {
    out[k] = in[k] / len;
  }
}

/// Distance to triangle f along the normalised ray, or false.
bool HitTriangle(const Surface& s,
  int f,
  const double o[3],
  const double d[3],
  double tMin,
  double tMax,
  double& t)
{
  const double* a = &s.Points[3 * s.Triangles[3 * f]];
  const double* b = &s.Points[3 * s.Triangles[3 * f + 1]];
  const double* c = &s.Points[3 * s.Triangles[3 * f + 2]];
  return RayCaster::IntersectTriangle(o, d, a, b, c, tMin, tMax, t);
}

/// Closest hit over all triangles, or false.
bool BruteForceFirstHit(const Surface& s, const Ray& ray, double tMin, double& t, int& triangle)
{
  double d[3];
  Normalise(ray.Direction, d);
  bool hit = false;
  double best = ray.TMax;
  for (int f = 0; f < s.NumberOfTriangles(); ++f)
  {
    double tf;
    if (HitTriangle(s, f, ray.Origin, d, tMin, best, tf))
    {
      best = tf;
      triangle = f;
      hit = true;
    }
  }
  if (hit)
  {
    t = best;
  }
  return hit;
}

/// Occluded and FirstHit agree exactly with the brute force on every ray: same
/// hit or miss, same t to the last bit; the same triangle, or another one
/// that the brute force hits at the same t within 1e-12 (a ray through an
/// edge). Returns the number of rays that hit.
int ExpectAgreement(const Surface& s, const RayCaster& caster, const std::vector<Ray>& rays)
{
  int hits = 0, mismatches = 0;
  for (size_t r = 0; r < rays.size(); ++r)
  {
    const Ray& ray = rays[r];
    double tRef = -1, t = -1;
    int triRef = -1, tri = -1;
    const bool hitRef = BruteForceFirstHit(s, ray, caster.GetEpsilon(), tRef, triRef);
    const bool occluded = caster.Occluded(ray.Origin, ray.Direction, ray.TMax);
    const bool hit = caster.FirstHit(ray.Origin, ray.Direction, ray.TMax, t, tri);
    hits += hitRef;
    bool ok = occluded == hitRef && hit == hitRef;
    if (ok && hit)
    {
      ok = t == tRef;
      if (ok && tri != triRef)
      {
        double d[3], tOther;
        Normalise(ray.Direction, d);
        ok = tri >= 0 && tri < s.NumberOfTriangles() &&
          HitTriangle(s, tri, ray.Origin, d, caster.GetEpsilon(), Inf, tOther) &&
          std::abs(tOther - tRef) <= 1e-12 * std::max(1.0, tRef);
      }
    }
    if (!ok && ++mismatches <= 5)
    {
      ADD_FAILURE() << "ray " << r << " from (" << ray.Origin[0] << ", " << ray.Origin[1] << ", "
                    << ray.Origin[2] << ") along (" << ray.Direction[0] << ", " << ray.Direction[1]
                    << ", " << ray.Direction[2] << "), tMax " << ray.TMax << ": brute force hit "
                    << hitRef << " t " << tRef << " triangle " << triRef << "; Occluded "
                    << occluded << ", FirstHit " << hit << " t " << t << " triangle " << tri;
    }
  }
  EXPECT_EQ(mismatches, 0) << "of " << rays.size() << " rays";
  return hits;
}

TEST(RayCaster, SphereAgreesWithBruteForce)
{
  const double center[3] = { 0.3, -0.2, 0.1 };
  const Surface sphere = UVSphere(40, 60, 1.0, center);
  RayCaster caster;
  caster.Build(sphere.Points, sphere.Triangles);
  EXPECT_EQ(caster.GetNumberOfTriangles(), sphere.NumberOfTriangles());
  EXPECT_GT(caster.GetDepth(), 5);
  EXPECT_LE(caster.GetDepth(), RayCaster::MaxDepth);
  std::mt19937_64 rng(7);
  const std::vector<Ray> rays = RandomRays(4000, -2.0, 2.0, 3.0, rng);
  const int hits = ExpectAgreement(sphere, caster, rays);
  EXPECT_GT(hits, 1000); // the test is not vacuous
  EXPECT_LT(hits, 3900);
}

// The build splits large ranges into OpenMP tasks and splices their nodes:
// the tree must be the serial one (same nodes, depth and answers) for any
// number of threads. 33,000 triangles: several levels above the task grain.
TEST(RayCaster, ParallelBuildEqualsSerial)
{
  const double center[3] = { 0.0, 0.0, 0.0 };
  const Surface sphere = UVSphere(120, 140, 1.0, center);
  ASSERT_GT(sphere.NumberOfTriangles(), 4 * 8192);
  const int saved = omp_get_max_threads();
  RayCaster casters[2];
  omp_set_num_threads(1);
  casters[0].Build(sphere.Points, sphere.Triangles);
  omp_set_num_threads(2);
  casters[1].Build(sphere.Points, sphere.Triangles);
  omp_set_num_threads(saved);
  EXPECT_EQ(casters[0].GetNumberOfNodes(), casters[1].GetNumberOfNodes());
  EXPECT_EQ(casters[0].GetDepth(), casters[1].GetDepth());
  std::mt19937_64 rng(5);
  const std::vector<Ray> rays = RandomRays(3000, -2.0, 2.0, 3.0, rng);
  int hits = 0;
  for (const Ray& ray : rays)
  {
    double t[2] = { -1.0, -1.0 };
    int tri[2] = { -1, -1 };
    bool hit[2];
    for (int k = 0; k < 2; ++k)
      hit[k] = casters[k].FirstHit(ray.Origin, ray.Direction, ray.TMax, t[k], tri[k]);
    ASSERT_EQ(hit[0], hit[1]);
    EXPECT_EQ(t[0], t[1]);
    EXPECT_EQ(tri[0], tri[1]);
    hits += hit[0];
  }
  EXPECT_GT(hits, 500); // not vacuous
  ExpectAgreement(sphere, casters[1], rays);
}

TEST(RayCaster, TriangleSoupAgreesWithBruteForce)
{
  std::mt19937_64 rng(11);
  const Surface soup = TriangleSoup(3000, rng);
  RayCaster caster;
  caster.Build(soup.Points, soup.Triangles);
  const std::vector<Ray> rays = RandomRays(4000, -0.5, 1.5, 1.5, rng);
  const int hits = ExpectAgreement(soup, caster, rays);
  EXPECT_GT(hits, 1000);
  EXPECT_LT(hits, 3900);

  // With a minimum distance: hits closer than epsilon are skipped.
  caster.SetEpsilon(0.05);
  EXPECT_EQ(caster.GetEpsilon(), 0.05);
  ExpectAgreement(soup, caster, rays);
}

TEST(RayCaster, ClosedBoxFromInsideAlwaysHits)
{
  const double size[3] = { 2.0, 1.0, 3.0 };
  const Surface box = BoxSurface(size, 12);
  RayCaster caster;
  caster.Build(box.Points, box.Triangles);
  std::mt19937_64 rng(5);
  std::vector<Ray> rays(4000);
  for (Ray& ray : rays)
  {
    for (int k = 0; k < 3; ++k)
    {
      ray.Origin[k] = size[k] * (0.001 + 0.998 * Uniform01(rng));
    }
    RandomDirection(rng, ray.Direction);
    ray.TMax = Inf;
  }
  const int hits = ExpectAgreement(box, caster, rays);
  EXPECT_EQ(hits, static_cast<int>(rays.size()));
  for (const Ray& ray : rays)
  {
    ASSERT_TRUE(caster.Occluded(ray.Origin, ray.Direction, Inf));
    // The distance to the wall the ray leaves through.
    double d[3];
    Normalise(ray.Direction, d);
    double exit = Inf;
    for (int k = 0; k < 3; ++k)
    {
      if (d[k] != 0.0)
      {
        exit = std::min(exit, ((d[k] > 0 ? size[k] : 0.0) - ray.Origin[k]) / d[k]);
      }
    }
    double t;
    int tri;
    ASSERT_TRUE(caster.FirstHit(ray.Origin, ray.Direction, Inf, t, tri));
    EXPECT_NEAR(t, exit, 1e-12 * exit);
    // Stopping just short of the wall: no hit.
    EXPECT_FALSE(caster.Occluded(ray.Origin, ray.Direction, exit * (1 - 1e-9)));
  }
}

TEST(RayCaster, DistanceEpsilonAndDirectionLength)
{
  // The square [-1, 1]^2 at z = 1, two triangles.
  const std::vector<double> points = { -1, -1, 1, 1, -1, 1, 1, 1, 1, -1, 1, 1 };
  const std::vector<int> triangles = { 0, 1, 2, 0, 2, 3 };
  RayCaster caster;
  caster.Build(points, triangles);
  const double o[3] = { 0.2, 0.3, 0.0 };
  const double up[3] = { 0, 0, 1 }, up5[3] = { 0, 0, 5 }, down[3] = { 0, 0, -1 };
  double t = -1;
  int tri = -1;
  ASSERT_TRUE(caster.FirstHit(o, up, Inf, t, tri));
  EXPECT_DOUBLE_EQ(t, 1.0);
  EXPECT_EQ(tri, 1); // (0.2, 0.3) is above the diagonal x = y
  ASSERT_TRUE(caster.FirstHit(o, up5, Inf, t, tri));
  EXPECT_DOUBLE_EQ(t, 1.0) << "t is in mm, whatever the direction's length";
  EXPECT_FALSE(caster.Occluded(o, down, Inf));
  EXPECT_FALSE(caster.Occluded(o, up, 0.999));
  EXPECT_FALSE(caster.Occluded(o, up, 1.0)) << "tMax is exclusive";
  EXPECT_TRUE(caster.Occluded(o, up5, 1.001));
  caster.SetEpsilon(0.999);
  EXPECT_TRUE(caster.Occluded(o, up, Inf));
  caster.SetEpsilon(1.0);
  EXPECT_FALSE(caster.Occluded(o, up, Inf)) << "epsilon is exclusive";
  EXPECT_THROW(caster.SetEpsilon(-1.0), Error);
  // A zero or non-finite direction hits nothing.
  const double zero[3] = { 0, 0, 0 }, nan[3] = { 0, std::nan(""), 1 };
  caster.SetEpsilon(0.0);
  EXPECT_FALSE(caster.Occluded(o, zero, Inf));
  EXPECT_FALSE(caster.FirstHit(o, nan, Inf, t, tri));
}

TEST(RayCaster, CoincidentTrianglesAndDeepTrees)
{
  // 1000 copies of one triangle: no split separates the centroids.
  Surface s;
  s.Points = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
  for (int f = 0; f < 1000; ++f)
  {
    s.Triangles.insert(s.Triangles.end(), { 0, 1, 2 });
  }
  RayCaster caster;
  caster.Build(s.Points, s.Triangles);
  EXPECT_LE(caster.GetDepth(), 12);
  std::mt19937_64 rng(3);
  ExpectAgreement(s, caster, RandomRays(500, -0.5, 1.0, 2.0, rng));

  // Triangles of geometrically shrinking size: the SAH keeps splitting off
  // one triangle at a time, the depth limit switches to median splits.
  Surface nested;
  for (int f = 0; f < 2000; ++f)
  {
    const double h = std::pow(0.98, f);
    const int base = static_cast<int>(nested.Points.size() / 3);
    nested.Points.insert(nested.Points.end(), { h, 0, 0.001 * f, 0, h, 0.001 * f, 0, 0, h });
    nested.Triangles.insert(nested.Triangles.end(), { base, base + 1, base + 2 });
  }
  caster.Build(nested.Points, nested.Triangles);
  EXPECT_LE(caster.GetDepth(), RayCaster::MaxDepth);
  ExpectAgreement(nested, caster, RandomRays(1000, -0.2, 1.2, 2.0, rng));
}

TEST(RayCaster, InvalidInputThrows)
{
  const std::vector<double> points = { 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1 };
  RayCaster caster;
  caster.Build(points, { 0, 1, 2 });
  auto message = [&](const std::vector<double>& p, const std::vector<int>& t)
  {
    try
    {
      caster.Build(p, t);
    }
    catch (const Error& e)
    {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_NE(message(points, { 0, 1, 2, 0, 1, 3, 0, 4, 1 }).find("triangle 2"), std::string::npos);
  EXPECT_NE(message(points, { 0, 1, 2, -1, 1, 3 }).find("triangle 1"), std::string::npos);
  EXPECT_NE(message(points, { 0, 1 }).find("multiple of 3"), std::string::npos);
  EXPECT_NE(message({ 0, 0, 0, 1 }, {}).find("multiple of 3"), std::string::npos);
  std::vector<double> nanPoints = points;
  nanPoints[7] = std::nan("");
  const std::string nanMessage = message(nanPoints, { 0, 1, 3, 0, 2, 3 });
  EXPECT_NE(nanMessage.find("triangle 1"), std::string::npos) << nanMessage;
  EXPECT_NE(nanMessage.find("point 2"), std::string::npos) << nanMessage;
  // After a failed build the caster is empty.
  const double o[3] = { 0.1, 0.1, -1 }, d[3] = { 0, 0, 1 };
  EXPECT_EQ(caster.GetNumberOfTriangles(), 0);
  EXPECT_FALSE(caster.Occluded(o, d, Inf));
}

TEST(RayCaster, EmptyMeshHitsNothing)
{
  const double o[3] = { 0, 0, 0 }, d[3] = { 1, 0, 0 };
  double t;
  int tri;
  RayCaster never;
  EXPECT_FALSE(never.Occluded(o, d, Inf));
  EXPECT_FALSE(never.FirstHit(o, d, Inf, t, tri));
  RayCaster empty;
  empty.Build({}, {});
  EXPECT_EQ(empty.GetNumberOfNodes(), 0);
  EXPECT_FALSE(empty.Occluded(o, d, Inf));
  empty.Build({ 1, 2, 3 }, {});
  EXPECT_FALSE(empty.FirstHit(o, d, Inf, t, tri));
}

TEST(RayCaster, ParallelQueriesEqualSerial)
{
  const double center[3] = { 0, 0, 0 };
  const Surface sphere = UVSphere(50, 80, 1.0, center);
  RayCaster caster;
  caster.Build(sphere.Points, sphere.Triangles);
  std::mt19937_64 rng(13);
  const std::vector<Ray> rays = RandomRays(20000, -1.5, 1.5, 2.0, rng);
  const int n = static_cast<int>(rays.size());
  std::vector<int> serialOccluded(n), serialTriangle(n, -1), parallelOccluded(n),
    parallelTriangle(n, -1);
  std::vector<double> serialT(n, -1), parallelT(n, -1);
  for (int r = 0; r < n; ++r)
  {
    serialOccluded[r] = caster.Occluded(rays[r].Origin, rays[r].Direction, rays[r].TMax);
    caster.FirstHit(rays[r].Origin, rays[r].Direction, rays[r].TMax, serialT[r], serialTriangle[r]);
  }
#pragma omp parallel for schedule(dynamic, 16) num_threads(4)
  for (int r = 0; r < n; ++r)
  {
    parallelOccluded[r] = caster.Occluded(rays[r].Origin, rays[r].Direction, rays[r].TMax);
    caster.FirstHit(
      rays[r].Origin, rays[r].Direction, rays[r].TMax, parallelT[r], parallelTriangle[r]);
  }
  EXPECT_EQ(serialOccluded, parallelOccluded);
  EXPECT_EQ(serialT, parallelT);
  EXPECT_EQ(serialTriangle, parallelTriangle);
}

//------------------------------------------------------------------------------
// ComputeBoundaryIrradiance: the shadow rays of the irradiance stage.

/// A unit cube [0, 1]^3 (8^3 cells) and, above it, a box
/// [0.25, 0.75]^2 x [1.5, 2] (4 x 4 x 4 cells) that shadows the middle of
/// the cube's top face from light falling along -z.
TetMesh TwoBoxes()
{
  const translucency::testing::MeshData lower =
    translucency::testing::BoxMesh(8, 8, 8, 1.0, 1.0, 1.0);
  const translucency::testing::MeshData upper =
    translucency::testing::BoxMesh(4, 4, 4, 0.5, 0.5, 0.5);
  std::vector<double> points = lower.Points;
  std::vector<int> tets = lower.Tets;
  const int base = lower.NumberOfPoints();
  for (int i = 0; i < upper.NumberOfPoints(); ++i)
  {
    points.push_back(upper.Points[3 * i] + 0.25);
    points.push_back(upper.Points[3 * i + 1] + 0.25);
    points.push_back(upper.Points[3 * i + 2] + 1.5);
  }
  for (int id : upper.Tets)
  {
    tets.push_back(id + base);
  }
  TetMesh mesh;
  mesh.SetGeometry(points, tets);
  return mesh;
}

LightSource FromAbove(double power)
{
  LightSource light;
  light.Type = LightSource::Kind::Directional;
  light.Direction = { 0.0, 0.0, -2.0 };
  light.Power = { power, 2 * power, 3 * power };
  return light;
}

TEST(RayCasterIrradiance, OneBoxShadowsAnother)
{
  const TetMesh mesh = TwoBoxes();
  const double eta = 1.4;
  const std::vector<double> pointEta(mesh.GetNumberOfPoints(), eta);
  const std::vector<LightSource> lights = { FromAbove(1.0) };
  std::vector<double> lit, unshadowed;
  ASSERT_TRUE(ComputeBoundaryIrradiance(mesh, pointEta, lights, 0.0, 0, true, lit));
  ASSERT_TRUE(ComputeBoundaryIrradiance(mesh, pointEta, lights, 0.0, 0, false, unshadowed));
  const double top = Fresnel::Transmittance(1.0, eta); // normal incidence
  int shadowedCount = 0, litCount = 0;
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    const double* x = mesh.GetPoint(i);
    if (!mesh.IsBoundaryPoint(i))
    {
      for (int c = 0; c < 3; ++c)
      {
        EXPECT_EQ(lit[3 * i + c], 0.0);
        EXPECT_EQ(unshadowed[3 * i + c], 0.0);
      }
      continue;
    }
    const bool interiorOfTopFace =
      std::abs(x[2] - 1.0) < 1e-12 && x[0] > 0.01 && x[0] < 0.99 && x[1] > 0.01 && x[1] < 0.99;
    if (!interiorOfTopFace)
    {
      continue;
    }
    const bool underUpperBox = x[0] > 0.26 && x[0] < 0.74 && x[1] > 0.26 && x[1] < 0.74;
    const bool clear = x[0] < 0.24 || x[0] > 0.76 || x[1] < 0.24 || x[1] > 0.76;
    for (int c = 0; c < 3; ++c)
    {
      EXPECT_NEAR(unshadowed[3 * i + c], (c + 1) * top, 1e-14);
      if (underUpperBox)
      {
        EXPECT_EQ(lit[3 * i + c], 0.0) << "point " << i;
      }
      else if (clear)
      {
        EXPECT_EQ(lit[3 * i + c], unshadowed[3 * i + c]) << "point " << i;
      }
    }
    shadowedCount += underUpperBox;
    litCount += clear;
  }
  EXPECT_EQ(shadowedCount, 9);
  EXPECT_GT(litCount, 20);
}

TEST(RayCasterIrradiance, UniformLight)
{
  const TetMesh mesh = TwoBoxes();
  const double eta = 1.3, e = 2.0;
  const int samples = 32;
  const std::vector<double> pointEta(mesh.GetNumberOfPoints(), eta);
  std::vector<double> exact, sampled;
  ASSERT_TRUE(ComputeBoundaryIrradiance(mesh, pointEta, {}, e, samples, false, exact));
  ASSERT_TRUE(ComputeBoundaryIrradiance(mesh, pointEta, {}, e, samples, true, sampled));
  const double unoccluded = e * Fresnel::UniformTransmittance(eta);
  const std::vector<double>& normals = mesh.GetPointNormals();
  int checked = 0;
  for (int i : mesh.GetBoundaryPoints())
  {
    EXPECT_DOUBLE_EQ(exact[3 * i], unoccluded);
    const double* x = mesh.GetPoint(i);
    // Top face of the upper box: nothing above, every ray escapes, so the
    // estimate is the plain cosine-weighted sum.
    if (std::abs(x[2] - 2.0) < 1e-12 && x[0] > 0.26 && x[0] < 0.74 && x[1] > 0.26 && x[1] < 0.74)
    {
      const double rotation = UniformSampleRotation(x);
      double sum = 0.0;
      for (int k = 0; k < samples; ++k)
      {
        double w[3];
        sum += Fresnel::Transmittance(
          HemisphereDirection(&normals[3 * i], k, samples, rotation, w), eta);
      }
      EXPECT_NEAR(sampled[3 * i], e * sum / samples, 1e-14);
      EXPECT_NEAR(sampled[3 * i], unoccluded, 0.02 * unoccluded);
      ++checked;
    }
    // Middle of the cube's top face: the upper box hides part of the sky.
    if (std::abs(x[2] - 1.0) < 1e-12 && std::abs(x[0] - 0.5) < 0.01 && std::abs(x[1] - 0.5) < 0.01)
    {
      EXPECT_LT(sampled[3 * i], 0.9 * unoccluded);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 10);
}

TEST(RayCasterIrradiance, ParallelEqualsSerial)
{
  const TetMesh mesh = TwoBoxes();
  std::vector<double> pointEta(mesh.GetNumberOfPoints());
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    pointEta[i] = 1.2 + 0.3 * mesh.GetPoint(i)[0];
  }
  LightSource point;
  point.Type = LightSource::Kind::Point;
  point.Position = { 2.0, -1.0, 3.0 };
  point.Power = { 5.0, 4.0, 3.0 };
  const std::vector<LightSource> lights = { FromAbove(0.5), point };
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  std::vector<double> serial;
  ASSERT_TRUE(ComputeBoundaryIrradiance(mesh, pointEta, lights, 0.7, 16, true, serial));
  omp_set_num_threads(4);
  std::vector<double> parallel;
  ASSERT_TRUE(ComputeBoundaryIrradiance(mesh, pointEta, lights, 0.7, 16, true, parallel));
  omp_set_num_threads(saved);
  EXPECT_EQ(serial, parallel);
}

TEST(RayCasterIrradiance, AbortAndInvalidInput)
{
  const TetMesh mesh = TwoBoxes();
  const std::vector<double> pointEta(mesh.GetNumberOfPoints(), 1.4);
  const std::vector<LightSource> lights = { FromAbove(1.0) };
  std::vector<double> q;
  // One thread: the callback runs once before the loop, then every 64 points.
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  int calls = 0;
  EXPECT_FALSE(ComputeBoundaryIrradiance(
    mesh, pointEta, lights, 1.0, 8, true, q, [&calls]() { return ++calls >= 3; }));
  EXPECT_EQ(calls, 3);
  omp_set_num_threads(saved);
  EXPECT_FALSE(
    ComputeBoundaryIrradiance(mesh, pointEta, lights, 1.0, 8, true, q, []() { return true; }));
  EXPECT_TRUE(
    ComputeBoundaryIrradiance(mesh, pointEta, lights, 1.0, 8, true, q, []() { return false; }));

  EXPECT_THROW(ComputeBoundaryIrradiance(mesh, { 1.4 }, lights, 0.0, 0, true, q), Error);
  EXPECT_THROW(ComputeBoundaryIrradiance(mesh, pointEta, lights, -1.0, 0, true, q), Error);
  EXPECT_THROW(ComputeBoundaryIrradiance(mesh, pointEta, lights, 1.0, -1, true, q), Error);
  LightSource uniform;
  uniform.Type = LightSource::Kind::Uniform;
  EXPECT_THROW(ComputeBoundaryIrradiance(mesh, pointEta, { uniform }, 0.0, 0, true, q), Error);
  LightSource dark = FromAbove(1.0);
  dark.Direction = { 0.0, 0.0, 0.0 };
  EXPECT_THROW(ComputeBoundaryIrradiance(mesh, pointEta, { dark }, 0.0, 0, true, q), Error);
  std::vector<double> badEta = pointEta;
  badEta[mesh.GetBoundaryPoints()[3]] = 0.0;
  EXPECT_THROW(ComputeBoundaryIrradiance(mesh, badEta, lights, 0.0, 0, true, q), Error);
}

//------------------------------------------------------------------------------
// FindEdgeCrossing: the quick self-intersection check of vtkTetrahedralizeSurface.

TEST(FindEdgeCrossing, ClosedSphereHasNone)
{
  const double center[3] = { 0.5, -1.0, 2.0 };
  const Surface sphere = UVSphere(30, 40, 3.0, center);
  EdgeCrossing crossing;
  EXPECT_FALSE(FindEdgeCrossing(sphere.Points, sphere.Triangles, crossing));
}

TEST(FindEdgeCrossing, SubdividedCoplanarTrianglesDoNotCross)
{
  // A closed surface whose faces are split into coplanar pieces (VTK's
  // linear subdivision of a mesh does this): every edge lies in the plane
  // of the neighbouring pieces up to round-off. Found on the bunny
  // subdivided twice, whose edge 1432-17373 was reported to cross the
  // coplanar triangle 24221 far outside it. Here: a rotated, off-centre
  // octahedron, each face split three times into 4 (64 coplanar pieces).
  const Eigen::Matrix3d rotation =
    (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())).toRotationMatrix();
  std::vector<Eigen::Vector3d> corners = { { 1, 0, 0 }, { -1, 0, 0 }, { 0, 1, 0 }, { 0, -1, 0 },
    { 0, 0, 1 }, { 0, 0, -1 } };
  for (Eigen::Vector3d& p : corners)
  {
    p = 8.3 * (rotation * p) + Eigen::Vector3d(-8.6, 0.3, -1.1);
  }
  std::vector<std::array<Eigen::Vector3d, 3>> faces;
  for (int sx : { 0, 1 })
    for (int sy : { 2, 3 })
      for (int sz : { 4, 5 })
      {
        const bool flip = (sx + sy + sz) % 2 == 0;
        faces.push_back({ corners[sx], flip ? corners[sz] : corners[sy],
          flip ? corners[sy] : corners[sz] });
      }
  for (int level = 0; level < 3; ++level)
  {
    std::vector<std::array<Eigen::Vector3d, 3>> finer;
    for (const auto& f : faces)
    {
      const Eigen::Vector3d m01 = 0.5 * (f[0] + f[1]), m12 = 0.5 * (f[1] + f[2]),
                            m20 = 0.5 * (f[2] + f[0]);
      finer.push_back({ f[0], m01, m20 });
      finer.push_back({ m01, f[1], m12 });
      finer.push_back({ m20, m12, f[2] });
      finer.push_back({ m01, m12, m20 });
    }
    faces = std::move(finer);
  }
  // Merge equal points (midpoints are computed the same way from both sides).
  std::vector<double> points;
  std::vector<int> triangles;
  std::map<std::array<double, 3>, int> ids;
  for (const auto& f : faces)
  {
    for (const Eigen::Vector3d& p : f)
    {
      const std::array<double, 3> key = { p[0], p[1], p[2] };
      auto it = ids.find(key);
      if (it == ids.end())
      {
        it = ids.emplace(key, static_cast<int>(points.size() / 3)).first;
        points.insert(points.end(), { p[0], p[1], p[2] });
      }
      triangles.push_back(it->second);
    }
  }
  ASSERT_EQ(triangles.size(), 3u * 8 * 64);
  ASSERT_EQ(points.size(), 3u * (8 * 64 / 2 + 2)); // Euler: V = F/2 + 2
  EdgeCrossing crossing;
  EXPECT_FALSE(FindEdgeCrossing(points, triangles, crossing))
    << "edge " << crossing.EdgePoints[0] << "-" << crossing.EdgePoints[1] << " triangle "
    << crossing.Triangle;
}

TEST(FindEdgeCrossing, OverlappingSpheresCross)
{
  const double c0[3] = { 0, 0, 0 }, c1[3] = { 1.0, 0.1, 0.05 };
  Surface both = UVSphere(12, 16, 1.0, c0);
  const Surface other = UVSphere(12, 16, 1.0, c1);
  const int offset = static_cast<int>(both.Points.size() / 3);
  both.Points.insert(both.Points.end(), other.Points.begin(), other.Points.end());
  for (int id : other.Triangles)
  {
    both.Triangles.push_back(id + offset);
  }
  EdgeCrossing crossing;
  ASSERT_TRUE(FindEdgeCrossing(both.Points, both.Triangles, crossing));
  // The point lies on the edge and in the plane of the crossed triangle,
  // which contains neither end of the edge.
  const int a = crossing.EdgePoints[0], b = crossing.EdgePoints[1];
  const int* tri = &both.Triangles[3 * crossing.Triangle];
  for (int k = 0; k < 3; ++k)
  {
    EXPECT_NE(tri[k], a);
    EXPECT_NE(tri[k], b);
  }
  const Eigen::Map<const Eigen::Vector3d> pa(&both.Points[3 * a]), pb(&both.Points[3 * b]),
    p0(&both.Points[3 * tri[0]]), p1(&both.Points[3 * tri[1]]), p2(&both.Points[3 * tri[2]]);
  const Eigen::Map<const Eigen::Vector3d> x(crossing.Point);
  EXPECT_NEAR((x - pa).cross(pb - pa).norm(), 0.0, 1e-12);
  EXPECT_NEAR((x - p0).dot((p1 - p0).cross(p2 - p0).normalized()), 0.0, 1e-12);
  EXPECT_GT((x - pa).norm(), 0.0);
  EXPECT_LT((x - pa).norm(), (pb - pa).norm());
}

TEST(FindEdgeCrossing, ShiftedVerticesSameAnswerOnAnyThreadCount)
{
  // The vertices shifted by one (a line inserted in an OBJ file): the same
  // topology over scrambled positions, crossing everywhere (TetGen's -d
  // pass took minutes on such a bunny).
  const double center[3] = { 0, 0, 0 };
  Surface s = UVSphere(40, 50, 1.0, center);
  std::rotate(s.Points.begin(), s.Points.begin() + 3, s.Points.end());
  const int saved = omp_get_max_threads();
  EdgeCrossing serial, parallel;
  omp_set_num_threads(1);
  ASSERT_TRUE(FindEdgeCrossing(s.Points, s.Triangles, serial));
  omp_set_num_threads(std::max(2, saved));
  ASSERT_TRUE(FindEdgeCrossing(s.Points, s.Triangles, parallel));
  omp_set_num_threads(saved);
  EXPECT_EQ(serial.EdgePoints[0], parallel.EdgePoints[0]);
  EXPECT_EQ(serial.EdgePoints[1], parallel.EdgePoints[1]);
  EXPECT_EQ(serial.Triangle, parallel.Triangle);
  for (int k = 0; k < 3; ++k)
  {
    EXPECT_EQ(serial.Point[k], parallel.Point[k]);
  }
}

TEST(FindEdgeCrossing, BadIdThrows)
{
  const std::vector<double> points = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
  EdgeCrossing crossing;
  EXPECT_THROW(FindEdgeCrossing(points, { 0, 1, 3 }, crossing), Error);
  EXPECT_THROW(FindEdgeCrossing(points, { 0, -1, 2 }, crossing), Error);
}

} // namespace
