// The SP3 solver against the project's Monte Carlo (issue 35's targets; the
// Monte Carlo agrees with an independent mesh Monte Carlo within 1-3 %):
// fluence by depth and transmittance under a collimated beam, the exitance
// at low albedo, an isotropic point source in a large medium, and (by hand:
// DISABLED_, a few minutes each) the pencil-beam slab's R(rho) and its mean
// time of flight (the frequency domain's low-frequency phase). Each prints
// a table (Documentation/Solvers.md, "SP3", has the measured numbers) with
// the FEM diffusion solver's errors beside SP3's.
//
// Run the disabled ones with
//   build/bin/TestDiffusion --gtest_also_run_disabled_tests \
//     --gtest_filter='Sp3Validation.DISABLED_*'

#include "DiffusionSolverFactory.h"
#include "Detectors.h"
#include "Fresnel.h"
#include "GradedMeshes.h"
#include "InteriorSources.h"
#include "LightSources.h"
#include "MonteCarlo.h"
#include "Sp3Solver.h"
#include "TestMeshes.h"
#include "TetMesh.h"
#include "TimeResolved.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace
{

using namespace translucency;
using namespace translucency::testing;

/// Mean and standard error of the mean of runs.
struct Estimate
{
  double Mean = 0.0, Error = 0.0;
};

Estimate MeanOf(const std::vector<double>& runs)
{
  Estimate e;
  for (double r : runs)
  {
    e.Mean += r / runs.size();
  }
  double spread = 0.0;
  for (double r : runs)
  {
    spread += (r - e.Mean) * (r - e.Mean);
  }
  e.Error = std::sqrt(spread / (runs.size() - 1) / runs.size());
  return e;
}

/// Volume-weighted mean of channel-0 tet values over the tets `select`s.
double TetMean(const TetMesh& mesh, const std::vector<double>& tetValues,
  const std::function<bool(const double*)>& select)
{
  double sum = 0.0, volume = 0.0;
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    double c[3] = { 0, 0, 0 };
    for (int a = 0; a < 4; ++a)
    {
      for (int k = 0; k < 3; ++k)
      {
        c[k] += 0.25 * mesh.GetPoint(mesh.GetTet(t)[a])[k];
      }
    }
    if (select(c))
    {
      sum += mesh.GetTetVolume(t) * tetValues[3 * static_cast<std::size_t>(t)];
      volume += mesh.GetTetVolume(t);
    }
  }
  return sum / volume;
}

/// The exact tet means of a P1 field (3 per point): the mean of the corners.
std::vector<double> TetMeansOf(const TetMesh& mesh, const std::vector<double>& pointValues)
{
  std::vector<double> out(3 * static_cast<std::size_t>(mesh.GetNumberOfTets()), 0.0);
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    for (int a = 0; a < 4; ++a)
    {
      for (int c = 0; c < 3; ++c)
      {
        out[3 * static_cast<std::size_t>(t) + c] +=
          0.25 * pointValues[3 * static_cast<std::size_t>(mesh.GetTet(t)[a]) + c];
      }
    }
  }
  return out;
}

/// The P1 integral of channel-0 point values over the boundary triangles
/// whose centroid `select`s, divided by their area.
double FaceMean(const TetMesh& mesh, const std::vector<double>& pointValues,
  const std::function<bool(const double*)>& select, double* areaOut = nullptr)
{
  double sum = 0.0, area = 0.0;
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    const int* tri = &mesh.GetBoundaryTriangles()[3 * static_cast<std::size_t>(f)];
    double c[3] = { 0, 0, 0 }, mean = 0.0;
    for (int a = 0; a < 3; ++a)
    {
      for (int k = 0; k < 3; ++k)
      {
        c[k] += mesh.GetPoint(tri[a])[k] / 3.0;
      }
      mean += pointValues[3 * static_cast<std::size_t>(tri[a])] / 3.0;
    }
    if (select(c))
    {
      sum += mesh.GetBoundaryTriangleAreas()[f] * mean;
      area += mesh.GetBoundaryTriangleAreas()[f];
    }
  }
  if (areaOut)
  {
    *areaOut = area;
  }
  return sum / area;
}

/// The Monte Carlo estimator's view of a P1 boundary field (3 per point):
/// per boundary point, the mean over its hat function, int e beta_i dS /
/// (S_i / 3) (consistent boundary mass). MonteCarloSolver's point exitance
/// is the weight escaping through point i's hat over S_i / 3, and its
/// detectors read that, so a P1 field goes through this map before the same
/// footprints for a like-with-like comparison (on the pencil slab's graded
/// surface the hat mean is 0.8 % above the point value at rho = 2 mm and
/// 2.6-3.4 % from 10 mm: the exitance is convex there).
std::vector<double> HatMeans(const TetMesh& mesh, const std::vector<double>& pointValues)
{
  std::vector<double> integral(pointValues.size(), 0.0), measure(pointValues.size() / 3, 0.0);
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    const int* tri = &mesh.GetBoundaryTriangles()[3 * static_cast<std::size_t>(f)];
    const double area = mesh.GetBoundaryTriangleAreas()[f];
    for (int c = 0; c < 3; ++c)
    {
      double sum = 0.0;
      for (int a = 0; a < 3; ++a)
      {
        sum += pointValues[3 * static_cast<std::size_t>(tri[a]) + c];
      }
      for (int a = 0; a < 3; ++a)
      {
        const std::size_t m = 3 * static_cast<std::size_t>(tri[a]) + c;
        integral[m] += area / 12.0 * (sum + pointValues[m]);
      }
    }
    for (int a = 0; a < 3; ++a)
    {
      measure[static_cast<std::size_t>(tri[a])] += area / 3.0;
    }
  }
  for (std::size_t m = 0; m < integral.size(); ++m)
  {
    integral[m] = measure[m / 3] > 0.0 ? integral[m] / measure[m / 3] : 0.0;
  }
  return integral;
}

/// SP3 (default linear solver) on `problem`: fluence and exitance.
void RunSp3(const DiffusionProblem& problem, std::vector<double>& fluence,
  std::vector<double>& exitance)
{
  Sp3Solver solver;
  solver.SetRelTol(1e-9);
  solver.SetMaxIter(20000);
  SolverReport report;
  ASSERT_TRUE(solver.Solve(problem, fluence, report));
  ASSERT_TRUE(report.Converged[0]) << report.Residual[0];
  exitance = solver.GetExitance();
}

/// FEM diffusion: fluence (total) and the diffuse fluence's exitance per
/// point, (phi_d - 4 q / (1 - Fdr)) / (2 A) + q with the coefficients of the
/// model's boundary rule (Detectors.h).
void RunFem(const DiffusionProblem& problem, std::vector<double>& fluence,
  std::vector<double>& exitance)
{
  std::unique_ptr<DiffusionSolver> fem = CreateDiffusionSolver("fem");
  fem->SetRelTol(1e-9);
  fem->SetMaxIter(20000);
  SolverReport report;
  ASSERT_TRUE(fem->Solve(problem, fluence, report));
  ASSERT_TRUE(report.Converged[0]);
  const Fresnel::BoundaryRule rule = problem.Collimated == CollimatedModel::ExtendedMoments
    ? Fresnel::BoundaryRule::Moments
    : Fresnel::BoundaryRule::Fit;
  const Fresnel::RobinCoefficients k =
    Fresnel::BoundaryCoefficients(problem.Material->RefractiveIndex[0], rule);
  const std::vector<double>& q = *problem.Irradiance;
  exitance.assign(fluence.size(), 0.0);
  for (std::size_t m = 0; m < fluence.size(); ++m)
  {
    const double diffuse =
      fluence[m] - (report.CollimatedFluence.empty() ? 0.0 : report.CollimatedFluence[m]);
    exitance[m] = q[m] + (diffuse - 4.0 * q[m] / (1.0 - k.Fdr)) / (2.0 * k.A);
  }
}

/// The box (20 x 20 x 10 mm, 10 x 10 x 40 cells, eta 1.3, g = 0)
/// under a face-on collimated beam of 1 W/mm^2: the problem with the
/// surface model's q, and a zero irradiance for the extended models.
struct LitBox
{
  TetMesh Mesh;
  OpticalProperties Material;
  std::vector<LightSource> Lights = { DirectionalLight({ 0, 0, -1 }, { 1, 0, 0 }) };
  std::vector<double> Q, Zero;
  DiffusionProblem Problem;
  double Eta = 1.3;

  LitBox(double muA, double muS)
  {
    const auto data = BoxMesh(10, 10, 40, 20.0, 20.0, 10.0);
    Mesh.SetGeometry(data.Points, data.Tets);
    const double a[3] = { muA, muA, muA }, s[3] = { muS, muS, muS };
    Material = OpticalProperties::Uniform(Mesh.GetNumberOfTets(), a, s, Eta);
    Problem.Mesh = &Mesh;
    Problem.Material = &Material;
    Problem.Lights = Lights;
    Problem.Shadows = false;
    EXPECT_TRUE(ComputeProjectedIrradiance(Mesh, Material.RefractiveIndex, Lights, 0.0, 0, false, Q));
    Zero.assign(Q.size(), 0.0);
    Problem.Irradiance = &Q;
  }

  /// The problem of a collimated model: the surface model with q, the
  /// extended ones with the zero irradiance (the beam is their source).
  DiffusionProblem With(CollimatedModel model) const
  {
    DiffusionProblem p = Problem;
    p.Collimated = model;
    if (IsExtendedCollimatedModel(model))
    {
      p.Irradiance = &Zero;
    }
    return p;
  }
};

/// `runs` Monte Carlo solves of `problem` with `photons` each and seeds
/// seed, seed + 1, ...; `tally` reads each finished solver.
void RunMonteCarlo(const DiffusionProblem& problem, int runs, long long photons, int seed,
  const std::function<void(const MonteCarloSolver&)>& tally)
{
  for (int run = 0; run < runs; ++run)
  {
    MonteCarloSolver mc;
    mc.SetNumberOfPhotons(photons);
    mc.SetSeed(seed + run);
    std::vector<double> fluence;
    SolverReport report;
    ASSERT_TRUE(mc.Solve(problem, fluence, report));
    tally(mc);
  }
}

// ---- Collimated beam on the box (20 x 20 x 10 mm, mu_a 0.01, mu_s'
// 1/mm, g = 0, eta 1.3, face-on, 1 W/mm^2): the mean fluence in layers 1 mm
// thick around depths 1-9 mm within 4 mm of the axis (exact tet means of the
// P1 solutions against the Monte Carlo tet tallies: the same estimator), and
// the transmittance (the exitance integrated over the bottom face, per
// W entering). SP3 with the extended collimated model (its first-collision
// source: exact for g = 0); fem with the surface model and with
// extended-moments (diffusion's best). Monte Carlo: 4 runs x 40k photons.
TEST(Sp3Validation, CollimatedBoxFluenceByDepthAndTransmittance)
{
  const LitBox box(0.01, 1.0);
  const TetMesh& mesh = box.Mesh;
  const double entering = 400.0 * (1.0 - Fresnel::Reflectance(1.0, box.Eta)); // W

  const int depths = 9;
  auto layer = [&](int d) {
    return [d](const double* c) {
      return std::abs(10.0 - c[2] - d) <= 0.5 && std::abs(c[0] - 10.0) <= 4.0 &&
        std::abs(c[1] - 10.0) <= 4.0;
    };
  };
  auto bottom = [](const double* c) { return c[2] < 1e-9; };
  std::vector<std::vector<double>> mcLayers(depths);
  std::vector<double> mcTransmittance;
  RunMonteCarlo(box.Problem, 4, 40000, 31, [&](const MonteCarloSolver& mc) {
    for (int d = 0; d < depths; ++d)
    {
      mcLayers[d].push_back(TetMean(mesh, mc.GetTetFluence(), layer(d + 1)));
    }
    double area = 0.0;
    const double mean = FaceMean(mesh, mc.GetExitance(), bottom, &area);
    mcTransmittance.push_back(mean * area / entering);
  });
  struct Model
  {
    const char* Name;
    std::vector<double> Layers;
    double Transmittance;
  };
  std::vector<Model> models;
  const CollimatedModel modelOf[3] = { CollimatedModel::Extended, CollimatedModel::Surface,
    CollimatedModel::ExtendedMoments };
  for (int m = 0; m < 3; ++m)
  {
    const DiffusionProblem p = box.With(modelOf[m]);
    std::vector<double> fluence, exitance;
    if (m == 0)
    {
      RunSp3(p, fluence, exitance);
    }
    else
    {
      RunFem(p, fluence, exitance);
    }
    Model model{ m == 0 ? "sp3" : (m == 1 ? "fem surface" : "fem extended-moments"), {}, 0.0 };
    const std::vector<double> tets = TetMeansOf(mesh, fluence);
    for (int d = 0; d < depths; ++d)
    {
      model.Layers.push_back(TetMean(mesh, tets, layer(d + 1)));
    }
    double area = 0.0;
    model.Transmittance = FaceMean(mesh, exitance, bottom, &area) * area / entering;
    models.push_back(model);
  }
  std::printf("depth | Monte Carlo (SE %%) | sp3 / MC | fem surface / MC | fem extended-moments / MC\n");
  for (int d = 0; d < depths; ++d)
  {
    const Estimate mc = MeanOf(mcLayers[d]);
    std::printf("%d mm | %.4f (%.2f %%) | %.4f | %.4f | %.4f\n", d + 1, mc.Mean,
      100.0 * mc.Error / mc.Mean, models[0].Layers[d] / mc.Mean, models[1].Layers[d] / mc.Mean,
      models[2].Layers[d] / mc.Mean);
    // The target: within 3 % from 1 mm deep to the bottom (plus
    // three standard errors of the reference).
    EXPECT_NEAR(models[0].Layers[d] / mc.Mean, 1.0, 0.03 + 3.0 * mc.Error / mc.Mean)
      << "depth " << d + 1;
  }
  const Estimate t = MeanOf(mcTransmittance);
  std::printf("transmittance | %.5f (%.2f %%) | %.4f | %.4f | %.4f\n", t.Mean,
    100.0 * t.Error / t.Mean, models[0].Transmittance / t.Mean, models[1].Transmittance / t.Mean,
    models[2].Transmittance / t.Mean);
  // The target: within 2 %.
  EXPECT_NEAR(models[0].Transmittance / t.Mean, 1.0, 0.02 + 3.0 * t.Error / t.Mean);
}

// ---- Low albedo (mu_a = mu_s' / 2: 0.5 and 1/mm, g = 0, eta 1.3): the same
// box and beam; the exitance on the top face within 4 mm of the axis per W
// entering there (the diffuse reflectance; the beam's specular reflection is
// in neither). Monte Carlo: 4 runs x 40k photons.
TEST(Sp3Validation, LowAlbedoExitance)
{
  const LitBox box(0.5, 1.0);
  const TetMesh& mesh = box.Mesh;
  const double transmitted = 1.0 - Fresnel::Reflectance(1.0, box.Eta); // W/mm^2 entering
  auto top = [](const double* c) {
    return c[2] > 10.0 - 1e-9 && std::abs(c[0] - 10.0) <= 4.0 && std::abs(c[1] - 10.0) <= 4.0;
  };
  std::vector<double> runs;
  RunMonteCarlo(box.Problem, 4, 40000, 51, [&](const MonteCarloSolver& mc) {
    runs.push_back(FaceMean(mesh, mc.GetExitance(), top) / transmitted);
  });
  const Estimate mc = MeanOf(runs);
  double ratio[3];
  const char* names[3] = { "sp3 (extended)", "fem surface", "fem extended-moments" };
  const CollimatedModel modelOf[3] = { CollimatedModel::Extended, CollimatedModel::Surface,
    CollimatedModel::ExtendedMoments };
  for (int m = 0; m < 3; ++m)
  {
    const DiffusionProblem p = box.With(modelOf[m]);
    std::vector<double> fluence, exitance;
    if (m == 0)
    {
      RunSp3(p, fluence, exitance);
    }
    else
    {
      RunFem(p, fluence, exitance);
    }
    // The exitance of the surface model includes nothing of the beam's
    // specular part either: q is the transmitted irradiance.
    ratio[m] = FaceMean(mesh, exitance, top) / transmitted / mc.Mean;
    std::printf("%s: diffuse reflectance / Monte Carlo %.4f\n", names[m], ratio[m]);
  }
  std::printf("Monte Carlo diffuse reflectance %.5f (SE %.2f %%)\n", mc.Mean,
    100.0 * mc.Error / mc.Mean);
  // The target: within 10 % where diffusion is off by more.
  EXPECT_NEAR(ratio[0], 1.0, 0.10 + 3.0 * mc.Error / mc.Mean);
  EXPECT_LT(std::abs(ratio[0] - 1.0), std::abs(ratio[1] - 1.0));
  EXPECT_LT(std::abs(ratio[0] - 1.0), std::abs(ratio[2] - 1.0));
}

// ---- An isotropic point source (1 W) at the centre of a cube of half side
// 15 mm (mu_a 0.05, mu_s' 1/mm, g = 0, eta 1.4): the fluence averaged over
// spherical shells of tets 1-2, 2-3, 3-4, 4-5 mm from the source (1.05 to
// 5.3 transport lengths), SP3 and fem (exact tet means of the P1 solutions)
// against the Monte Carlo tet tallies (4 runs x 15k photons).
TEST(Sp3Validation, PointSourceInALargeMedium)
{
  const std::unique_ptr<TetMesh> mesh = GradedCube(24, 4.0, 15.0, 0.5);
  const double muA[3] = { 0.05, 0.05, 0.05 }, muS[3] = { 1.0, 1.0, 1.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh->GetNumberOfTets(), muA, muS, 1.4);
  const std::array<double, 3> source = { 0.013, 0.021, -0.017 };
  Sources sources;
  PointSource point;
  point.Position = source;
  point.Power = { 1.0, 0.0, 0.0 };
  sources.AddPointSource(point);
  const std::vector<double> q(3 * static_cast<std::size_t>(mesh->GetNumberOfPoints()), 0.0);
  DiffusionProblem problem;
  problem.Mesh = mesh.get();
  problem.Material = &material;
  problem.Irradiance = &q;
  problem.InteriorSources = &sources;
  const double shells[] = { 1.0, 2.0, 3.0, 4.0, 5.0 };
  auto shell = [&](int s) {
    return [&, s](const double* c) {
      const double r = std::sqrt((c[0] - source[0]) * (c[0] - source[0]) +
        (c[1] - source[1]) * (c[1] - source[1]) + (c[2] - source[2]) * (c[2] - source[2]));
      return r >= shells[s] && r < shells[s + 1];
    };
  };
  std::vector<std::vector<double>> runs(4);
  RunMonteCarlo(problem, 4, 15000, 71, [&](const MonteCarloSolver& mc) {
    for (int s = 0; s < 4; ++s)
    {
      runs[s].push_back(TetMean(*mesh, mc.GetTetFluence(), shell(s)));
    }
  });
  std::vector<double> sp3, fem, exitance;
  RunSp3(problem, sp3, exitance);
  RunFem(problem, fem, exitance);
  const std::vector<double> sp3Tets = TetMeansOf(*mesh, sp3), femTets = TetMeansOf(*mesh, fem);
  std::printf("shell | Monte Carlo (SE %%) | sp3 / MC | fem / MC\n");
  for (int s = 0; s < 4; ++s)
  {
    const Estimate mc = MeanOf(runs[s]);
    const double a = TetMean(*mesh, sp3Tets, shell(s)) / mc.Mean;
    const double b = TetMean(*mesh, femTets, shell(s)) / mc.Mean;
    std::printf("%g-%g mm | %.5f (%.2f %%) | %.4f | %.4f\n", shells[s], shells[s + 1], mc.Mean,
      100.0 * mc.Error / mc.Mean, a, b);
    // The target: within 5 % from one transport length.
    EXPECT_NEAR(a, 1.0, 0.05 + 3.0 * mc.Error / mc.Mean) << "shell " << s;
  }
}

// ---- The pencil-beam slab of the issue (60 x 60 x 30 mm, mu_a 0.01, mu_s'
// 1/mm, g = 0, eta 1.3, normal incidence, 1 W): R(rho) read by fibre
// detectors (radius 0.5 mm at 2 mm, 1 mm at 4 and 6 mm, 2 mm from 10 mm;
// six azimuths averaged) from the Monte Carlo point tallies and from the
// solutions' exitance fields through the same estimator (HatMeans) and the
// same footprints (LocateDetectors); the last column reads the P1 field at
// the points (the comparison before session 23: 2.6-3.4 % lower from 10 mm).
// SP3: the beam's first-collision source (ComputeSp3SourceLoad); fem:
// Farrell's equivalent point source (the diffusion solvers' model).
// A measurement, run by hand (see the top of the file; 400k photons, about
// 2 minutes on an idle 2-core machine): it prints the table of
// Documentation/Solvers.md. The targets (5 % from 2 mm, 2 % from
// 6 mm) are NOT met (+24 % at 2 mm, -6 to -10 % from 10 mm: the SP_N model
// itself, Solvers.md "SP3" has the measurements that rule out the mesh, the
// boundary coefficients, the source (exact single scatter and up to five
// exact scattering orders) and the angular order (SP5, SP7)), so the test
// asserts only what the table needs: the reference's precision.
/// The pencil-beam slab (60 x 60 x 30 mm, graded mesh, mu_a 0.01,
/// mu_s' 1/mm, g = 0, eta 1.3, 1 W face-on at the origin) and its fibre
/// detectors: radii 2, 4, 6, 10, 15, 20 mm (fibres 0.5, 1, 1, 2, 2, 2 mm),
/// six azimuths each (detector r * Azimuths + a).
struct PencilSlab
{
  static constexpr int Rings = 6, Azimuths = 6;
  const double Radii[Rings] = { 2.0, 4.0, 6.0, 10.0, 15.0, 20.0 };
  const double Fibres[Rings] = { 0.5, 1.0, 1.0, 2.0, 2.0, 2.0 };
  std::unique_ptr<TetMesh> Mesh = GradedSlab(40, 20, 30.0, 30.0, 0.2);
  OpticalProperties Material;
  std::vector<double> Q;
  Sources Beam;
  DiffusionProblem Problem;
  std::vector<Detector> Detectors;
  std::vector<DetectorFootprint> Footprints;

  PencilSlab()
  {
    const double muA[3] = { 0.01, 0.01, 0.01 }, muS[3] = { 1.0, 1.0, 1.0 };
    Material = OpticalProperties::Uniform(Mesh->GetNumberOfTets(), muA, muS, 1.3);
    Q.assign(3 * static_cast<std::size_t>(Mesh->GetNumberOfPoints()), 0.0);
    PencilBeam beam;
    beam.Position = { 0.0, 0.0, 0.0 };
    beam.Direction = { 0.0, 0.0, -1.0 };
    beam.Power = { 1.0, 0.0, 0.0 };
    Beam.AddPencilBeam(beam);
    Problem.Mesh = Mesh.get();
    Problem.Material = &Material;
    Problem.Irradiance = &Q;
    Problem.InteriorSources = &Beam;
    const double pi = 3.14159265358979323846;
    for (int r = 0; r < Rings; ++r)
    {
      for (int a = 0; a < Azimuths; ++a)
      {
        const double angle = 0.2 + 2.0 * pi * a / Azimuths;
        Detector detector;
        detector.Position = { Radii[r] * std::cos(angle), Radii[r] * std::sin(angle), 0.0 };
        detector.Radius = Fibres[r];
        Detectors.push_back(detector);
      }
    }
    Footprints = LocateDetectors(*Mesh, Detectors);
  }

  /// Channel 0 of a point field (3 per point) read by detector k.
  double Read(const std::vector<double>& values, std::size_t k) const
  {
    double sum = 0.0;
    for (const auto& [point, weight] : Footprints[k].GetPointWeights(*Mesh))
    {
      sum += weight * values[3 * static_cast<std::size_t>(point)];
    }
    return sum;
  }
};

TEST(Sp3Validation, DISABLED_PencilSlabReflectance)
{
  const PencilSlab slab;
  const TetMesh* mesh = slab.Mesh.get();
  const DiffusionProblem& problem = slab.Problem;
  const double* radii = slab.Radii;
  const int azimuths = PencilSlab::Azimuths;
  const std::vector<Detector>& detectors = slab.Detectors;
  MonteCarloSolver mc;
  mc.SetNumberOfPhotons(400000);
  mc.SetSeed(5);
  mc.SetDetectors(detectors);
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(mc.Solve(problem, fluence, report));
  std::vector<double> sp3, sp3Exitance, fem, femExitance;
  RunSp3(problem, sp3, sp3Exitance);
  RunFem(problem, fem, femExitance);
  auto read = [&](const std::vector<double>& values, std::size_t k) { return slab.Read(values, k); };
  const std::vector<double> sp3Hat = HatMeans(*mesh, sp3Exitance);
  const std::vector<double> femHat = HatMeans(*mesh, femExitance);
  std::printf("rho | Monte Carlo (SE %%) | sp3 / MC | fem / MC | sp3 point read / MC\n");
  for (int r = 0; r < 6; ++r)
  {
    double value = 0.0, variance = 0.0, a = 0.0, b = 0.0, point = 0.0;
    for (int z = 0; z < azimuths; ++z)
    {
      const std::size_t k = static_cast<std::size_t>(r) * azimuths + z;
      value += mc.GetDetectorReadings()[k].Exitance[0] / azimuths;
      const double e = mc.GetDetectorStandardErrors()[k].Exitance[0];
      variance += e * e / (azimuths * azimuths);
      a += read(sp3Hat, k) / azimuths;
      b += read(femHat, k) / azimuths;
      point += read(sp3Exitance, k) / azimuths;
    }
    const double se = std::sqrt(variance);
    std::printf("%g mm | %.4e (%.2f %%) | %.4f | %.4f | %.4f\n", radii[r], value,
      100.0 * se / value, a / value, b / value, point / value);
    EXPECT_LT(se / value, 0.05) << radii[r];
    EXPECT_TRUE(std::isfinite(a) && a > 0.0 && std::isfinite(b) && b > 0.0) << radii[r];
  }
}

// ---- The frequency domain against transport. The project's Monte Carlo
// has time gates but no frequency domain; at low frequency the phase of a
// reading is -omega <t> (to O((omega t)^2)), <t> the mean time of flight of
// the detected light, which the Monte Carlo's gated exitance gives. The
// pencil slab (above) at 20 MHz: SP3 and fem (Farrell's source) <t> =
// -arg(J) / omega, both through the Monte Carlo's estimator (HatMeans),
// against the Monte Carlo's sum t_g J_g / sum J_g over 0.01 ns gates to
// 4 ns (4 x 100k photons). A measurement, run by hand like the reflectance
// (Solvers.md "SP3" has the table); it asserts the reference's precision.
TEST(Sp3Validation, DISABLED_PencilSlabMeanTimeOfFlight)
{
  const PencilSlab slab;
  const int rings = PencilSlab::Rings, azimuths = PencilSlab::Azimuths;
  TimeGates gates;
  gates.Start = 0.0;
  gates.End = 4.0;
  gates.Count = 400;
  std::vector<std::vector<double>> mcTimes(rings);
  for (int run = 0; run < 4; ++run)
  {
    MonteCarloSolver mc;
    mc.SetNumberOfPhotons(100000);
    mc.SetSeed(91 + run);
    TimeResolvedResult result;
    SolverReport report;
    ASSERT_TRUE(mc.SolveTimeResolved(slab.Problem, gates, slab.Detectors, {}, result, report));
    const std::vector<std::vector<DetectorReading>>& readings = mc.GetGateReadings();
    ASSERT_EQ(readings.size(), static_cast<std::size_t>(gates.Count));
    for (int r = 0; r < rings; ++r)
    {
      double weighted = 0.0, total = 0.0;
      for (int g = 0; g < gates.Count; ++g)
      {
        const double t = gates.Start + (g + 0.5) * gates.GetWidth();
        for (int a = 0; a < azimuths; ++a)
        {
          const double j = readings[g][static_cast<std::size_t>(r * azimuths + a)].Exitance[0];
          weighted += t * j;
          total += j;
        }
      }
      mcTimes[r].push_back(weighted / total);
    }
  }
  const double frequency = 20e6, omega = 2.0 * 3.14159265358979323846 * frequency; // rad/s
  // SP3: its complex exitance; fem: J = Phi / (2 A) (q = 0), the phase of Phi.
  Sp3Solver sp3;
  sp3.SetRelTol(1e-10);
  sp3.SetMaxIter(20000);
  std::vector<std::complex<double>> phi;
  SolverReport report;
  ASSERT_TRUE(sp3.SolveFrequencyDomain(slab.Problem, frequency, phi, report));
  ASSERT_TRUE(report.Converged[0]);
  std::vector<double> sp3Re, sp3Im;
  for (const std::complex<double>& j : sp3.GetComplexExitance())
  {
    sp3Re.push_back(j.real());
    sp3Im.push_back(j.imag());
  }
  std::unique_ptr<DiffusionSolver> fem = CreateDiffusionSolver("fem");
  fem->SetRelTol(1e-10);
  fem->SetMaxIter(20000);
  ASSERT_TRUE(fem->SolveFrequencyDomain(slab.Problem, frequency, phi, report));
  std::vector<double> femRe, femIm;
  for (const std::complex<double>& value : phi)
  {
    femRe.push_back(value.real());
    femIm.push_back(value.imag());
  }
  const std::vector<double> fields[4] = { HatMeans(*slab.Mesh, sp3Re), HatMeans(*slab.Mesh, sp3Im),
    HatMeans(*slab.Mesh, femRe), HatMeans(*slab.Mesh, femIm) };
  std::printf("rho | Monte Carlo <t> ns (SE) | sp3 / MC | fem / MC\n");
  for (int r = 0; r < rings; ++r)
  {
    std::complex<double> a, b;
    for (int z = 0; z < azimuths; ++z)
    {
      const std::size_t k = static_cast<std::size_t>(r * azimuths + z);
      a += std::complex<double>(slab.Read(fields[0], k), slab.Read(fields[1], k));
      b += std::complex<double>(slab.Read(fields[2], k), slab.Read(fields[3], k));
    }
    const double tSp3 = -std::arg(a) / omega * 1e9, tFem = -std::arg(b) / omega * 1e9; // ns
    const Estimate mc = MeanOf(mcTimes[r]);
    std::printf("%g mm | %.4f (%.2f %%) | %.4f | %.4f\n", slab.Radii[r], mc.Mean,
      100.0 * mc.Error / mc.Mean, tSp3 / mc.Mean, tFem / mc.Mean);
    EXPECT_LT(mc.Error / mc.Mean, 0.05) << slab.Radii[r];
    EXPECT_TRUE(tSp3 > 0.0 && tFem > 0.0) << slab.Radii[r];
  }
}

} // namespace
