// Issue 19: the extended collimated-source model in the frequency and the
// time domain (Documentation/DiffuseOptics.md, "Collimated beams in the
// frequency and time domain"). Three independent checks:
// (1) omega -> 0: the frequency-domain solve is the continuous-wave one (to
//     the solver tolerance), and the beam's own phase is -omega eta s / c
//     exactly at every vertex of a face-on box;
// (2) the time integral of the gates is the continuous-wave solve (the
//     identity TimeResolved.TimeIntegralIsContinuousWave checks for the
//     boundary and interior sources, here with two beams, both models);
// (3) the frequency-domain readings are the Fourier transform of the
//     time-domain ones at the same frequency, within the time
//     discretisation error (a second method for the beam's delay).
#include "DiffusionSolverFactory.h"
#include "Detectors.h"
#include "Error.h"
#include "Fresnel.h"
#include "LightSources.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TetMesh.h"
#include "VertexDiffusionSolver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <iostream>
#include <memory>
#include <vector>

namespace translucency
{
namespace
{

using translucency::testing::MakeProblem;

constexpr double Pi = 3.14159265358979323846;

LightSource Directional(double dx, double dy, double dz, double r, double g, double b)
{
  LightSource light;
  light.Type = LightSource::Kind::Directional;
  light.Direction = { dx, dy, dz };
  light.Power = { r, g, b };
  return light;
}

/// The 10 mm cube [0, 10]^3 of TimeResolved.TimeIntegralIsContinuousWave
/// (8 cells per side, jittered inside).
TetMesh Cube(int cells)
{
  const translucency::testing::MeshData data =
    translucency::testing::CubeMesh(cells, 10.0, 0.2, 5);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  return mesh;
}

VertexDiffusionSolver& Vertex(std::unique_ptr<DiffusionSolver>& solver)
{
  return dynamic_cast<VertexDiffusionSolver&>(*solver);
}

} // namespace

// (1) A face-on beam on the box: at f = 1 Hz (omega eta s / c < 1e-10 rad)
// the frequency-domain fluence equals the continuous-wave one to 1e-8 of its
// largest value (rel-tol 1e-12; COCG against CG), both discretisations and
// both extended models, with a second, oblique beam through a side face (the
// per-beam integration); at 2 GHz the beam's own phase is -omega eta s / c
// at every vertex (face-on: s = depth), its amplitude the CW E_c, and the
// load at k = 0 is the CW load.
TEST(CollimatedFrequency, ZeroFrequencyIsContinuousWave)
{
  const TetMesh mesh = Cube(6);
  const double muA[3] = { 0.02, 0.1, 0.05 }, muS[3] = { 1.0, 0.5, 2.0 };
  const double eta = 1.4;
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, muS, eta);
  const std::vector<LightSource> lights = { Directional(0, 0, -1, 1.0, 2.0, 0.5),
    Directional(-1, 0.2, -0.3, 0.3, 0.3, 0.3) };
  std::vector<double> q(3 * static_cast<size_t>(mesh.GetNumberOfPoints()), 0.0);
  for (CollimatedModel model : { CollimatedModel::Extended, CollimatedModel::ExtendedMoments })
  for (const char* name : { "divergence", "fem" })
  {
    SCOPED_TRACE(name);
    DiffusionProblem problem = MakeProblem(mesh, material, q);
    problem.Lights = lights;
    problem.Collimated = model;
    std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver(name);
    solver->SetRelTol(1e-12);
    solver->SetMaxIter(20000);
    std::vector<double> cw;
    SolverReport cwReport;
    ASSERT_TRUE(solver->Solve(problem, cw, cwReport));
    std::vector<std::complex<double>> fd;
    SolverReport report;
    ASSERT_TRUE(Vertex(solver).SolveFrequencyDomain(problem, 1.0, fd, report));
    ASSERT_EQ(fd.size(), cw.size());
    ASSERT_EQ(report.CollimatedFluence.size(), cw.size());
    const double largest = *std::max_element(cw.begin(), cw.end());
    double worst = 0.0, imaginary = 0.0;
    for (size_t k = 0; k < cw.size(); ++k)
    {
      worst = std::max(worst, std::abs(fd[k] - cw[k]));
      imaginary = std::max(imaginary, std::abs(fd[k].imag()));
      ASSERT_NEAR(report.CollimatedFluence[k], cwReport.CollimatedFluence[k],
        1e-14 * largest);
    }
    std::cout << name << (model == CollimatedModel::Extended ? " extended" : " moments")
              << ": max |Phi(1 Hz) - phi_CW| / max phi_CW = " << worst / largest
              << ", max |Im| / max = " << imaginary / largest << std::endl;
    EXPECT_LT(worst, 1e-8 * largest);
    for (int c = 0; c < 3; ++c)
    {
      EXPECT_EQ(report.CollimatedScattered[c], cwReport.CollimatedScattered[c]);
      EXPECT_EQ(report.CollimatedEntering[c], cwReport.CollimatedEntering[c]);
    }
  }

  // The beam's own modulation, one face-on beam: arg E_c = -omega eta depth / c.
  const double frequency = 2e9;
  const double k = 2.0 * Pi * frequency / (SpeedOfLightMillimetresPerNanosecond * 1e12);
  const std::vector<LightSource> faceOn = { Directional(0, 0, -1, 1.0, 2.0, 0.5) };
  const CollimatedSource source = ComputeCollimatedSource(mesh, material, faceOn, false);
  std::vector<std::complex<double>> load, fluence, load0, fluence0;
  ComputeCollimatedFrequencyLoad(mesh, material, source, k, load, fluence);
  ComputeCollimatedFrequencyLoad(mesh, material, source, 0.0, load0, fluence0);
  double total = 0.0;
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    const double depth = 10.0 - mesh.GetPoint(i)[2];
    for (int c = 0; c < 3; ++c)
    {
      const size_t j = 3 * static_cast<size_t>(i) + c;
      ASSERT_NEAR(std::abs(fluence[j]), source.Fluence[j], 1e-14 * source.Fluence[j]);
      ASSERT_NEAR(std::arg(fluence[j]), -k * eta * depth, 1e-12) << "point " << i;
      ASSERT_EQ(load0[j].imag(), 0.0);
      ASSERT_NEAR(load0[j].real(), source.Load[j], 1e-14 * std::abs(source.Load[j]) + 1e-300);
      total += std::abs(load0[j]);
    }
  }
  EXPECT_GT(total, 0.0);
  EXPECT_THROW(ComputeCollimatedFrequencyLoad(mesh, material, source, -1.0, load, fluence), Error);
}

// (2) The power identity of the time domain with the beams: two directional
// lights (one oblique through the top face, one through a side face) as
// delayed pulses, a boundary irradiance on the top face as the q pulse,
// 60 gates over 0-6 ns (the response has died out: the tail is < e^-25, as
// in TimeResolved.TimeIntegralIsContinuousWave): the integrated fluence
// equals the continuous-wave solve (phi_d + E_c) to 1e-8 of its largest
// value, the detectors' integrals their continuous-wave readings to 1e-8,
// fem with extended, divergence with extended-moments; the deposits carry exactly
// the continuous-wave load (1e-12), and the snapshots sum to the integral.
TEST(CollimatedTime, TimeIntegralIsContinuousWave)
{
  const TetMesh mesh = Cube(8);
  const double muA[3] = { 0.05, 0.1, 0.02 }, muS[3] = { 1.0, 1.5, 0.8 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, muS, 1.4);
  std::vector<double> irradiance(3 * static_cast<std::size_t>(mesh.GetNumberOfPoints()), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    for (int c = 0; c < 3; ++c)
    {
      irradiance[3 * i + c] = mesh.GetPoint(i)[2] > 9.999 ? 0.01 * (c + 1) : 0.0;
    }
  }
  const std::vector<LightSource> lights = { Directional(0.3, 0.1, -1.0, 1.0, 0.5, 2.0),
    Directional(-1.0, 0.0, -0.2, 0.2, 0.4, 0.3) };
  std::vector<Detector> detectors(2);
  detectors[0].Position = { 2.0, 3.0, 10.0 }; // on the lit face
  detectors[1].Position = { 0.0, 4.0, 3.0 };  // on the face the second beam enters
  detectors[1].Radius = 1.5;

  // The deposits carry the continuous-wave load, whatever the time grid,
  // once it reaches past every arrival (the farthest, 10.2 mm from the
  // entry face, at 0.048 ns); a grid ending at 0.03 ns leaves the later
  // arrivals out.
  const CollimatedSource source = ComputeCollimatedSource(mesh, material, lights, false);
  for (const double end : { 0.06, 0.03 })
  {
    std::vector<double> times = { 0.0, 0.004, 0.01, 0.02, 0.03 };
    if (end > 0.03)
    {
      times.push_back(end);
    }
    const std::vector<CollimatedDeposit> deposits =
      ComputeCollimatedTimeLoad(mesh, material, source, times);
    std::vector<double> sum(source.Load.size(), 0.0);
    int late = 0;
    for (const CollimatedDeposit& d : deposits)
    {
      late += d.Time == 5 ? 1 : 0;
      for (int c = 0; c < 3; ++c)
      {
        sum[3 * static_cast<size_t>(d.Point) + c] += d.Load[c];
      }
    }
    double total = 0.0, load = 0.0;
    for (size_t j = 0; j < sum.size(); ++j)
    {
      total += sum[j];
      load += source.Load[j];
      if (end > 0.03)
      {
        ASSERT_NEAR(sum[j], source.Load[j], 1e-12 * std::abs(source.Load[j]) + 1e-300);
      }
    }
    if (end > 0.03)
    {
      EXPECT_GT(late, 0); // arrivals after 0.03 ns
    }
    else
    {
      EXPECT_LT(total, (1.0 - 1e-9) * load);
      EXPECT_GT(total, 0.9 * load);
    }
  }

  // fem with extended, divergence with extended-moments (the four pairs take
  // 2x the time for nothing new: the rule and the discretisation are
  // independent of the time stepping).
  for (const auto& [name, model] : { std::make_pair("fem", CollimatedModel::Extended),
         std::make_pair("divergence", CollimatedModel::ExtendedMoments) })
  {
    SCOPED_TRACE(name);
    const Fresnel::BoundaryRule rule = model == CollimatedModel::ExtendedMoments
      ? Fresnel::BoundaryRule::Moments
      : Fresnel::BoundaryRule::Fit;
    DiffusionProblem problem = MakeProblem(mesh, material, irradiance);
    problem.Lights = lights;
    problem.Collimated = model;
    auto solver = CreateDiffusionSolver(name);
    solver->SetRelTol(1e-12);
    solver->SetMaxIter(10000);
    std::vector<double> cw;
    SolverReport cwReport;
    ASSERT_TRUE(solver->Solve(problem, cw, cwReport));
    std::vector<double> diffuse = cw;
    for (size_t k = 0; k < cw.size(); ++k)
    {
      diffuse[k] -= cwReport.CollimatedFluence[k];
    }
    const auto cwReadings = ReadDetectors(mesh, material, detectors, diffuse, &irradiance, rule);
    TimeGates gates;
    gates.End = 6.0;
    gates.Count = 60;
    gates.StepsPerGate = 3;
    std::vector<int> all(60);
    for (int g = 0; g < 60; ++g)
    {
      all[g] = g;
    }
    TimeResolvedResult result;
    SolverReport report;
    ASSERT_TRUE(
      Vertex(solver).SolveTimeResolved(problem, gates, detectors, all, result, report));
    ASSERT_EQ(result.IntegratedFluence.size(), cw.size());
    ASSERT_EQ(report.CollimatedFluence.size(), cw.size());
    double largest = 0.0, difference = 0.0, snapshotDifference = 0.0;
    for (std::size_t i = 0; i < cw.size(); ++i)
    {
      largest = std::max(largest, std::abs(cw[i]));
      difference = std::max(difference, std::abs(result.IntegratedFluence[i] - cw[i]));
      double sum = 0.0;
      for (const std::vector<double>& snapshot : result.Snapshots)
      {
        sum += gates.GetWidth() * snapshot[i];
      }
      snapshotDifference = std::max(snapshotDifference, std::abs(sum - cw[i]));
      // Every beam arrives within the first gate here: E_c is all in.
      ASSERT_NEAR(report.CollimatedFluence[i], cwReport.CollimatedFluence[i], 1e-15 * largest);
    }
    std::cout << name << (model == CollimatedModel::Extended ? " extended" : " moments")
              << ": largest |integral - CW| / max CW " << difference / largest << std::endl;
    EXPECT_LT(difference / largest, 1e-8);
    EXPECT_LT(snapshotDifference / largest, 1e-8);
    for (std::size_t k = 0; k < detectors.size(); ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        double fluence = 0.0, exitance = 0.0;
        for (int g = 0; g < gates.Count; ++g)
        {
          fluence += gates.GetWidth() * result.Readings[g][k].Fluence[c];
          exitance += gates.GetWidth() * result.Readings[g][k].Exitance[c];
        }
        EXPECT_NEAR(fluence / cwReadings[k].Fluence[c], 1.0, 1e-8) << name << " detector " << k;
        EXPECT_NEAR(exitance / cwReadings[k].Exitance[c], 1.0, 1e-8) << name << " detector " << k;
      }
    }
  }
}

// (3) A second method: the frequency-domain detector readings at 1 GHz
// equal the Fourier transform of the time-domain TPSFs, sum over the gates
// of (gate average) x (integral of exp(-i omega t) over the gate), on the
// 10 mm cube lit by a face-on and an oblique beam (no q: the q pulse's
// exitance term would add its own gate-averaging error), fem and
// divergence; 150 gates of 10 ps over 0-1.5 ns (the response has fallen
// by more than e^-30 by then: the cube's slowest mode decays at about
// 35/ns). Tolerance 0.6 % of the amplitude (the complex difference; the
// measured 0.06-0.20 % is a phase lead of 1-2 mrad): the time
// discretisation, 4 steps of 2.5 ps per gate: BDF2 and the gate averaging
// are O((omega dt)^2) ~ 1e-4; the first-order backward-Euler start shifts
// the response by a fraction of a step, omega dt / 2 = 4e-3 at most. The
// beam's own delay moves the phase by about omega <tau> (<tau> the
// E_c-weighted mean arrival time, 0.05 rad here): the test checks that it
// is more than 5x the tolerance, so the same comparison without the delay
// in either domain fails (checked: without it in the frequency domain the
// difference is 1.5-4.5 %).
TEST(CollimatedTime, FourierTransformIsFrequencyDomain)
{
  const TetMesh mesh = Cube(6);
  const double muA[3] = { 0.05, 0.1, 0.02 }, muS[3] = { 0.3, 0.6, 0.4 };
  const double eta = 1.4;
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, muS, eta);
  std::vector<double> q(3 * static_cast<std::size_t>(mesh.GetNumberOfPoints()), 0.0);
  const std::vector<LightSource> lights = { Directional(0, 0, -1, 1.0, 0.5, 2.0),
    Directional(-1.0, 0.3, -0.5, 0.2, 0.4, 0.3) };
  std::vector<Detector> detectors(4);
  detectors[0].Position = { 5.0, 5.0, 0.0 };  // bottom, opposite the face-on beam
  detectors[1].Position = { 10.0, 5.0, 5.0 }; // the face the oblique beam enters
  detectors[2].Position = { 0.0, 5.0, 5.0 };  // the side away from it
  detectors[3].Position = { 5.0, 3.0, 10.0 }; // the lit top face
  const double frequency = 1e9;
  const double omega = 2.0 * Pi * frequency * 1e-9; // rad/ns
  // The load-weighted mean arrival time (ns), the delay's phase omega <tau>.
  const CollimatedSource source = ComputeCollimatedSource(mesh, material, lights, false);
  double meanDelay = 0.0, weight = 0.0;
  for (const CollimatedSource::Beam& beam : source.Beams)
  {
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      const double w = beam.Fluence[3 * static_cast<size_t>(i)];
      meanDelay += w * beam.OpticalPath[i] / SpeedOfLightMillimetresPerNanosecond;
      weight += w;
    }
  }
  meanDelay /= weight;
  const double tolerance = 0.006;
  std::cout << "omega <tau> = " << omega * meanDelay << " rad" << std::endl;
  EXPECT_GT(omega * meanDelay, 5.0 * tolerance);

  for (const char* name : { "fem", "divergence" })
  {
    SCOPED_TRACE(name);
    DiffusionProblem problem = MakeProblem(mesh, material, q);
    problem.Lights = lights;
    problem.Collimated = CollimatedModel::Extended;
    auto solver = CreateDiffusionSolver(name);
    solver->SetRelTol(1e-11);
    solver->SetMaxIter(10000);
    std::vector<std::complex<double>> fd;
    SolverReport report;
    ASSERT_TRUE(Vertex(solver).SolveFrequencyDomain(problem, frequency, fd, report));
    // The detectors read the diffuse field: Phi - E_c exp(i phase).
    std::vector<double> re(fd.size()), im(fd.size());
    for (size_t k = 0; k < fd.size(); ++k)
    {
      const std::complex<double> diffuse =
        fd[k] - std::polar(report.CollimatedFluence[k], report.CollimatedFluencePhase[k]);
      re[k] = diffuse.real();
      im[k] = diffuse.imag();
    }
    const auto fdRe = ReadDetectors(mesh, material, detectors, re, nullptr);
    const auto fdIm = ReadDetectors(mesh, material, detectors, im, nullptr);

    TimeGates gates;
    gates.End = 1.5;
    gates.Count = 150;
    gates.StepsPerGate = 4;
    TimeResolvedResult result;
    ASSERT_TRUE(Vertex(solver).SolveTimeResolved(problem, gates, detectors, {}, result, report));
    const double w = gates.GetWidth();
    for (size_t d = 0; d < detectors.size(); ++d)
    {
      for (int c = 0; c < 3; ++c)
      {
        std::complex<double> transform = 0.0;
        for (int g = 0; g < gates.Count; ++g)
        {
          const double t0 = gates.GetGateStart(g);
          // integral of exp(-i omega t) over [t0, t0 + w]
          const std::complex<double> kernel = (std::polar(1.0, -omega * t0) -
                                                std::polar(1.0, -omega * (t0 + w))) /
            std::complex<double>(0.0, omega);
          transform += result.Readings[g][d].Fluence[c] * kernel;
        }
        const std::complex<double> expected(fdRe[d].Fluence[c], fdIm[d].Fluence[c]);
        const double error = std::abs(transform - expected) / std::abs(expected);
        std::cout << name << " detector " << d << " channel " << c << ": FD " << std::abs(expected)
                  << " arg " << std::arg(expected) << ", FT(TD) " << std::abs(transform)
                  << " arg " << std::arg(transform) << ", |difference| / |FD| " << error
                  << std::endl;
        EXPECT_LT(error, tolerance) << name << " detector " << d << " channel " << c;
      }
    }
  }
}

} // namespace translucency
