// The Monte Carlo reference (MonteCarloSolver) against an analytic solution
// (a non-scattering absorbing slab with Fresnel reflections), an exact power
// balance, its own reported standard errors (spread over seeds), the
// diffusion solvers deep inside a strongly scattering box, and its
// reproducibility (same seed: bit-identical for 1 and 2 threads).

#include "DiffusionSolverFactory.h"
#include "Error.h"
#include "Fresnel.h"
#include "LightSources.h"
#include "MonteCarlo.h"
#include "Radiance.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TetMesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <iostream>
#include <string>
#include <vector>

namespace
{

using namespace translucency;
using translucency::testing::BoxMesh;
using translucency::testing::CubeMesh;
using translucency::testing::MeshData;
using translucency::testing::MakeProblem;

constexpr double Pi = 3.14159265358979323846;

TetMesh Build(const MeshData& data)
{
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  return mesh;
}

/// An L-shaped block: the cube [0, 6]^3 (n cells per side, jittered) without
/// the tets whose centroid has x > 3 and z > 3. Lights from +x+z cast
/// shadows on it.
MeshData LShape(int n, std::uint64_t seed)
{
  MeshData cube = CubeMesh(n, 6.0, 0.2, seed);
  MeshData out;
  out.Points = cube.Points;
  for (int t = 0; t < cube.NumberOfTets(); ++t)
  {
    double centroid[3] = { 0.0, 0.0, 0.0 };
    for (int a = 0; a < 4; ++a)
    {
      for (int k = 0; k < 3; ++k)
      {
        centroid[k] += 0.25 * cube.Points[3 * cube.Tets[4 * t + a] + k];
      }
    }
    if (!(centroid[0] > 3.0 && centroid[2] > 3.0))
    {
      out.Tets.insert(out.Tets.end(), &cube.Tets[4 * t], &cube.Tets[4 * t + 4]);
    }
  }
  return out;
}

LightSource Directional(double dx, double dy, double dz, double r, double g, double b)
{
  LightSource light;
  light.Type = LightSource::Kind::Directional;
  light.Direction = { dx, dy, dz };
  light.Power = { r, g, b };
  return light;
}

/// Integral over tet t of f(x) (mm^3 x units of f) by a collapsed (Duffy)
/// 8 x 8 x 8 Gauss-Legendre rule: exact to round-off for the smooth
/// exponentials used here.
double IntegrateOverTet(const TetMesh& mesh, int t, const std::function<double(const double*)>& f)
{
  static const double nodes[8] = { -0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
    -0.1834346424956498, 0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
    0.9602898564975363 };
  static const double weights[8] = { 0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
    0.3626837833783620, 0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
    0.1012285362903763 };
  const int* v = mesh.GetTet(t);
  const double* p0 = mesh.GetPoint(v[0]);
  double e[3][3];
  for (int a = 0; a < 3; ++a)
  {
    for (int k = 0; k < 3; ++k)
    {
      e[a][k] = mesh.GetPoint(v[a + 1])[k] - p0[k];
    }
  }
  double sum = 0.0;
  for (int i = 0; i < 8; ++i)
  {
    for (int j = 0; j < 8; ++j)
    {
      for (int k = 0; k < 8; ++k)
      {
        const double u = 0.5 * (nodes[i] + 1.0), w1 = 0.5 * (nodes[j] + 1.0),
                     w2 = 0.5 * (nodes[k] + 1.0);
        const double xi[3] = { u, w1 * (1.0 - u), w2 * (1.0 - u) * (1.0 - w1) };
        double x[3];
        for (int d = 0; d < 3; ++d)
        {
          x[d] = p0[d] + xi[0] * e[0][d] + xi[1] * e[1][d] + xi[2] * e[2][d];
        }
        const double jac = (1.0 - u) * (1.0 - u) * (1.0 - w1) / 8.0;
        sum += weights[i] * weights[j] * weights[k] * jac * f(x);
      }
    }
  }
  return 6.0 * mesh.GetTetVolume(t) * sum;
}

struct Result
{
  std::vector<double> Fluence;
  SolverReport Report;
};

Result Solve(MonteCarloSolver& solver, const DiffusionProblem& problem)
{
  Result run;
  EXPECT_TRUE(solver.Solve(problem, run.Fluence, run.Report));
  return run;
}

// ---------------------------------------------------------------------------
// Analytic: a non-scattering absorbing slab under a normal collimated beam.
// A box 24 x 24 x 4 mm lit from +z: below the middle of the top face the
// photons go straight down, are reflected at the bottom (probability R) and
// at the top, so the fluence is the geometric series
//   phi(z) = q [exp(-mu (L - z)) + R exp(-mu (L + z))] / (1 - R^2 exp(-2 mu L)),
// q = E F_t(1), R = Fresnel reflectance at normal incidence, and the exitance
// M_bottom = q (1 - R) exp(-mu L) / (1 - R^2 exp(-2 mu L)),
// M_top = q R (1 - R) exp(-2 mu L) / (1 - R^2 exp(-2 mu L)).
// The expected vertex estimate is the integral of phi over the vertex's tets
// / V_i (computed here by quadrature). Photons entering near the top edges
// start diffusely (their q comes from tilted vertex normals) but die within
// the 10 mm to the middle (mu L >= 3).
TEST(MonteCarlo, NonScatteringSlabMatchesBeerLambertWithFresnelReflections)
{
  const double lx = 24.0, lz = 4.0;
  const TetMesh mesh = Build(BoxMesh(12, 12, 4, lx, lx, lz));
  const double eta = 1.4;
  const double muA[3] = { 0.5, 0.3, 0.2 }, sigmaS[3] = { 0.0, 0.0, 0.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigmaS, eta);
  DiffusionProblem problem = MakeProblem(mesh, material);
  problem.Lights = { Directional(0.0, 0.0, -1.0, 1.0, 2.0, 0.0) }; // blue dark
  problem.Shadows = false;

  MonteCarloSolver solver;
  solver.SetNumberOfPhotons(150000);
  solver.SetSeed(7);
  const Result run = Solve(solver, problem);

  const double r = Fresnel::Reflectance(1.0, eta);
  ASSERT_GT(r, 0.02); // the reflections matter
  int checked = 0;
  for (int c = 0; c < 2; ++c)
  {
    const double e = problem.Lights[0].Power[c];
    const double q = e * Fresnel::Transmittance(1.0, eta);
    const double mu = muA[c];
    const double denom = 1.0 - r * r * std::exp(-2.0 * mu * lz);
    auto phi = [&](const double* x) {
      return q * (std::exp(-mu * (lz - x[2])) + r * std::exp(-mu * (lz + x[2]))) / denom;
    };
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      const double* x = mesh.GetPoint(i);
      if (std::abs(x[0] - 12.0) > 2.1 || std::abs(x[1] - 12.0) > 2.1)
      {
        continue; // the middle 3 x 3 columns of vertices
      }
      const double value = run.Fluence[3 * i + c];
      const double se = run.Report.FluenceStandardError[3 * i + c];
      {
        double integral = 0.0;
        for (int k = mesh.GetPointTetOffsets()[i]; k < mesh.GetPointTetOffsets()[i + 1]; ++k)
        {
          integral += IntegrateOverTet(mesh, mesh.GetPointTets()[k], phi);
        }
        const double expected = integral / mesh.GetVertexVolumes()[i];
        EXPECT_LT(se, 0.03 * expected) << "point " << i;
        EXPECT_NEAR(value, expected, 4.0 * se) << "channel " << c << " point " << i << " z "
                                                << x[2];
        ++checked;
      }
      if (mesh.IsBoundaryPoint(i) && (x[2] == 0.0 || x[2] == lz))
      {
        const double m = x[2] == 0.0 ? q * (1.0 - r) * std::exp(-mu * lz) / denom
                                     : q * r * (1.0 - r) * std::exp(-2.0 * mu * lz) / denom;
        const double exitance = solver.GetExitance()[3 * i + c];
        const double exitanceSe = solver.GetExitanceStandardError()[3 * i + c];
        if (x[2] == 0.0)
        {
          EXPECT_LT(exitanceSe, 0.03 * m) << "point " << i; // top: few photons come back
        }
        EXPECT_NEAR(exitance, m, 4.0 * exitanceSe) << "channel " << c << " point " << i;
        // Radiance: the documented conversion of the exitance.
        const double toRadiance =
          Fresnel::Transmittance(1.0, eta) / (Pi * Fresnel::UniformTransmittance(eta));
        EXPECT_NEAR(run.Report.Radiance[3 * i + c], exitance * toRadiance, 1e-12 * exitance);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 2 * 9 * (5 + 2));
  // The dark channel gets no photon and stays 0; nothing is lost.
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    EXPECT_EQ(run.Fluence[3 * i + 2], 0.0);
  }
  EXPECT_EQ(solver.GetPowerBalance(2).Photons, 0);
  EXPECT_EQ(solver.GetNumberOfPhotonsTraced(), 300000);
  for (int c = 0; c < 2; ++c)
  {
    EXPECT_EQ(solver.GetPowerBalance(c).LostPhotons, 0);
  }
}

// ---------------------------------------------------------------------------
// Power balance. With continuous absorption the weight a photon loses on a
// segment is both the absorbed power and mu_a x its track-length tally, so
// sum_t mu_a phi_t V_t + sum_i M_i S_i / 3 (+ lost) = injected + roulette
// gain, to round-off, whatever the number of photons. The roulette gain
// has mean 0 and is tiny (weights below 1e-4 of the launch weight); the
// injected power equals the integral of the pipeline's q over the boundary.
TEST(MonteCarlo, PowerBalanceIsExact)
{
  const TetMesh mesh = Build(LShape(6, 3));
  const double muA[3] = { 0.05, 0.2, 0.8 }, sigmaS[3] = { 1.5, 1.0, 0.6 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigmaS, 1.4);
  DiffusionProblem problem = MakeProblem(mesh, material);
  LightSource point;
  point.Type = LightSource::Kind::Point;
  point.Position = { 12.0, 3.0, 12.0 };
  point.Power = { 50.0, 30.0, 20.0 };
  problem.Lights = { Directional(-1.0, -0.3, -1.0, 1.0, 0.5, 2.0), point };
  problem.UniformIrradiance = 0.3;
  problem.Shadows = true;

  MonteCarloSolver solver;
  solver.SetNumberOfPhotons(20000);
  solver.SetUniformLightSamples(16);
  const Result run = Solve(solver, problem);

  // The pipeline's q with the same lights and samples (vtkSurfaceIrradiance's
  // triangle-integrated irradiance).
  std::vector<double> q;
  ASSERT_TRUE(ComputeProjectedIrradiance(mesh, material.RefractiveIndex, problem.Lights,
    problem.UniformIrradiance, 16, true, q));
  for (int c = 0; c < 3; ++c)
  {
    double injected = 0.0;
    for (int i : mesh.GetBoundaryPoints())
    {
      injected += mesh.GetBoundaryAreas()[i] / 3.0 * q[3 * i + c];
    }
    double absorbed = 0.0;
    for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
    {
      absorbed += muA[c] * solver.GetTetFluence()[3 * t + c] * mesh.GetTetVolume(t);
    }
    double escaped = 0.0;
    for (int i : mesh.GetBoundaryPoints())
    {
      escaped += solver.GetExitance()[3 * i + c] * mesh.GetBoundaryAreas()[i] / 3.0;
    }
    const MonteCarloSolver::PowerBalance& b = solver.GetPowerBalance(c);
    EXPECT_NEAR(b.Injected, injected, 1e-12 * injected) << "channel " << c;
    EXPECT_EQ(b.LostPhotons, 0);
    EXPECT_EQ(b.Photons, 20000);
    // Round-off identity (1e-11 relative: sums of ~1e6 positive terms).
    EXPECT_NEAR(absorbed + escaped + b.Lost, b.Injected + b.RouletteGain, 1e-11 * injected)
      << "channel " << c;
    EXPECT_NEAR(absorbed, b.Absorbed, 1e-11 * injected);
    EXPECT_NEAR(escaped, b.Escaped, 1e-11 * injected);
    // Statistical: the roulette is unbiased and its gain small.
    EXPECT_LT(std::abs(b.RouletteGain), 1e-3 * injected) << "channel " << c;
    EXPECT_GT(absorbed, 0.05 * injected); // both terms matter
    EXPECT_GT(escaped, 0.05 * injected);
  }
  // Vertex fluence = tet fluence averaged with weights V_t.
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    if (mesh.GetVertexVolumes()[i] == 0.0)
    {
      EXPECT_EQ(run.Fluence[3 * i], 0.0);
      continue;
    }
    double sum = 0.0;
    for (int k = mesh.GetPointTetOffsets()[i]; k < mesh.GetPointTetOffsets()[i + 1]; ++k)
    {
      const int t = mesh.GetPointTets()[k];
      sum += solver.GetTetFluence()[3 * t] * mesh.GetTetVolume(t);
    }
    EXPECT_NEAR(run.Fluence[3 * i], sum / mesh.GetVertexVolumes()[i], 1e-12 * run.Fluence[3 * i]);
  }
}

// ---------------------------------------------------------------------------
// Reproducibility: the same seed gives bit-identical tallies for 1 and 2
// threads (per-photon random streams, batches added in order); another seed
// gives different ones.
TEST(MonteCarlo, SameSeedIsBitIdenticalForOneAndTwoThreads)
{
  const TetMesh mesh = Build(LShape(5, 1));
  const MaterialPreset& marble = FindMaterialPreset("marble");
  const OpticalProperties material = OpticalProperties::Uniform(
    mesh.GetNumberOfTets(), marble.Absorption, marble.ReducedScattering, marble.RefractiveIndex);
  DiffusionProblem problem = MakeProblem(mesh, material);
  problem.Lights = { Directional(-1.0, 0.2, -1.0, 1.0, 1.0, 1.0) };
  problem.UniformIrradiance = 0.2;

  auto run = [&](int threads, unsigned long long seed) {
    MonteCarloSolver solver;
    solver.SetNumberOfPhotons(6000);
    solver.SetNumberOfBatches(8);
    solver.SetNumberOfThreads(threads);
    solver.SetSeed(seed);
    solver.SetUniformLightSamples(8);
    Result r = Solve(solver, problem);
    EXPECT_EQ(solver.GetNumberOfThreadsUsed(), threads);
    r.Fluence.insert(r.Fluence.end(), solver.GetTetFluence().begin(),
      solver.GetTetFluence().end());
    return r;
  };
  const Result serial = run(1, 5), parallel = run(2, 5), again = run(2, 5), other = run(2, 6);
  ASSERT_EQ(serial.Fluence.size(),
    3u * (mesh.GetNumberOfPoints() + static_cast<size_t>(mesh.GetNumberOfTets())));
  EXPECT_EQ(serial.Fluence, parallel.Fluence);
  EXPECT_EQ(serial.Report.FluenceStandardError, parallel.Report.FluenceStandardError);
  EXPECT_EQ(serial.Report.Radiance, parallel.Report.Radiance);
  EXPECT_EQ(serial.Report.RadianceStandardError, parallel.Report.RadianceStandardError);
  EXPECT_EQ(parallel.Fluence, again.Fluence);
  EXPECT_NE(parallel.Fluence, other.Fluence);
  EXPECT_EQ(serial.Report.LinearSolver, "photons");
}

// ---------------------------------------------------------------------------
// The reported standard errors match the spread over independent seeds:
// ratio of the empirical SD over 8 seeds to the mean reported SE, pooled
// over the vertices as sqrt(sum s_i^2 / sum se_i^2), in [0.7, 1.4]. (Each
// s_i^2 has 7 degrees of freedom; pooled over ~200 vertices the ratio is
// known to a few per cent, the band is for the correlation between
// neighbouring vertices.)
TEST(MonteCarlo, StandardErrorMatchesSpreadOverSeeds)
{
  const TetMesh mesh = Build(CubeMesh(6, 4.0, 0.2, 2));
  const double muA[3] = { 0.1, 0.1, 0.1 }, sigmaS[3] = { 1.0, 1.0, 1.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigmaS, 1.3);
  DiffusionProblem problem = MakeProblem(mesh, material);
  problem.Lights = { Directional(-0.3, -0.2, -1.0, 1.0, 0.0, 0.0) };

  const int seeds = 8;
  const int numPoints = mesh.GetNumberOfPoints();
  std::vector<double> sum(numPoints, 0.0), sum2(numPoints, 0.0), se2(numPoints, 0.0);
  std::vector<double> rsum(numPoints, 0.0), rsum2(numPoints, 0.0), rse2(numPoints, 0.0);
  for (int s = 0; s < seeds; ++s)
  {
    MonteCarloSolver solver;
    solver.SetNumberOfPhotons(8000);
    solver.SetNumberOfBatches(16);
    solver.SetSeed(100 + s);
    const Result run = Solve(solver, problem);
    for (int i = 0; i < numPoints; ++i)
    {
      const double v = run.Fluence[3 * i], e = run.Report.FluenceStandardError[3 * i];
      sum[i] += v;
      sum2[i] += v * v;
      se2[i] += e * e / seeds;
      const double rv = run.Report.Radiance[3 * i], re = run.Report.RadianceStandardError[3 * i];
      rsum[i] += rv;
      rsum2[i] += rv * rv;
      rse2[i] += re * re / seeds;
    }
  }
  double var = 0.0, reported = 0.0, rvar = 0.0, rreported = 0.0;
  int count = 0, rcount = 0;
  for (int i = 0; i < numPoints; ++i)
  {
    var += (sum2[i] - sum[i] * sum[i] / seeds) / (seeds - 1);
    reported += se2[i];
    ++count;
    if (mesh.IsBoundaryPoint(i))
    {
      rvar += (rsum2[i] - rsum[i] * rsum[i] / seeds) / (seeds - 1);
      rreported += rse2[i];
      ++rcount;
    }
  }
  const double ratio = std::sqrt(var / reported), rratio = std::sqrt(rvar / rreported);
  std::cout << "SD over seeds / reported SE: fluence " << ratio << " (" << count
            << " vertices), radiance " << rratio << " (" << rcount << " boundary vertices)\n";
  EXPECT_GT(ratio, 0.7);
  EXPECT_LT(ratio, 1.4);
  EXPECT_GT(rratio, 0.7);
  EXPECT_LT(rratio, 1.4);
}

// ---------------------------------------------------------------------------
// Exact transport: the plane albedo of a half-space of isotropic scatterers
// (single-scattering albedo omega, index-matched boundary) for a normal
// collimated beam is 1 - H(1) sqrt(1 - omega) (Chandrasekhar, Radiative
// Transfer, Sec. 26), H the H-function, computed here by its fixed-point
// iteration H(mu) = 1 / (1 - (omega/2) mu int_0^1 H(mu') / (mu + mu') dmu')
// with 64-point Gauss-Legendre (omega = 0.9: H(1) = 1.850099, albedo
// 0.414947). The slab 80 x 80 x 15 mm (mu_t = 1 /mm) is lit on its top face;
// the exitance 12 mm or more from the sides is that of the half-space (the
// lateral and bottom leaks decay as exp(-0.53 x distance in mm)). Vertices 2
// cells apart share no triangle, so their tallies come from different
// photons and the standard error of their mean is sqrt(sum se_i^2) / n.
double PlaneAlbedoIsotropic(double omega)
{
  const int n = 64;
  std::vector<double> mu(n), w(n);
  for (int i = 0; i < n; ++i)
  {
    double x = std::cos(Pi * (i + 0.75) / (n + 0.5)), dp = 0.0;
    for (int iter = 0; iter < 100; ++iter)
    {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k)
      {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-15)
      {
        break;
      }
    }
    mu[i] = 0.5 * (x + 1.0);
    w[i] = 1.0 / ((1.0 - x * x) * dp * dp);
  }
  std::vector<double> h(n, 1.0), next(n);
  auto evaluate = [&](double m) {
    double sum = 0.0;
    for (int j = 0; j < n; ++j)
    {
      sum += w[j] * h[j] / (m + mu[j]);
    }
    return 1.0 / (1.0 - 0.5 * omega * m * sum);
  };
  for (int iter = 0; iter < 1000; ++iter)
  {
    double change = 0.0;
    for (int i = 0; i < n; ++i)
    {
      next[i] = evaluate(mu[i]);
      change = std::max(change, std::abs(next[i] - h[i]));
    }
    h.swap(next);
    if (change < 1e-14)
    {
      break;
    }
  }
  return 1.0 - evaluate(1.0) * std::sqrt(1.0 - omega);
}

TEST(MonteCarlo, HalfSpaceAlbedoMatchesChandrasekhar)
{
  const double omega = 0.9;
  const double albedo = PlaneAlbedoIsotropic(omega);
  EXPECT_NEAR(albedo, 0.414947, 2e-6); // the iteration itself

  const double lx = 80.0, lz = 15.0;
  const TetMesh mesh = Build(BoxMesh(20, 20, 15, lx, lx, lz));
  const double muA[3] = { 1.0 - omega, 0.1, 0.1 }, sigmaS[3] = { omega, 1.0, 1.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigmaS, 1.0);
  DiffusionProblem problem = MakeProblem(mesh, material);
  const double e = 2.0; // W/mm^2
  problem.Lights = { Directional(0.0, 0.0, -1.0, e, 0.0, 0.0) };
  MonteCarloSolver solver;
  solver.SetNumberOfPhotons(200000);
  Result run = Solve(solver, problem);

  double sum = 0.0, variance = 0.0;
  int count = 0;
  for (int i : mesh.GetBoundaryPoints())
  {
    const double* x = mesh.GetPoint(i);
    const long ix = std::lround(x[0] / 4.0), iy = std::lround(x[1] / 4.0);
    if (x[2] != lz || ix % 2 != 1 || iy % 2 != 1 || x[0] < 12.0 || x[0] > lx - 12.0 ||
      x[1] < 12.0 || x[1] > lx - 12.0)
    {
      continue;
    }
    sum += solver.GetExitance()[3 * i];
    variance += std::pow(solver.GetExitanceStandardError()[3 * i], 2);
    ++count;
  }
  ASSERT_EQ(count, 64);
  const double mean = sum / count / e, se = std::sqrt(variance) / count / e;
  std::cout << "half-space albedo: Monte Carlo " << mean << " +- " << se << ", exact " << albedo
            << " (" << run.Report.SolveMilliseconds << " ms, "
            << solver.GetPhotonsPerSecondPerThread() << " photons/s/thread)\n";
  EXPECT_LT(se, 0.015 * albedo);
  EXPECT_NEAR(mean, albedo, 4.0 * se);
}

// ---------------------------------------------------------------------------
// Against diffusion in a strongly scattering, weakly absorbing cube
// (sigma_s' = 3 /mm, mu_a = 0.03 /mm, eta = 1.3: transport mean free path
// l' = 1/mu_t' = 0.33 mm, cube 8 mm = 24 l'), compared at the vertices
// farther than 4 l' from every face, with the FEM solution ("fem" if the
// factory has it, else "divergence"; both converge to the same diffusion
// solution, their difference on this mesh is < 1 %).

struct DiffusionComparison
{
  TetMesh Mesh;
  OpticalProperties Material;
  std::vector<double> Irradiance;
  DiffusionProblem Problem;
  std::vector<double> Diffusion;
  std::string Reference;
  double LPrime = 0.0, Size = 8.0;

  /// A uniform light, or `light` (default: the directional light along -z).
  explicit DiffusionComparison(bool uniformLight, const LightSource* light = nullptr)
    : Mesh(Build(CubeMesh(16, 8.0, 0.0)))
  {
    const double muA[3] = { 0.03, 0.03, 0.03 }, sigmaS[3] = { 3.0, 3.0, 3.0 };
    LPrime = 1.0 / (muA[0] + sigmaS[0]);
    Material = OpticalProperties::Uniform(Mesh.GetNumberOfTets(), muA, sigmaS, 1.3);
    Problem = MakeProblem(Mesh, Material);
    if (uniformLight)
    {
      Problem.UniformIrradiance = 1.0;
    }
    else if (light)
    {
      Problem.Lights = { *light };
    }
    else
    {
      Problem.Lights = { Directional(0.0, 0.0, -1.0, 1.0, 0.0, 0.0) };
    }
    // The pipeline's (vtkSurfaceIrradiance's) triangle-integrated q.
    EXPECT_TRUE(ComputeProjectedIrradiance(Mesh, Material.RefractiveIndex, Problem.Lights,
      Problem.UniformIrradiance, 32, true, Irradiance));
    Problem.Irradiance = &Irradiance;
    const std::vector<std::string> names = GetDiffusionSolverNames();
    Reference =
      std::find(names.begin(), names.end(), "fem") != names.end() ? "fem" : "divergence";
    std::unique_ptr<DiffusionSolver> diffusion = CreateDiffusionSolver(Reference);
    diffusion->SetRelTol(1e-10);
    SolverReport report;
    EXPECT_TRUE(diffusion->Solve(Problem, Diffusion, report));
  }

  bool Deep(int i) const
  {
    const double* x = Mesh.GetPoint(i);
    for (int k = 0; k < 3; ++k)
    {
      if (std::min(x[k], Size - x[k]) < 4.0 * LPrime)
      {
        return false;
      }
    }
    return true;
  }
};

// A uniform (environment) light enters diffusely, which is what the
// diffusion boundary condition assumes (q as an incoming diffuse partial
// current). What remains is the P1 closure of the Robin condition
// (extrapolation length 2 A kappa instead of the exact transport one; a few
// per cent of the deep field) and the vertex averaging of the tallies
// (< 1 % here): tolerance 3 standard errors + 6 %.
TEST(MonteCarlo, AgreesWithDiffusionUnderDiffuseLight)
{
  DiffusionComparison setup(true);
  MonteCarloSolver solver;
  solver.SetNumberOfPhotons(60000);
  const Result run = Solve(solver, setup.Problem);
  int checked = 0;
  double worst = 0.0;
  for (int i = 0; i < setup.Mesh.GetNumberOfPoints(); ++i)
  {
    if (!setup.Deep(i))
    {
      continue;
    }
    // The uniform light is white and the material grey: the three channels
    // are three independent estimates (own random streams) of one fluence.
    double mc = 0.0, variance = 0.0;
    for (int c = 0; c < 3; ++c)
    {
      mc += run.Fluence[3 * i + c] / 3.0;
      variance += std::pow(run.Report.FluenceStandardError[3 * i + c] / 3.0, 2);
    }
    const double se = std::sqrt(variance);
    const double d = setup.Diffusion[3 * i];
    EXPECT_NEAR(mc, d, 3.0 * se + 0.06 * d) << "point " << i;
    worst = std::max(worst, std::abs(mc - d) / d);
    ++checked;
  }
  std::cout << "diffuse light, Monte Carlo vs " << setup.Reference << ": " << checked
            << " vertices, largest relative difference " << worst << " ("
            << run.Report.SolveMilliseconds << " ms)\n";
  EXPECT_GT(checked, 500);
}

// A directional (collimated) light enters along one direction and first
// scatters about l' below the surface; diffusion puts the same power on the
// surface as a diffuse source. The deep field therefore has the same shape
// but a larger amplitude in transport: for an index-matched, conservative
// half-space under normal incidence the ratio is H(1) / (2 int H(mu) mu dmu)
// = 1.26 (Chandrasekhar's H-function); Fresnel internal reflection
// (eta = 1.3) randomises the entering light and lowers it. So: the ratio
// Monte Carlo / diffusion must lie in [1.0, 1.3] on average, and be the
// same at every deep vertex within 3 standard errors + 6 % (the shape),
// at the vertices whose standard error is below 5 %.
void CheckCollimatedSourceFactor(const DiffusionComparison& setup, const std::string& label,
  std::size_t minimumVertices)
{
  MonteCarloSolver solver;
  solver.SetNumberOfPhotons(60000);
  const Result run = Solve(solver, setup.Problem);
  std::vector<int> deep;
  double sum = 0.0, weights = 0.0;
  for (int i = 0; i < setup.Mesh.GetNumberOfPoints(); ++i)
  {
    // Deep and well sampled: the tally of a rarely visited vertex is skewed
    // (few large contributions), and its batch standard error unreliable.
    if (setup.Deep(i) && run.Report.FluenceStandardError[3 * i] < 0.05 * run.Fluence[3 * i])
    {
      deep.push_back(i);
      // Mean ratio weighted by 1 / relative variance.
      const double r = run.Fluence[3 * i] / setup.Diffusion[3 * i];
      const double rel = run.Report.FluenceStandardError[3 * i] / run.Fluence[3 * i];
      sum += r / (rel * rel);
      weights += 1.0 / (rel * rel);
    }
  }
  const double ratio = sum / weights;
  EXPECT_GT(ratio, 1.0);
  EXPECT_LT(ratio, 1.3);
  double worst = 0.0;
  for (int i : deep)
  {
    const double mc = run.Fluence[3 * i], se = run.Report.FluenceStandardError[3 * i];
    const double d = ratio * setup.Diffusion[3 * i];
    EXPECT_NEAR(mc, d, 3.0 * se + 0.06 * d) << "point " << i;
    worst = std::max(worst, std::abs(mc - d) / d);
  }
  std::cout << label << ", Monte Carlo / " << setup.Reference << " = " << ratio << " over "
            << deep.size() << " vertices, largest relative deviation " << worst << " ("
            << run.Report.SolveMilliseconds << " ms)\n";
  EXPECT_GT(deep.size(), minimumVertices);
}

TEST(MonteCarlo, AgreesWithDiffusionUpToTheCollimatedSourceFactor)
{
  DiffusionComparison setup(false);
  CheckCollimatedSourceFactor(setup, "directional light", 400u);
}

// A spot light (cone and fall-off) launches its photons from its position
// with the density of its own q (the cone and cos^X fall-off are in q).
// Here it lights the whole top face from 8 mm above its centre (cone 60
// degrees, exponent 2: q at the corners about 0.4 x the centre's, incidence
// 0-35 degrees): the physics of the directional-light test, so its test and
// tolerance: ratio in [1.0, 1.3], shape within 3 SE + 6 % at the
// well-sampled deep vertices. (A cone edge inside the lit face makes the
// collimated-source factor vary across the face; the cut itself is checked
// by SpotLightPowerBalanceIsExact.)
TEST(MonteCarlo, AgreesWithDiffusionUnderASpotLight)
{
  const LightSource spot = SpotLight({ 4.0, 4.0, 16.0 }, { 0.0, 0.0, -1.0 }, 60.0, 2.0,
    { 64.0, 0.0, 0.0 });
  DiffusionComparison setup(false, &spot);
  CheckCollimatedSourceFactor(setup, "spot light", 400u);
}

// Power balance with a spot light: the injected power is the integral of
// the pipeline's q (the cone cuts the top face), and the tallies close to
// round-off; no power enters the side faces (outside the cone).
TEST(MonteCarlo, SpotLightPowerBalanceIsExact)
{
  const TetMesh mesh = Build(CubeMesh(8, 8.0, 0.0));
  const double muA[3] = { 0.02, 0.1, 0.3 }, sigmaS[3] = { 1.5, 1.0, 0.6 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigmaS, 1.4);
  DiffusionProblem problem = MakeProblem(mesh, material);
  problem.Lights = { SpotLight(
    { 4.0, 4.0, 14.0 }, { 0.0, 0.0, -1.0 }, 15.0, 4.0, { 50.0, 30.0, 20.0 }) };
  std::vector<double> q;
  ASSERT_TRUE(ComputeProjectedIrradiance(
    mesh, material.RefractiveIndex, problem.Lights, 0.0, 0, false, q));
  problem.Irradiance = &q;
  MonteCarloSolver solver;
  solver.SetNumberOfPhotons(20000);
  Solve(solver, problem);
  for (int c = 0; c < 3; ++c)
  {
    double injected = 0.0, sides = 0.0;
    for (int i : mesh.GetBoundaryPoints())
    {
      injected += mesh.GetBoundaryAreas()[i] / 3.0 * q[3 * i + c];
      if (mesh.GetPoint(i)[2] < 8.0 - 1e-9)
      {
        sides += q[3 * i + c];
      }
    }
    EXPECT_EQ(sides, 0.0); // the cone (radius 1.6 mm at the top face) misses the sides
    double absorbed = 0.0, escaped = 0.0;
    for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
    {
      absorbed += muA[c] * solver.GetTetFluence()[3 * t + c] * mesh.GetTetVolume(t);
    }
    for (int i : mesh.GetBoundaryPoints())
    {
      escaped += solver.GetExitance()[3 * i + c] * mesh.GetBoundaryAreas()[i] / 3.0;
    }
    const MonteCarloSolver::PowerBalance& b = solver.GetPowerBalance(c);
    EXPECT_GT(injected, 0.0);
    EXPECT_NEAR(b.Injected, injected, 1e-12 * injected) << "channel " << c;
    EXPECT_EQ(b.LostPhotons, 0);
    EXPECT_NEAR(absorbed + escaped + b.Lost, b.Injected + b.RouletteGain, 1e-11 * injected)
      << "channel " << c;
    EXPECT_LT(std::abs(b.RouletteGain), 1e-3 * injected) << "channel " << c;
    EXPECT_GT(absorbed, 0.05 * injected);
    EXPECT_GT(escaped, 0.05 * injected);
  }
}

// ---------------------------------------------------------------------------
TEST(MonteCarlo, FactoryProgressAndAbort)
{
  std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver("MonteCarlo");
  EXPECT_EQ(solver->GetName(), "montecarlo");
  EXPECT_NE(dynamic_cast<MonteCarloSolver*>(solver.get()), nullptr);
  const std::vector<std::string> names = GetDiffusionSolverNames();
  EXPECT_NE(std::find(names.begin(), names.end(), "montecarlo"), names.end());

  const TetMesh mesh = Build(CubeMesh(3, 2.0));
  const double muA[3] = { 0.1, 0.1, 0.1 }, sigmaS[3] = { 1.0, 1.0, 1.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigmaS, 1.3);
  DiffusionProblem problem = MakeProblem(mesh, material);
  problem.Lights = { Directional(0.0, 0.0, -1.0, 1.0, 1.0, 1.0) };
  solver->SetOptions(SolverOptions{ { DiffusionOption::Photons, 5000 } });
  std::vector<double> progress;
  solver->SetProgressCallback([&progress](double f) {
    progress.push_back(f);
    return true;
  });
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  ASSERT_GE(progress.size(), 3u);
  EXPECT_TRUE(std::is_sorted(progress.begin(), progress.end()));
  EXPECT_EQ(progress.back(), 1.0);
  EXPECT_EQ(fluence.size(), 3u * mesh.GetNumberOfPoints());
  EXPECT_EQ(report.Solver, "montecarlo");
  EXPECT_GT(report.MemoryBytes, 0u);

  // Abort half-way: Solve returns false and leaves the output alone.
  int calls = 0;
  solver->SetProgressCallback([&calls](double f) { return ++calls < 3 || f < 0.0; });
  std::vector<double> untouched = { 42.0 };
  EXPECT_FALSE(solver->Solve(problem, untouched, report));
  EXPECT_EQ(untouched, std::vector<double>{ 42.0 });
}

// Fewer photons than batches: one photon per batch; a single photon has no
// standard error (NaN), two or more do.
TEST(MonteCarlo, FewerPhotonsThanBatches)
{
  const TetMesh mesh = Build(CubeMesh(3, 2.0));
  const double muA[3] = { 0.1, 0.1, 0.1 }, sigmaS[3] = { 1.0, 1.0, 1.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigmaS, 1.3);
  DiffusionProblem problem = MakeProblem(mesh, material);
  problem.Lights = { Directional(0.0, 0.0, -1.0, 1.0, 0.0, 0.0) };
  MonteCarloSolver solver;
  solver.SetNumberOfPhotons(5);
  Result run = Solve(solver, problem);
  EXPECT_EQ(solver.GetPowerBalance(0).Photons, 5);
  double total = 0.0;
  for (std::size_t k = 0; k < run.Fluence.size(); k += 3)
  {
    EXPECT_TRUE(std::isfinite(run.Report.FluenceStandardError[k]));
    total += run.Fluence[k];
  }
  EXPECT_GT(total, 0.0);
  solver.SetNumberOfPhotons(1);
  run = Solve(solver, problem);
  EXPECT_EQ(solver.GetPowerBalance(0).Photons, 1);
  EXPECT_TRUE(std::isnan(run.Report.FluenceStandardError[0]));
}

TEST(MonteCarlo, InvalidInputThrows)
{
  const TetMesh mesh = Build(CubeMesh(2, 1.0));
  const double muA[3] = { 0.1, 0.1, 0.1 }, sigmaS[3] = { 1.0, 1.0, 1.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigmaS, 1.3);
  DiffusionProblem problem = MakeProblem(mesh, material);
  problem.Lights = { Directional(0.0, 0.0, -1.0, 1.0, 1.0, 1.0) };
  std::vector<double> fluence;
  SolverReport report;
  auto message = [&](MonteCarloSolver& solver, const DiffusionProblem& p) {
    try
    {
      solver.Solve(p, fluence, report);
    }
    catch (const Error& e)
    {
      return std::string(e.what());
    }
    return std::string("no error");
  };

  for (long long photons : { 0LL, -5LL })
  {
    MonteCarloSolver solver;
    solver.SetNumberOfPhotons(photons);
    EXPECT_NE(message(solver, problem).find("photons " + std::to_string(photons)),
      std::string::npos)
      << message(solver, problem);
  }
  {
    MonteCarloSolver solver;
    DiffusionProblem dark = problem;
    dark.Lights.clear();
    EXPECT_NE(message(solver, dark).find("no light"), std::string::npos);
    dark.UniformIrradiance = -1.0;
    EXPECT_NE(message(solver, dark).find("uniform irradiance -1"), std::string::npos);
  }
  {
    MonteCarloSolver solver;
    const TetMesh empty;
    DiffusionProblem p = problem;
    p.Mesh = &empty;
    EXPECT_NE(message(solver, p).find("no tets"), std::string::npos);
    p.Mesh = nullptr;
    EXPECT_THROW(solver.Solve(p, fluence, report), Error);
  }
  {
    MonteCarloSolver solver;
    solver.SetNumberOfBatches(1);
    EXPECT_NE(message(solver, problem).find("batches 1"), std::string::npos);
  }
  {
    MonteCarloSolver solver;
    solver.SetAnisotropy(1.0);
    EXPECT_NE(message(solver, problem).find("g = 1"), std::string::npos);
  }
  {
    MonteCarloSolver solver;
    DiffusionProblem p = problem;
    p.Lights[0].Power[1] = -1.0;
    EXPECT_NE(message(solver, p).find("power -1"), std::string::npos);
    p = problem;
    p.Lights[0].Type = LightSource::Kind::Uniform;
    EXPECT_NE(message(solver, p).find("uniform"), std::string::npos);
  }
  {
    MonteCarloSolver solver;
    OpticalProperties bad = material;
    bad.AbsorptionCoefficient[4] = -0.5;
    DiffusionProblem p = problem;
    p.Material = &bad;
    EXPECT_THROW(solver.Solve(p, fluence, report), Error);
  }
}

} // namespace
