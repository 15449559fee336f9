// Translucent radiosity (TranslucentRadiosity, eq. 14): form factors
// against analytic values and identities (reciprocity, closed-box row sums,
// invisibility), the all-opaque scene against classical radiosity solved
// directly with Eigen, convergence and the spectral radius of S F, the
// diffusion S operator's energy balance (and eq. 3 with the n^2 law), the
// dipole profile against its closed-form integral, diffusion S against the
// paper's profile S, opaque -> translucent trends, bad input.

#include "Error.h"
#include "FormFactors.h"
#include "Fresnel.h"
#include "ProfileSubsurface.h"
#include "RadiosityScene.h"
#include "RadiositySession.h"
#include "Radiance.h"
#include "TestMeshes.h"
#include "TetMesh.h"
#include "TranslucentRadiosity.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace
{

using namespace translucency;

constexpr double Pi = 3.14159265358979323846;

/// A square [x0, x0 + 1] x [y0, y0 + 1] at height z as 2 triangles, normal +z or -z.
void Square(double z, bool up, std::vector<double>& points, std::vector<int>& triangles)
{
  points = { 0, 0, z, 1, 0, z, 1, 1, z, 0, 1, z };
  triangles = up ? std::vector<int>{ 0, 1, 2, 0, 2, 3 } : std::vector<int>{ 0, 2, 1, 0, 3, 2 };
}

/// Area-weighted form factor from the patches [a0, a1) to [b0, b1).
double GroupFormFactor(const RadiosityScene& scene, const FormFactorMatrix& F, int a0, int a1,
  int b0, int b1)
{
  double num = 0.0, area = 0.0;
  for (int i = a0; i < a1; ++i)
  {
    area += scene.GetAreas()[i];
    for (int j = b0; j < b1; ++j)
    {
      num += scene.GetAreas()[i] * F.Get(i, j);
    }
  }
  return num / area;
}

std::vector<double> Grey(int triangles, double a)
{
  return std::vector<double>(3 * static_cast<size_t>(triangles), a);
}

std::shared_ptr<TetMesh> Cube(int n, double side, const double origin[3])
{
  translucency::testing::MeshData data = translucency::testing::CubeMesh(n, side);
  for (size_t k = 0; k < data.Points.size(); ++k)
  {
    data.Points[k] += origin[k % 3];
  }
  auto mesh = std::make_shared<TetMesh>();
  mesh->SetGeometry(data.Points, data.Tets);
  return mesh;
}

std::shared_ptr<TetMesh> Box(int nx, int ny, int nz, const double lo[3], const double hi[3])
{
  translucency::testing::MeshData data =
    translucency::testing::BoxMesh(nx, ny, nz, hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  for (size_t k = 0; k < data.Points.size(); ++k)
  {
    data.Points[k] += lo[k % 3];
  }
  auto mesh = std::make_shared<TetMesh>();
  mesh->SetGeometry(data.Points, data.Tets);
  return mesh;
}

OpticalProperties Material(int tets, double muA, double sigmaS, double eta = 1.3)
{
  const double a[3] = { muA, muA, muA }, s[3] = { sigmaS, sigmaS, sigmaS };
  return OpticalProperties::Uniform(tets, a, s, eta);
}

/// A closed room [0, 10]^3 (inward walls, 4 x 4 squares per face, wall
/// albedo per face) to hold test objects.
void AddRoom(RadiosityScene& scene, double cell = 2.5)
{
  const double lo[3] = { 0, 0, 0 }, hi[3] = { 10, 10, 10 };
  std::vector<double> points;
  std::vector<int> triangles, faces;
  RadiosityScene::BoxSurface(lo, hi, cell, true, -1, points, triangles, &faces);
  std::vector<double> albedo;
  const double colours[6][3] = { { 0.7, 0.1, 0.1 }, { 0.1, 0.7, 0.1 }, { 0.6, 0.6, 0.6 },
    { 0.6, 0.6, 0.6 }, { 0.5, 0.5, 0.5 }, { 0.4, 0.4, 0.4 } };
  for (int f : faces)
  {
    albedo.insert(albedo.end(), colours[f], colours[f] + 3);
  }
  scene.AddOpaque("room", points, triangles, albedo);
}

LightSource PointLight(double x, double y, double z, double power = 100.0)
{
  LightSource light;
  light.Type = LightSource::Kind::Point;
  light.Position = { x, y, z };
  light.Power = { power, power, power };
  return light;
}

// ---- Form factors

TEST(Radiosity, FormFactorParallelSquares)
{
  // Two coaxial unit squares 1 apart, facing each other:
  // F = 0.19982 (Howell's catalogue, C-11 with X = Y = 1).
  RadiosityScene scene;
  std::vector<double> p;
  std::vector<int> t;
  Square(0.0, true, p, t);
  scene.AddOpaque("bottom", p, t, Grey(2, 0.5));
  Square(1.0, false, p, t);
  scene.AddOpaque("top", p, t, Grey(2, 0.5));
  scene.Build();
  FormFactorComputer computer;
  const int n = 40000;
  computer.SetRaysPerPatch(n);
  FormFactorMatrix F;
  ASSERT_TRUE(computer.Compute(scene, F));
  const double x = 1.0;
  const double analytic = 2.0 / (Pi * x * x) *
    (std::log(std::sqrt((1 + x * x) * (1 + x * x) / (1 + 2 * x * x))) +
      2 * x * std::sqrt(1 + x * x) * std::atan(x / std::sqrt(1 + x * x)) - 2 * x * std::atan(x));
  EXPECT_NEAR(analytic, 0.19982, 1e-4); // the closed form itself
  const double f = GroupFormFactor(scene, F, 0, 2, 2, 4);
  const double sigma = std::sqrt(analytic * (1 - analytic) / (2.0 * n));
  EXPECT_NEAR(f, analytic, 4.0 * sigma);
  // Reciprocity at equal areas.
  EXPECT_NEAR(GroupFormFactor(scene, F, 2, 4, 0, 2), analytic, 4.0 * sigma);
}

TEST(Radiosity, FormFactorPerpendicularSquares)
{
  // Unit squares with a common edge at 90 degrees: F = 0.20004.
  RadiosityScene scene;
  std::vector<double> p;
  std::vector<int> t;
  Square(0.0, true, p, t);
  scene.AddOpaque("floor", p, t, Grey(2, 0.5));
  // Wall x = 0, normal +x.
  p = { 0, 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1 };
  t = { 0, 1, 2, 0, 2, 3 };
  scene.AddOpaque("wall", p, t, Grey(2, 0.5));
  scene.Build();
  ASSERT_GT(scene.GetNormals()[6], 0.99); // wall normal +x
  FormFactorComputer computer;
  const int n = 40000;
  computer.SetRaysPerPatch(n);
  FormFactorMatrix F;
  ASSERT_TRUE(computer.Compute(scene, F));
  const double analytic = 0.20004;
  const double sigma = std::sqrt(analytic * (1 - analytic) / (2.0 * n));
  EXPECT_NEAR(GroupFormFactor(scene, F, 0, 2, 2, 4), analytic, 4.0 * sigma);
  EXPECT_NEAR(GroupFormFactor(scene, F, 2, 4, 0, 2), analytic, 4.0 * sigma);
}

TEST(Radiosity, FormFactorClosedBoxRowsAndReciprocity)
{
  RadiosityScene scene;
  AddRoom(scene, 5.0);
  const double lo[3] = { 3, 3, 0.5 }, hi[3] = { 6, 5, 4 };
  std::vector<double> points;
  std::vector<int> triangles;
  RadiosityScene::BoxSurface(lo, hi, 2.0, false, -1, points, triangles);
  scene.AddOpaque("block", points, triangles, Grey(static_cast<int>(triangles.size() / 3), 0.5));
  scene.Build();
  FormFactorComputer computer;
  const int n = 4096;
  computer.SetRaysPerPatch(n);
  FormFactorMatrix F;
  ASSERT_TRUE(computer.Compute(scene, F));
  const int numPatches = scene.GetNumberOfPatches();
  // Closed scene: every ray hits a front face, so every row sums to 1 (up to
  // rays slipping through a shared edge in the last bits).
  for (int i = 0; i < numPatches; ++i)
  {
    EXPECT_LE(F.RowSum(i), 1.0 + 1e-6) << "patch " << i;
    EXPECT_GE(F.RowSum(i), 0.999) << "patch " << i;
    EXPECT_EQ(F.Get(i, i), 0.0); // flat patches do not see themselves
  }
  // Reciprocity A_i F_ij = A_j F_ji within 5 standard errors of the difference.
  const std::vector<double>& A = scene.GetAreas();
  int checked = 0;
  for (int i = 0; i < numPatches; ++i)
  {
    for (int j = i + 1; j < numPatches; ++j)
    {
      const double fij = F.Get(i, j), fji = F.Get(j, i);
      if (fij == 0.0 && fji == 0.0)
      {
        continue;
      }
      const double f = 0.5 * (fij + fji * A[j] / A[i]); // estimate of F_ij
      const double g = f * A[i] / A[j];                  // estimate of F_ji
      const double sigma = std::sqrt(A[i] * A[i] * std::max(f * (1 - f), 1.0 / n) / n +
        A[j] * A[j] * std::max(g * (1 - g), 1.0 / n) / n);
      EXPECT_LE(std::abs(A[i] * fij - A[j] * fji), 5.0 * sigma) << i << " " << j;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
  EXPECT_GT(computer.GetMemoryBytes(), 0u);
}

TEST(Radiosity, FormFactorInvisiblePatchesAreZero)
{
  // Two closed rooms side by side: no patch of one sees a patch of the other.
  RadiosityScene scene;
  const double lo1[3] = { 0, 0, 0 }, hi1[3] = { 2, 2, 2 };
  const double lo2[3] = { 3, 0, 0 }, hi2[3] = { 5, 2, 2 };
  std::vector<double> p;
  std::vector<int> t;
  RadiosityScene::BoxSurface(lo1, hi1, 1.0, true, -1, p, t);
  scene.AddOpaque("room1", p, t, Grey(static_cast<int>(t.size() / 3), 0.5));
  const int split = static_cast<int>(t.size() / 3);
  RadiosityScene::BoxSurface(lo2, hi2, 1.0, true, -1, p, t);
  scene.AddOpaque("room2", p, t, Grey(static_cast<int>(t.size() / 3), 0.5));
  scene.Build();
  FormFactorComputer computer;
  computer.SetRaysPerPatch(1024);
  FormFactorMatrix F;
  ASSERT_TRUE(computer.Compute(scene, F));
  for (int i = 0; i < scene.GetNumberOfPatches(); ++i)
  {
    for (int e = F.RowOffsets[i]; e < F.RowOffsets[i + 1]; ++e)
    {
      EXPECT_EQ(i < split, F.Columns[e] < split) << i << " sees " << F.Columns[e];
    }
  }
  // Coplanar patches of one wall do not see each other either.
  EXPECT_EQ(F.Get(0, 1), 0.0);
}

TEST(Radiosity, FormFactorsIndependentOfThreads)
{
  RadiosityScene scene;
  AddRoom(scene, 5.0);
  scene.Build();
  FormFactorComputer computer;
  computer.SetRaysPerPatch(256);
  FormFactorMatrix a, b;
  ASSERT_TRUE(computer.Compute(scene, a));
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  ASSERT_TRUE(computer.Compute(scene, b));
  omp_set_num_threads(threads);
  EXPECT_EQ(a.RowOffsets, b.RowOffsets);
  EXPECT_EQ(a.Columns, b.Columns);
  EXPECT_EQ(a.Values, b.Values);
}

// ---- Opaque scene = classical radiosity

TEST(Radiosity, OpaqueSceneEqualsClassicalRadiosity)
{
  RadiosityScene scene;
  AddRoom(scene);
  const double lo[3] = { 2, 2, 0 }, hi[3] = { 5, 4, 3 };
  std::vector<double> points;
  std::vector<int> triangles;
  RadiosityScene::BoxSurface(lo, hi, 1.5, false, -1, points, triangles);
  std::vector<double> albedo;
  for (size_t t = 0; t < triangles.size() / 3; ++t)
  {
    albedo.insert(albedo.end(), { 0.8, 0.7, 0.2 });
  }
  scene.AddOpaque("block", points, triangles, albedo);
  scene.Build();
  FormFactorComputer computer;
  computer.SetRaysPerPatch(256);
  FormFactorMatrix F;
  ASSERT_TRUE(computer.Compute(scene, F));
  const std::vector<LightSource> lights = { PointLight(7, 7, 9) };

  // Classical radiosity B = (I - P F)^-1 P E (paper eq. 2), dense direct solve.
  const int n = scene.GetNumberOfPatches();
  std::vector<double> E, transmitted;
  scene.ComputeDirectIrradiance(lights, true, E, transmitted);
  TranslucentRadiosity solver;
  solver.SetScene(&scene);
  solver.SetFormFactors(&F);
  const std::vector<double> P = solver.GetDiffuseAlbedo();
  for (int c = 0; c < 3; ++c)
  {
    Eigen::MatrixXd M = Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd rhs(n);
    for (int i = 0; i < n; ++i)
    {
      for (int e = F.RowOffsets[i]; e < F.RowOffsets[i + 1]; ++e)
      {
        M(i, F.Columns[e]) -= P[3 * i + c] * F.Values[e];
      }
      rhs[i] = P[3 * i + c] * E[3 * i + c];
    }
    const Eigen::VectorXd reference = M.partialPivLu().solve(rhs);
    for (auto iteration :
      { TranslucentRadiosity::Iteration::Jacobi, TranslucentRadiosity::Iteration::GaussSeidel })
    {
      solver.SetIteration(iteration);
      solver.SetRelTol(1e-12);
      solver.SetMaxIter(1000);
      RadiosityResult result;
      solver.Solve(lights, result);
      EXPECT_TRUE(result.Converged);
      double err = 0.0, norm = 0.0;
      for (int i = 0; i < n; ++i)
      {
        err = std::max(err, std::abs(result.Combined[3 * i + c] - reference[i]));
        norm = std::max(norm, std::abs(reference[i]));
      }
      EXPECT_LT(err, 1e-9 * norm) << "channel " << c;
      // First bounce of an opaque scene: P E.
      for (int i = 0; i < n; ++i)
      {
        EXPECT_NEAR(result.FirstBounce[3 * i + c], rhs[i], 1e-12 * norm);
      }
    }
  }
}

// ---- Translucent scene: convergence, spectral radius, heuristics

struct TranslucentScene
{
  RadiosityScene Scene;
  FormFactorMatrix F;
  std::shared_ptr<TetMesh> Mesh;
  int Block = -1;
};

void MakeTranslucentScene(TranslucentScene& s, double muA, double sigmaS, int rays = 128)
{
  AddRoom(s.Scene);
  const double origin[3] = { 3, 3, 0 };
  s.Mesh = Cube(4, 3.0, origin);
  s.Block = s.Scene.AddTranslucent("cube", s.Mesh, Material(s.Mesh->GetNumberOfTets(), muA, sigmaS));
  s.Scene.Build();
  FormFactorComputer computer;
  computer.SetRaysPerPatch(rays);
  ASSERT_TRUE(computer.Compute(s.Scene, s.F));
}

TEST(Radiosity, IterationConvergesMonotonically)
{
  TranslucentScene s;
  MakeTranslucentScene(s, 0.01, 1.0);
  TranslucentRadiosity solver;
  solver.SetScene(&s.Scene);
  solver.SetFormFactors(&s.F);
  solver.SetIteration(TranslucentRadiosity::Iteration::Jacobi);
  solver.SetRelTol(1e-6);
  RadiosityResult result;
  solver.Solve({ PointLight(8, 8, 8) }, result);
  ASSERT_TRUE(result.Converged);
  ASSERT_GT(result.ResidualHistory.size(), 3u);
  for (size_t k = 1; k < result.ResidualHistory.size(); ++k)
  {
    EXPECT_LT(result.ResidualHistory[k], result.ResidualHistory[k - 1]) << "iteration " << k;
  }
  // Spectral radius of S F below 1 (paper eq. 15 and after), and the
  // asymptotic ratio of the Jacobi residuals is that radius.
  const std::array<double, 3> rho = solver.EstimateSpectralRadius(60);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_GT(rho[c], 0.1);
    EXPECT_LT(rho[c], 1.0);
  }
  const size_t last = result.ResidualHistory.size() - 1;
  const double ratio = result.ResidualHistory[last] / result.ResidualHistory[last - 1];
  const double rhoMax = std::max({ rho[0], rho[1], rho[2] });
  EXPECT_NEAR(ratio, rhoMax, 0.05);

  // Gauss-Seidel reaches the same B in fewer iterations.
  solver.SetIteration(TranslucentRadiosity::Iteration::GaussSeidel);
  RadiosityResult gs;
  solver.Solve({ PointLight(8, 8, 8) }, gs);
  ASSERT_TRUE(gs.Converged);
  EXPECT_LT(gs.Iterations, result.Iterations);
  double err = 0.0, norm = 0.0;
  for (size_t k = 0; k < gs.Combined.size(); ++k)
  {
    err = std::max(err, std::abs(gs.Combined[k] - result.Combined[k]));
    norm = std::max(norm, std::abs(result.Combined[k]));
  }
  EXPECT_LT(err, 1e-4 * norm);
  // The decomposition: B = S E + inter-reflection, all non-negative on the walls.
  for (size_t k = 0; k < 3 * static_cast<size_t>(s.Scene.GetPatchOffset(1)); ++k)
  {
    EXPECT_NEAR(gs.FirstBounce[k] + gs.InterReflection[k], gs.Combined[k], 1e-12 * norm);
    EXPECT_GE(gs.InterReflection[k], 0.0);
  }
  // Heuristics: h1 keeps S E and only replaces later bounces; both are
  // non-negative and differ from B.
  std::vector<double> h1, h2;
  solver.SolveHeuristics(h1, h2);
  double d1 = 0.0, d2 = 0.0;
  for (size_t k = 0; k < h1.size(); ++k)
  {
    EXPECT_GE(h1[k], gs.FirstBounce[k] - 1e-12 * norm);
    d1 += std::abs(h1[k] - gs.Combined[k]);
    d2 += std::abs(h2[k] - gs.Combined[k]);
  }
  EXPECT_GT(d1, 0.0);
  EXPECT_GT(d2, 0.0);
}

TEST(Radiosity, ParallelLoopsMatchOneThread)
{
  // Direct light, profile S (Dijkstra, evaluation) and a whole solve: the
  // same numbers with one thread and with the default team.
  TranslucentScene s;
  MakeTranslucentScene(s, 0.05, 1.0, 64);
  auto run = [&](std::vector<double>& E, std::vector<double>& profileOut,
               std::vector<double>& B) {
    std::vector<double> q;
    s.Scene.ComputeDirectIrradiance({ PointLight(8, 8, 8) }, true, E, q);
    ProfileSubsurface profile;
    profile.SetVoxelSize(0.5);
    profile.Setup(s.Scene, s.Block);
    const int begin = s.Scene.GetPatchOffset(s.Block);
    std::vector<double> local(q.begin() + 3 * begin, q.end());
    profile.Apply(local, profileOut);
    TranslucentRadiosity solver;
    solver.SetScene(&s.Scene);
    solver.SetFormFactors(&s.F);
    RadiosityResult result;
    solver.Solve({ PointLight(8, 8, 8) }, result);
    B = result.Combined;
  };
  std::vector<double> e1, p1, b1, e2, p2, b2;
  run(e1, p1, b1);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  run(e2, p2, b2);
  omp_set_num_threads(threads);
  EXPECT_EQ(e1, e2);
  EXPECT_EQ(p1, p2);
  ASSERT_EQ(b1.size(), b2.size());
  for (size_t k = 0; k < b1.size(); ++k)
  {
    EXPECT_NEAR(b1[k], b2[k], 1e-9 * std::abs(b1[k]) + 1e-15); // CG sums may differ in the last bits
  }
}

TEST(Radiosity, DiffusionOperatorConservesEnergy)
{
  // mu_a = 0: every watt that enters leaves (the exitance of the discrete
  // energy balance), whatever the pattern of q.
  TranslucentScene s;
  MakeTranslucentScene(s, 0.0, 2.0, 16);
  DiffusionSubsurface op;
  op.SetRelTol(1e-12);
  op.Setup(s.Scene, s.Block);
  const int begin = s.Scene.GetPatchOffset(s.Block);
  const int n = s.Mesh->GetNumberOfBoundaryTriangles();
  std::vector<double> q(3 * n, 0.0), B;
  for (int t = 0; t < n; ++t)
  {
    q[3 * t] = (t % 7 == 0) ? 1.0 : 0.0; // a sparse pattern in R
    q[3 * t + 1] = 1.0;                  // uniform in G
    q[3 * t + 2] = s.Scene.GetCentroids()[3 * (begin + t) + 2];
  }
  op.Apply(q, B);
  const std::vector<double>& A = s.Mesh->GetBoundaryTriangleAreas();
  for (int c = 0; c < 3; ++c)
  {
    double in = 0.0, out = 0.0;
    for (int t = 0; t < n; ++t)
    {
      in += A[t] * q[3 * t + c];
      out += A[t] * B[3 * t + c];
    }
    EXPECT_NEAR(out, in, 1e-8 * in) << "channel " << c;
  }
  // With absorption, less leaves.
  s.Scene.SetMaterial(s.Block, Material(s.Mesh->GetNumberOfTets(), 0.1, 2.0));
  op.Setup(s.Scene, s.Block);
  op.Apply(q, B);
  double in = 0.0, out = 0.0;
  for (int t = 0; t < n; ++t)
  {
    in += A[t] * q[3 * t + 1];
    out += A[t] * B[3 * t + 1];
  }
  EXPECT_LT(out, 0.99 * in);
  EXPECT_GT(out, 0.0);
}

TEST(Radiosity, ExitanceMatchesEquation3WithNSquaredLaw)
{
  // The exitance M = phi/(2A) - q (1 - Fdr)/(1 + Fdr) against the
  // hemispherical integral of TransCut eq. 3 with the n^2 law: the two agree
  // up to the polynomial fit of Fdr (1 - Fdr_internal vs T_u / eta^2).
  for (double eta : { 1.3, 1.5 })
  {
    const double fdr = Fresnel::DiffuseReflectance(eta);
    const double a = Fresnel::MismatchA(eta);
    for (double phi : { 3.0, 10.0 })
    {
      const double q = 1.0;
      const double ours = phi / (2 * a) - q * (1 - fdr) / (1 + fdr);
      // 2 pi int_0^1 L(mu) mu dmu by the midpoint rule.
      const int m = 20000;
      double integral = 0.0;
      for (int k = 0; k < m; ++k)
      {
        const double mu = (k + 0.5) / m;
        integral += OutgoingRadiance(phi, q, eta, mu, RadianceReadout::EnergyConserving) * mu / m;
      }
      integral *= 2 * Pi;
      EXPECT_NEAR(ours, integral, 0.03 * integral) << "eta " << eta << " phi " << phi;
    }
  }
}

// ---- Profile S

TEST(Radiosity, DipoleProfileIntegratesToTotalReflectance)
{
  // int_0^inf R_d(r) 2 pi r dr = the closed-form total diffuse reflectance.
  for (double muA : { 0.002, 0.05, 0.5 })
  {
    const double sigmaS = 2.0, eta = 1.3;
    double sum = 0.0;
    const double dr = 1e-4;
    for (double r = 0.5 * dr; r < 400.0; r += dr * (1.0 + r))
    {
      const double step = dr * (1.0 + r);
      sum += DipoleProfile(r, muA, sigmaS, eta) * 2 * Pi * r * step;
    }
    EXPECT_NEAR(sum, DipoleTotalReflectance(muA, sigmaS, eta),
      2e-3 * DipoleTotalReflectance(muA, sigmaS, eta))
      << "mu_a " << muA;
  }
}

TEST(Radiosity, DiffusionAndProfileAgreeOnHomogeneousCube)
{
  // A 6 mm cube of a marble-like material lit by a point light above one
  // face, alone (no room: S E only). The dipole assumes a flat half-space;
  // on a cube it misses the edges and the finite size.
  RadiosityScene scene;
  const double origin[3] = { 0, 0, 0 };
  auto mesh = Cube(8, 6.0, origin);
  const int block = scene.AddTranslucent("cube", mesh, Material(mesh->GetNumberOfTets(), 0.02, 2.0));
  scene.Build();
  const std::vector<LightSource> lights = { PointLight(3, 3, 12, 100.0) };
  std::vector<double> E, q;
  scene.ComputeDirectIrradiance(lights, true, E, q);
  DiffusionSubsurface diffusion;
  diffusion.SetRelTol(1e-10);
  diffusion.Setup(scene, block);
  ProfileSubsurface profile;
  profile.SetVoxelSize(0.5);
  profile.Setup(scene, block);
  std::vector<double> bd, bp;
  diffusion.Apply(q, bd);
  profile.Apply(q, bp);
  const std::vector<double>& A = mesh->GetBoundaryTriangleAreas();
  const int n = mesh->GetNumberOfBoundaryTriangles();
  double in = 0.0, outD = 0.0, outP = 0.0, topD = 0.0, topP = 0.0;
  for (int t = 0; t < n; ++t)
  {
    in += A[t] * q[3 * t];
    outD += A[t] * bd[3 * t];
    outP += A[t] * bp[3 * t];
    if (scene.GetNormals()[3 * t + 2] > 0.9)
    {
      topD += A[t] * bd[3 * t];
      topP += A[t] * bp[3 * t];
    }
  }
  // Both below the power that entered. On the lit face, where the object
  // looks like a half-space, within 10 %; in total the dipole gives less:
  // the half-space loses what the finite cube sends out through its other
  // faces (within 25 %; see Documentation/Radiosity.md for the numbers).
  EXPECT_LT(outD, in);
  EXPECT_LT(outP, in);
  EXPECT_LT(outP, outD);
  EXPECT_NEAR(outP, outD, 0.25 * outD);
  EXPECT_NEAR(topP, topD, 0.10 * topD);
  std::printf("cube: in %.4g, out diffusion %.4g, profile %.4g; lit face %.4g vs %.4g\n", in, outD,
    outP, topD, topP);
  // Translucency change reuses the distances: a second Setup with another
  // material changes the values, not the pattern.
  const long long nnz = profile.GetNumberOfNonZeros();
  scene.SetMaterial(block, Material(mesh->GetNumberOfTets(), 0.2, 2.0));
  profile.Setup(scene, block);
  EXPECT_EQ(profile.GetNumberOfNonZeros(), nnz);
  std::vector<double> bp2;
  profile.Apply(q, bp2);
  double out2 = 0.0;
  for (int t = 0; t < n; ++t)
  {
    out2 += A[t] * bp2[3 * t];
  }
  EXPECT_LT(out2, outP);
}

TEST(Radiosity, HeterogeneityHeuristicDarkensAbsorbingPart)
{
  // Eq. 16: a cube whose half x < 2 turns much more absorbing lets less light
  // out. (Eq. 16 does not reduce to the homogeneous profile when a
  // homogeneous object is split into two parts: S(f r) S((1-f) r) / S(0) is
  // not S(r) for the dipole, so no such identity is tested.)
  RadiosityScene scene;
  const double origin[3] = { 0, 0, 0 };
  auto mesh = Cube(6, 4.0, origin);
  OpticalProperties m = Material(mesh->GetNumberOfTets(), 0.05, 1.5);
  OpticalProperties m2 = m;
  const int block = scene.AddTranslucent("cube", mesh, m);
  scene.Build();
  std::vector<double> E, q;
  scene.ComputeDirectIrradiance({ PointLight(3, 2, 8) }, true, E, q);
  ProfileSubsurface one, two;
  one.SetVoxelSize(0.4);
  two.SetVoxelSize(0.4);
  one.Setup(scene, block);
  std::vector<double> b1, b2;
  one.Apply(q, b1);
  // A much more absorbing half darkens the exit on the far side.
  for (int t = 0; t < mesh->GetNumberOfTets(); ++t)
  {
    if (mesh->GetPoint(mesh->GetTet(t)[0])[0] < 2.0)
    {
      for (int c = 0; c < 3; ++c)
        m2.AbsorptionCoefficient[3 * t + c] = 1.0;
    }
  }
  scene.SetMaterial(block, m2);
  two.Setup(scene, block);
  two.Apply(q, b2);
  // Patches of the far half (x < 2) darken more than those of the lit half.
  double far1 = 0.0, far2 = 0.0, near1 = 0.0, near2 = 0.0;
  for (int t = 0; t < mesh->GetNumberOfBoundaryTriangles(); ++t)
  {
    const double x = scene.GetCentroids()[3 * t];
    (x < 2.0 ? far1 : near1) += b1[3 * t];
    (x < 2.0 ? far2 : near2) += b2[3 * t];
  }
  EXPECT_LT(far2 / far1, near2 / near1);
  double s1 = 0.0, s2 = 0.0;
  for (size_t k = 0; k < b1.size(); ++k)
  {
    s1 += b1[k];
    s2 += b2[k];
  }
  EXPECT_LT(s2, s1);
}

// ---- Opaque -> translucent

TEST(Radiosity, TranslucentBlockLightsItsShadow)
{
  // A thin translucent slab between a spot light and the wall behind it:
  // when the slab turns from opaque (its diffuse stand-in albedo) to
  // translucent, light diffuses through it and the wall in its shadow gets
  // brighter; the lit side of the slab gets darker (light leaves elsewhere).
  RadiosityScene scene;
  AddRoom(scene);
  const double lo[3] = { 4.5, 2, 2 }, hi[3] = { 5.5, 8, 8 };
  auto mesh = Box(2, 8, 8, lo, hi);
  OpticalProperties material = Material(mesh->GetNumberOfTets(), 0.002, 1.0);
  const int block = scene.AddTranslucent("slab", mesh, material);
  scene.Build();
  FormFactorComputer computer;
  computer.SetRaysPerPatch(128);
  FormFactorMatrix F;
  ASSERT_TRUE(computer.Compute(scene, F));
  TranslucentRadiosity solver;
  solver.SetScene(&scene);
  solver.SetFormFactors(&F);
  LightSource spot;
  spot.Type = LightSource::Kind::Spot;
  spot.Position = { 1, 5, 5 };
  spot.Direction = { 1, 0, 0 };
  spot.SpotCutoff = 25.0;
  spot.Power = { 200, 200, 200 };
  RadiosityResult translucent;
  solver.Solve({ spot }, translucent);
  ASSERT_TRUE(translucent.Converged);

  // The same scene with an opaque slab of the stand-in albedo.
  RadiosityScene opaqueScene;
  AddRoom(opaqueScene);
  const std::vector<double> albedo = solver.GetDiffuseAlbedo();
  const int begin = scene.GetPatchOffset(block);
  std::vector<double> slabAlbedo(albedo.begin() + 3 * begin, albedo.end());
  opaqueScene.AddOpaque("slab", mesh->GetPoints(), mesh->GetBoundaryTriangles(), slabAlbedo);
  opaqueScene.Build();
  FormFactorMatrix F2;
  ASSERT_TRUE(computer.Compute(opaqueScene, F2));
  TranslucentRadiosity opaqueSolver;
  opaqueSolver.SetScene(&opaqueScene);
  opaqueSolver.SetFormFactors(&F2);
  RadiosityResult opaque;
  opaqueSolver.Solve({ spot }, opaque);

  // Wall x = 10 (face 1 of the room), in the slab's shadow.
  double wallT = 0.0, wallO = 0.0, litT = 0.0, litO = 0.0;
  for (int p = 0; p < scene.GetNumberOfPatches(); ++p)
  {
    const double* c = &scene.GetCentroids()[3 * p];
    const double* nrm = &scene.GetNormals()[3 * p];
    const double a = scene.GetAreas()[p];
    if (p < begin && c[0] > 9.99 && std::abs(c[1] - 5) < 2 && std::abs(c[2] - 5) < 2)
    {
      wallT += a * translucent.Combined[3 * p + 1];
      wallO += a * opaque.Combined[3 * p + 1];
    }
    if (p >= begin && nrm[0] < -0.9)
    {
      litT += a * translucent.Combined[3 * p + 1];
      litO += a * opaque.Combined[3 * p + 1];
    }
  }
  EXPECT_GT(wallT, 1.5 * wallO);
  EXPECT_LT(litT, litO);
}

TEST(Radiosity, NearZeroTranslucencyTendsToOpaque)
{
  // mu_a = 0 and sigma_s' -> infinity: light re-emerges where it entered,
  // and (no absorption) all of it: an opaque block of albedo T_u(eta) for
  // diffuse light. The block is not lit directly (the spot light misses it),
  // so it only receives diffuse light. The difference of the wall radiosity
  // between the translucent and the opaque block must fall with sigma_s'.
  RadiosityScene opaqueScene;
  AddRoom(opaqueScene);
  const double lo[3] = { 6, 6, 0 }, hi[3] = { 9, 9, 3 };
  auto mesh = Box(3, 3, 3, lo, hi);
  const double tu = Fresnel::UniformTransmittance(1.3);
  opaqueScene.AddOpaque("block", mesh->GetPoints(), mesh->GetBoundaryTriangles(),
    Grey(mesh->GetNumberOfBoundaryTriangles(), tu));
  opaqueScene.Build();
  FormFactorComputer computer;
  computer.SetRaysPerPatch(128);
  FormFactorMatrix Fo;
  ASSERT_TRUE(computer.Compute(opaqueScene, Fo));
  LightSource spot;
  spot.Type = LightSource::Kind::Spot;
  spot.Position = { 2, 2, 9 };
  spot.Direction = { 0, 0, -1 };
  spot.SpotCutoff = 20.0;
  spot.Power = { 100, 100, 100 };
  TranslucentRadiosity opaqueSolver;
  opaqueSolver.SetScene(&opaqueScene);
  opaqueSolver.SetFormFactors(&Fo);
  opaqueSolver.SetRelTol(1e-6);
  RadiosityResult opaque;
  opaqueSolver.Solve({ spot }, opaque);
  const int walls = opaqueScene.GetPatchOffset(1);

  double previous = std::numeric_limits<double>::infinity();
  for (double sigmaS : { 0.3, 3.0, 30.0, 300.0 })
  {
    RadiosityScene scene;
    AddRoom(scene);
    scene.AddTranslucent("block", mesh, Material(mesh->GetNumberOfTets(), 0.0, sigmaS));
    scene.Build();
    // Same geometry and seed: the same form factors.
    FormFactorMatrix F;
    ASSERT_TRUE(computer.Compute(scene, F));
    TranslucentRadiosity solver;
    solver.SetScene(&scene);
    solver.SetFormFactors(&F);
    solver.SetRelTol(1e-6);
    RadiosityResult result;
    solver.Solve({ spot }, result);
    ASSERT_TRUE(result.Converged);
    double diff = 0.0, norm = 0.0;
    for (int k = 0; k < 3 * walls; ++k)
    {
      const double a = scene.GetAreas()[k / 3];
      diff += a * std::abs(result.Combined[k] - opaque.Combined[k]);
      norm += a * std::abs(opaque.Combined[k]);
    }
    const double relative = diff / norm;
    std::printf("sigma_s' %g: wall difference to opaque %.3g\n", sigmaS, relative);
    EXPECT_LT(relative, previous);
    previous = relative;
  }
  EXPECT_LT(previous, 0.01);
}

// ---- Bad input

TEST(Radiosity, BadInput)
{
  RadiosityScene scene;
  std::vector<double> p;
  std::vector<int> t;
  Square(0.0, true, p, t);
  try
  {
    scene.AddOpaque("floor", p, t, { 0.5, 0.5, 0.5, 0.5, 1.2, 0.5 });
    FAIL() << "albedo > 1 accepted";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("triangle 1 has albedo 1.2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'floor'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(scene.AddOpaque("floor", p, t, { 0.5, 0.5, -0.1, 0.5, 0.5, 0.5 }), Error);
  EXPECT_THROW(scene.AddOpaque("floor", p, t, { 0.5, 0.5, 0.5 }), Error);
  const double origin[3] = { 0, 0, 0 };
  auto mesh = Cube(2, 1.0, origin);
  try
  {
    scene.AddTranslucent("marble", mesh, OpticalProperties());
    FAIL() << "translucent object without coefficients accepted";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("without coefficients"), std::string::npos) << e.what();
  }
  OpticalProperties bad = Material(mesh->GetNumberOfTets(), 0.1, 1.0);
  bad.AbsorptionCoefficient[4] = -1.0;
  EXPECT_THROW(scene.AddTranslucent("marble", mesh, bad), Error);

  // A light inside a closed opaque block.
  RadiosityScene room;
  AddRoom(room);
  const double lo[3] = { 2, 2, 0 }, hi[3] = { 5, 4, 3 };
  RadiosityScene::BoxSurface(lo, hi, 1.0, false, -1, p, t);
  room.AddOpaque("block", p, t, Grey(static_cast<int>(t.size() / 3), 0.5));
  room.Build();
  std::vector<double> E, q;
  try
  {
    room.ComputeDirectIrradiance({ PointLight(3, 3, 1) }, true, E, q);
    FAIL() << "light inside an opaque block accepted";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("inside the closed opaque object 1 'block'"),
      std::string::npos)
      << e.what();
  }
  // Inside the open room is fine.
  EXPECT_NO_THROW(room.ComputeDirectIrradiance({ PointLight(8, 8, 8) }, true, E, q));
  LightSource spot;
  spot.Type = LightSource::Kind::Spot;
  spot.Position = { 8, 8, 8 };
  spot.SpotCutoff = 0.0;
  EXPECT_THROW(room.ComputeDirectIrradiance({ spot }, true, E, q), Error);
  // Form factors that do not match the scene.
  FormFactorMatrix F;
  TranslucentRadiosity solver;
  solver.SetScene(&room);
  solver.SetFormFactors(&F);
  EXPECT_THROW(solver.Setup(), Error);
  EXPECT_THROW(solver.SetSubsurfaceMethod("hemicube"), Error);
}

TEST(Radiosity, SpotLightCone)
{
  // Irradiance of a spot light: I cos^e(alpha) cos(theta) / d^2 inside the
  // cone, 0 outside.
  LightSource spot;
  spot.Type = LightSource::Kind::Spot;
  spot.Position = { 0, 0, 10 };
  spot.Direction = { 0, 0, -2 };
  spot.SpotCutoff = 30.0;
  spot.SpotExponent = 2.0;
  spot.Power = { 100, 100, 100 };
  const double n[3] = { 0, 0, 1 };
  double q[3], w[3], d;
  const double x[3] = { 3, 0, 0 }; // alpha = atan(0.3) = 16.7 deg
  ASSERT_TRUE(DirectIrradiance(spot, x, n, 1.0, q, w, d));
  const double cosA = 10.0 / std::sqrt(109.0);
  EXPECT_NEAR(q[0], 100.0 * cosA * cosA * cosA / 109.0, 1e-12);
  const double far[3] = { 7, 0, 0 }; // 35 deg: outside
  EXPECT_FALSE(DirectIrradiance(spot, far, n, 1.0, q, w, d));
  EXPECT_EQ(q[0], 0.0);
}


// ---- RadiositySession: what is kept between runs

/// A room with a translucent cube, gathered like the filter does (Build(false)).
std::unique_ptr<RadiosityScene> SessionScene(
  const std::shared_ptr<TetMesh>& mesh, double sigmaS, double wall = -1.0)
{
  auto scene = std::make_unique<RadiosityScene>();
  AddRoom(*scene, 5.0);
  if (wall >= 0.0)
  {
    RadiosityObject room = scene->GetObject(0);
    scene = std::make_unique<RadiosityScene>();
    scene->AddOpaque("room", room.Points, room.Triangles,
      std::vector<double>(room.Albedo.size(), wall));
  }
  scene->AddTranslucent("cube", mesh, Material(mesh->GetNumberOfTets(), 0.05, sigmaS));
  scene->Build(false);
  return scene;
}

TEST(Radiosity, SessionKeepsFormFactorsAndUpdatesMaterials)
{
  const double origin[3] = { 3, 3, 0 };
  auto mesh = Cube(3, 3.0, origin);
  const std::vector<LightSource> lights = { PointLight(5, 5, 9) };
  RadiositySession session;
  session.SetRaysPerPatch(32);
  EXPECT_FALSE(session.HasValidFormFactors());
  EXPECT_THROW(session.GetSolver(SubsurfaceSettings()), Error);
  ASSERT_TRUE(session.UpdateScene(SessionScene(mesh, 1.0)));
  EXPECT_TRUE(session.HasValidFormFactors());
  const RadiosityScene* kept = session.GetScene();
  RadiosityResult first;
  session.GetSolver(SubsurfaceSettings()).Solve(lights, first);
  const TranslucentRadiosity* solver = session.GetKeptSolver();

  // Same patches, new material and wall albedo: the scene, F and solver are kept and updated.
  session.ResetTimes();
  ASSERT_TRUE(session.UpdateScene(SessionScene(mesh, 2.0, 0.3)));
  EXPECT_EQ(session.GetScene(), kept);
  EXPECT_EQ(session.GetFormFactorMilliseconds(), 0.0);
  EXPECT_EQ(session.GetKeptSolver(), solver);
  EXPECT_EQ(kept->GetObject(1).Material.ReducedScatteringCoefficient[0], 2.0);
  EXPECT_EQ(kept->GetObject(0).Albedo[0], 0.3);
  RadiosityResult updated, fresh;
  session.GetSolver(SubsurfaceSettings()).Solve(lights, updated);
  // A session started on the changed scene gives the same radiosity.
  RadiositySession other;
  other.SetRaysPerPatch(32);
  ASSERT_TRUE(other.UpdateScene(SessionScene(mesh, 2.0, 0.3)));
  other.GetSolver(SubsurfaceSettings()).Solve(lights, fresh);
  ASSERT_EQ(updated.Combined.size(), fresh.Combined.size());
  for (size_t i = 0; i < fresh.Combined.size(); ++i)
  {
    EXPECT_NEAR(updated.Combined[i], fresh.Combined[i], 1e-3 * std::abs(fresh.Combined[i]) + 1e-12);
  }

  // New ray settings: new form factors and a new solver; new subsurface settings: a new solver.
  session.SetRaysPerPatch(16);
  EXPECT_FALSE(session.HasValidFormFactors());
  ASSERT_TRUE(session.UpdateScene(SessionScene(mesh, 2.0, 0.3)));
  EXPECT_NE(session.GetScene(), kept);
  EXPECT_EQ(session.GetKeptSolver(), nullptr);
  SubsurfaceSettings profile;
  profile.Method = "profile";
  TranslucentRadiosity& a = session.GetSolver(SubsurfaceSettings());
  TranslucentRadiosity& b = session.GetSolver(profile);
  EXPECT_EQ(b.GetSubsurfaceMethod(), "profile");
  EXPECT_EQ(&session.GetSolver(profile), &b);
  (void)a;

  // Stopped by the progress callback: nothing kept.
  session.SetRaysPerPatch(8);
  session.SetProgressCallback([](double) { return false; });
  EXPECT_FALSE(session.UpdateScene(SessionScene(mesh, 2.0)));
  EXPECT_EQ(session.GetScene(), nullptr);
  EXPECT_FALSE(session.HasValidFormFactors());
}

} // namespace

// Issue 21: the patch count of a box is estimated before anything is
// allocated; a cell size of 1e-3 mm (or a 1.5e13 mm box) is refused with a
// message naming the count and the override, and a larger limit lifts it.
TEST(RadiosityScene, BoxSurfaceRefusesTooManyPatches)
{
  using namespace translucency;
  std::vector<double> points;
  std::vector<int> triangles;
  const double lo[3] = { 0, 0, 0 }, hi[3] = { 20, 20, 20 }, huge[3] = { 1.5e13, 1.5e13, 1.5e13 };
  try
  {
    RadiosityScene::BoxSurface(lo, hi, 1e-3, true, -1, points, triangles);
    FAIL() << "no error for 4.8e9 patches";
  }
  catch (const Error& e)
  {
    const std::string m = e.what();
    EXPECT_NE(m.find("cell size 0.001 mm"), std::string::npos) << m;
    EXPECT_NE(m.find("4.8e+09 patches"), std::string::npos) << m;
    EXPECT_NE(m.find("--memory-limit"), std::string::npos) << m;
  }
  EXPECT_TRUE(points.empty());
  EXPECT_THROW(RadiosityScene::BoxSurface(lo, huge, 2.0, true, -1, points, triangles), Error);
  // 4800 patches (~4.8 MB): refused under a 1 MiB limit, built under the default.
  EXPECT_THROW(
    RadiosityScene::BoxSurface(lo, hi, 1.0, true, -1, points, triangles, nullptr, 1 << 20), Error);
  RadiosityScene::BoxSurface(lo, hi, 1.0, true, -1, points, triangles);
  EXPECT_EQ(triangles.size(), 3u * 4800u);
}
