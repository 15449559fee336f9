// ComputeSurfacePointIrradiance (the distributed Surface Irradiance's kernel
// on the gathered boundary surface) equals the serial
// ComputeProjectedIrradiance on the TetMesh's own boundary, to round-off, on
// a box with a well (shadows matter), a heterogeneous refractive index,
// directional, point and uniform (sampled) lights; also with the surface's
// triangles in another order (the gather's order is not the mesh's).
// SurfacePointIrradianceCache (the distributed path's per-light cache) equals
// the full computation bit for bit and recomputes only what changed.

#include "Error.h"
#include "LightSources.h"
#include "SurfaceLightKernel.h"
#include "TestMeshes.h"
#include "TetMesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace
{

using namespace translucency;

struct WellCase
{
  TetMesh Mesh;
  std::vector<double> TetEta;
};

/// An 8 mm cube in 8^3 cells with a 4 x 4 x 4 mm well dug from its top.
void MakeWell(WellCase& c)
{
  const translucency::testing::MeshData box = translucency::testing::CubeMesh(8, 8.0, 0.2, 7);
  std::vector<int> tets;
  for (size_t t = 0; t < box.Tets.size() / 4; ++t)
  {
    double centre[3] = { 0.0, 0.0, 0.0 };
    for (int v = 0; v < 4; ++v)
      for (int d = 0; d < 3; ++d)
        centre[d] += 0.25 * box.Points[3 * static_cast<size_t>(box.Tets[4 * t + v]) + d];
    if (centre[0] > 2.0 && centre[0] < 6.0 && centre[1] > 2.0 && centre[1] < 6.0 &&
      centre[2] > 4.0)
      continue;
    tets.insert(tets.end(), box.Tets.begin() + 4 * t, box.Tets.begin() + 4 * t + 4);
    c.TetEta.push_back(1.3 + 0.1 * (centre[0] > 4.0) + 0.05 * (centre[2] > 3.0));
  }
  c.Mesh.SetGeometry(box.Points, tets);
}

BoundarySurface SurfaceOf(const TetMesh& mesh, const std::vector<double>& tetEta, bool reversed)
{
  BoundarySurface s;
  s.Points = mesh.GetPoints();
  const int n = mesh.GetNumberOfBoundaryTriangles();
  for (int k = 0; k < n; ++k)
  {
    const int f = reversed ? n - 1 - k : k;
    for (int m = 0; m < 3; ++m)
      s.Triangles.push_back(mesh.GetBoundaryTriangles()[3 * static_cast<size_t>(f) + m]);
    s.TriangleEta.push_back(tetEta[mesh.GetBoundaryTriangleTets()[f]]);
  }
  double lo[3] = { 1e300, 1e300, 1e300 }, hi[3] = { -1e300, -1e300, -1e300 };
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    for (int d = 0; d < 3; ++d)
    {
      lo[d] = std::min(lo[d], mesh.GetPoint(i)[d]);
      hi[d] = std::max(hi[d], mesh.GetPoint(i)[d]);
    }
  s.Diagonal = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
    (hi[2] - lo[2]) * (hi[2] - lo[2]));
  return s;
}

TEST(SurfaceLightKernel, EqualsTheSerialProjectedIrradiance)
{
  WellCase c;
  MakeWell(c);
  const std::vector<LightSource> lights = { DirectionalLight({ 0.3, -0.5, -1.0 }, { 1.0, 0.5, 0.2 }),
    PointLight({ 9.0, 4.0, 12.0 }, { 50.0, 60.0, 70.0 }) };
  const int numPoints = c.Mesh.GetNumberOfPoints();
  std::vector<int> all(static_cast<size_t>(numPoints));
  std::vector<double> rotations(all.size());
  for (int i = 0; i < numPoints; ++i)
  {
    all[i] = i;
    rotations[i] = UniformSampleRotation(c.Mesh.GetPoint(i));
  }
  for (const bool shadows : { true, false })
  {
    std::vector<double> serial;
    ASSERT_TRUE(ComputeProjectedIrradiance(c.Mesh, c.TetEta, lights, 0.2, 16, shadows, serial));
    for (const bool reversed : { false, true })
    {
      const BoundarySurface surface = SurfaceOf(c.Mesh, c.TetEta, reversed);
      std::vector<double> q;
      ASSERT_TRUE(
        ComputeSurfacePointIrradiance(surface, all, rotations, lights, 0.2, 16, shadows, q));
      ASSERT_EQ(q.size(), serial.size());
      double scale = 0.0;
      for (double v : serial)
        scale = std::max(scale, std::abs(v));
      ASSERT_GT(scale, 0.0);
      for (size_t k = 0; k < q.size(); ++k)
        EXPECT_NEAR(q[k], serial[k], 1e-13 * scale) << "value " << k << " reversed " << reversed;
    }
  }
  // Shadows matter on this mesh (else the comparison above proves little).
  std::vector<double> lit, unlit;
  ComputeProjectedIrradiance(c.Mesh, c.TetEta, lights, 0.2, 16, true, lit);
  ComputeProjectedIrradiance(c.Mesh, c.TetEta, lights, 0.2, 16, false, unlit);
  int shadowed = 0;
  for (size_t k = 0; k < lit.size(); ++k)
    shadowed += lit[k] < unlit[k] - 1e-6 ? 1 : 0;
  EXPECT_GT(shadowed, 30);
}

TEST(SurfaceLightKernel, SampledUniformLightDoesNotDependOnThePointOrder)
{
  // The uniform light's sample rotation is keyed on the point's coordinates:
  // the same mesh with its points and tets numbered in reverse gets the same
  // irradiance at every point (a partitioned or redistributed mesh too).
  WellCase c;
  MakeWell(c);
  const int n = c.Mesh.GetNumberOfPoints();
  const int m = c.Mesh.GetNumberOfTets();
  std::vector<double> points(3 * static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    std::copy_n(c.Mesh.GetPoint(i), 3, &points[3 * static_cast<size_t>(n - 1 - i)]);
  std::vector<int> tets(4 * static_cast<size_t>(m));
  std::vector<double> eta(static_cast<size_t>(m));
  for (int t = 0; t < m; ++t)
  {
    for (int a = 0; a < 4; ++a)
      tets[4 * static_cast<size_t>(m - 1 - t) + a] = n - 1 - c.Mesh.GetTets()[4 * static_cast<size_t>(t) + a];
    eta[m - 1 - t] = c.TetEta[t];
  }
  TetMesh reversed;
  reversed.SetGeometry(points, tets);
  const std::vector<LightSource> none;
  std::vector<double> q, qReversed, unoccluded;
  ASSERT_TRUE(ComputeProjectedIrradiance(c.Mesh, c.TetEta, none, 0.2, 16, true, q));
  ASSERT_TRUE(ComputeProjectedIrradiance(reversed, eta, none, 0.2, 16, true, qReversed));
  ASSERT_TRUE(ComputeProjectedIrradiance(c.Mesh, c.TetEta, none, 0.2, 16, false, unoccluded));
  double scale = 0.0;
  int occluded = 0;
  for (size_t k = 0; k < q.size(); ++k)
  {
    scale = std::max(scale, std::abs(q[k]));
    occluded += q[k] < unoccluded[k] - 1e-6 ? 1 : 0;
  }
  ASSERT_GT(scale, 0.0);
  EXPECT_GT(occluded, 30) << "the well must occlude samples for the test to mean anything";
  for (int i = 0; i < n; ++i)
    for (int ch = 0; ch < 3; ++ch)
      EXPECT_NEAR(qReversed[3 * static_cast<size_t>(n - 1 - i) + ch],
        q[3 * static_cast<size_t>(i) + ch], 1e-13 * scale)
        << "point " << i;
}

TEST(SurfaceLightKernel, SomePointsOnlyAndErrors)
{
  WellCase c;
  MakeWell(c);
  const BoundarySurface surface = SurfaceOf(c.Mesh, c.TetEta, false);
  const std::vector<LightSource> lights = { PointLight({ 9.0, 4.0, 12.0 }, { 50.0, 60.0, 70.0 }) };
  const int n = c.Mesh.GetNumberOfPoints();
  std::vector<int> all, some;
  std::vector<double> rAll, rSome;
  for (int i = 0; i < n; ++i)
  {
    all.push_back(i);
    rAll.push_back(UniformSampleRotation(&surface.Points[3 * i]));
    if (i % 7 == 3)
    {
      some.push_back(i);
      rSome.push_back(UniformSampleRotation(&surface.Points[3 * i]));
    }
  }
  std::vector<double> qAll, qSome;
  ASSERT_TRUE(ComputeSurfacePointIrradiance(surface, all, rAll, lights, 0.1, 8, true, qAll));
  ASSERT_TRUE(ComputeSurfacePointIrradiance(surface, some, rSome, lights, 0.1, 8, true, qSome));
  for (size_t k = 0; k < some.size(); ++k)
    for (int ch = 0; ch < 3; ++ch)
      EXPECT_EQ(qSome[3 * k + ch], qAll[3 * static_cast<size_t>(some[k]) + ch]);
  BoundarySurface bad = surface;
  bad.TriangleEta[5] = -1.0;
  EXPECT_THROW(ComputeSurfacePointIrradiance(bad, some, rSome, lights, 0.1, 8, true, qSome), Error);
  EXPECT_THROW(ComputeSurfacePointIrradiance(surface, { n }, { 0.0 }, lights, 0.1, 8, true, qSome),
    Error);
  EXPECT_THROW(ComputeSurfacePointIrradiance(surface, some, rSome, lights, -1.0, 8, true, qSome),
    Error);
}

TEST(SurfaceLightKernel, CacheRecomputesTheChangedLightOnlyBitForBit)
{
  WellCase c;
  MakeWell(c);
  BoundarySurface surface = SurfaceOf(c.Mesh, c.TetEta, true);
  std::vector<int> some;
  std::vector<double> rotations;
  for (int i = 0; i < c.Mesh.GetNumberOfPoints(); i += 2)
  {
    some.push_back(i);
    rotations.push_back(UniformSampleRotation(&surface.Points[3 * static_cast<size_t>(i)]));
  }
  SurfacePointIrradianceCache cache;
  std::vector<double> q;
  EXPECT_THROW(cache.Compute({}, 0.1, 8, true, q), Error); // no surface yet
  cache.SetSurface(surface, some, rotations);
  std::vector<LightSource> lights = { DirectionalLight({ 0.3, -0.5, -1.0 }, { 1.0, 0.5, 0.2 }),
    PointLight({ 9.0, 4.0, 12.0 }, { 50.0, 60.0, 70.0 }),
    SpotLight({ 4.0, 4.0, 14.0 }, { 0.0, 0.0, -1.0 }, 40.0, 2.0, { 30.0, 30.0, 30.0 }) };
  // Each step: what changes, then the lights and uniform terms computed.
  auto check = [&](double uniform, int samples, bool shadows, int lightsComputed,
                 bool uniformComputed, const char* step) {
    std::vector<double> full;
    ASSERT_TRUE(cache.Compute(lights, uniform, samples, shadows, q)) << step;
    EXPECT_EQ(cache.GetNumberOfLightsComputed(), lightsComputed) << step;
    EXPECT_EQ(cache.GetUniformComputed(), uniformComputed) << step;
    ASSERT_TRUE(
      ComputeSurfacePointIrradiance(surface, some, rotations, lights, uniform, samples, shadows, full));
    ASSERT_EQ(q.size(), full.size());
    double largest = 0.0;
    for (size_t k = 0; k < q.size(); ++k)
    {
      EXPECT_EQ(q[k], full[k]) << step << ", value " << k; // the same sums in the same order
      largest = std::max(largest, q[k]);
    }
    EXPECT_GT(largest, 0.0) << step;
  };
  check(0.2, 16, true, 3, true, "first");
  check(0.2, 16, true, 0, false, "again");
  lights[1] = PointLight({ 2.0, 9.0, 11.0 }, { 50.0, 60.0, 70.0 });
  check(0.2, 16, true, 1, false, "a light moved");
  std::swap(lights[0], lights[2]);
  check(0.2, 16, true, 0, false, "the same lights in another order");
  check(0.3, 16, true, 0, true, "another uniform irradiance");
  check(0.3, 16, false, 3, true, "shadows off");
  lights.pop_back();
  check(0.3, 16, false, 0, false, "a light removed");
  // A new surface forgets everything; an aborted light is not kept.
  cache.SetSurface(surface, some, rotations);
  EXPECT_FALSE(cache.Compute(lights, 0.3, 16, false, q, [] { return true; }));
  check(0.3, 16, false, 2, true, "after an abort");
  EXPECT_THROW(cache.SetSurface(surface, { -1 }, { 0.0 }), Error);
}

} // namespace
