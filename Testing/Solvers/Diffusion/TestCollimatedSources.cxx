// Issue 19, collimated broad beams (Documentation/DiffuseOptics.md):
// (A) the boundary irradiance integrated per boundary triangle: a flat lit
//     face injects exactly E cos F_t S, a face parallel to the beam nothing;
// (B) the extended-source model: the unscattered beam E_c, its volume source
//     mu_s' E_c, the power balance, and the gain in accuracy against Monte
//     Carlo on the 20 x 20 x 10 mm box of the issue.
#include "CollimatedModels.h"
#include "Detectors.h"
#include "DiffusionSolverFactory.h"
#include "Error.h"
#include "Fresnel.h"
#include "LightSources.h"
#include "MonteCarlo.h"
#include "Radiance.h"
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

using translucency::testing::BoxMesh;
using translucency::testing::MakeProblem;

const double BoxEta = 1.3;

/// The box [0, 20] x [0, 20] x [0, 10] mm (jittered inside: the faces stay
/// flat), lit face z = 10.
TetMesh Box(int nx, int nz, double jitter)
{
  const auto data = BoxMesh(nx, nx, nz, 20.0, 20.0, 10.0, jitter, 7);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  return mesh;
}

LightSource Directional(double dx, double dy, double dz, double r, double g, double b)
{
  LightSource light;
  light.Type = LightSource::Kind::Directional;
  light.Direction = { dx, dy, dz };
  light.Power = { r, g, b };
  return light;
}

/// Unit outward normal of boundary triangle f (the box's faces are axis
/// aligned: the normal is exact to round-off).
void TriangleNormal(const TetMesh& mesh, int f, double n[3])
{
  const int* tri = &mesh.GetBoundaryTriangles()[3 * static_cast<size_t>(f)];
  const double* a = mesh.GetPoint(tri[0]);
  const double* b = mesh.GetPoint(tri[1]);
  const double* c = mesh.GetPoint(tri[2]);
  const double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
  const double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int k = 0; k < 3; ++k)
  {
    n[k] /= l;
  }
}

} // namespace

// ---- (A) Per-triangle boundary irradiance.

// Face-on and oblique beams, with and without shadows: each face of the box
// receives exactly E max(0, n . w) F_t S (w towards the light), so the flat
// lit face injects E F_t S to round-off and the faces parallel to a
// face-on beam exactly 0; the projected point irradiance carries the same
// total (the divergence load S_i q_i / 3) and is exactly 0 on the side
// faces below their top edge. The point evaluation with vertex normals
// (ComputeBoundaryIrradiance) over-injects on the same mesh (the issue's
// 11.9 W of 399.7 W on a finer mesh).
TEST(TriangleIrradiance, EachFaceInjectsIncidentPowerTimesTransmittance)
{
  const TetMesh mesh = Box(8, 4, 0.3);
  const double muA[3] = { 0.01, 0.01, 0.01 }, muS[3] = { 1.0, 1.0, 1.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, muS, BoxEta);
  const double travel[2][3] = { { 0.0, 0.0, -1.0 }, { -1.0, -2.0, -3.0 } };
  const std::array<double, 3> power = { 1.0, 2.0, 0.5 };
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  for (const auto& d : travel)
  {
    for (bool shadows : { false, true })
    {
      SCOPED_TRACE(std::string(d[0] == 0.0 ? "face-on" : "oblique") +
        (shadows ? ", shadows" : ", no shadows"));
      const LightSource light = Directional(d[0], d[1], d[2], power[0], power[1], power[2]);
      std::vector<double> corner;
      ASSERT_TRUE(ComputeTriangleCornerIrradiance(
        mesh, material.RefractiveIndex, { light }, 0.0, 0, shadows, corner));
      const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      // Per face (axis, side): injected and expected power.
      double injected[6][3] = {}, expected[6][3] = {}, total[3] = {};
      for (int f = 0; f < numTriangles; ++f)
      {
        double n[3];
        TriangleNormal(mesh, f, n);
        const int axis = std::abs(n[0]) > 0.5 ? 0 : (std::abs(n[1]) > 0.5 ? 1 : 2);
        const int face = 2 * axis + (n[axis] > 0 ? 1 : 0);
        const double cosIn = -(n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / len;
        const double area = mesh.GetBoundaryTriangleAreas()[f];
        for (int c = 0; c < 3; ++c)
        {
          const double* q = &corner[9 * static_cast<size_t>(f) + c];
          injected[face][c] += area * (q[0] + q[3] + q[6]) / 3.0;
          total[c] += area * (q[0] + q[3] + q[6]) / 3.0;
          if (cosIn > 0.0)
          {
            expected[face][c] += power[c] * area * cosIn * Fresnel::Transmittance(cosIn, BoxEta);
          }
        }
      }
      for (int face = 0; face < 6; ++face)
      {
        for (int c = 0; c < 3; ++c)
        {
          if (expected[face][c] == 0.0)
          {
            EXPECT_EQ(injected[face][c], 0.0) << "face " << face << ", channel " << c;
          }
          else
          {
            EXPECT_NEAR(injected[face][c] / expected[face][c], 1.0, 1e-12)
              << "face " << face << ", channel " << c;
          }
        }
      }
      if (d[0] == 0.0)
      {
        // Face-on: only the top face, 400 mm^2 x E F_t(normal incidence).
        for (int c = 0; c < 3; ++c)
        {
          EXPECT_NEAR(
            injected[5][c] / (400.0 * power[c] * Fresnel::Transmittance(1.0, BoxEta)), 1.0, 1e-12);
        }
      }
      // The projected point irradiance: the same total, 0 below the rim.
      std::vector<double> q;
      ProjectCornerIrradiance(mesh, corner, q);
      double pointTotal[3] = {};
      for (int i : mesh.GetBoundaryPoints())
      {
        for (int c = 0; c < 3; ++c)
        {
          pointTotal[c] += mesh.GetBoundaryAreas()[i] / 3.0 * q[3 * static_cast<size_t>(i) + c];
        }
        if (d[0] == 0.0 && mesh.GetPoint(i)[2] < 10.0 - 1e-9)
        {
          EXPECT_EQ(q[3 * static_cast<size_t>(i)], 0.0) << "point " << i;
        }
      }
      for (int c = 0; c < 3; ++c)
      {
        EXPECT_NEAR(pointTotal[c] / total[c], 1.0, 1e-12);
        // What the solvers inject: ComputePowerBalance's BoundaryInjected.
        const std::vector<double> zero(q.size(), 0.0);
        const PowerBalance balance = ComputePowerBalance(mesh, material, zero, &q);
        EXPECT_NEAR(balance.BoundaryInjected[c] / total[c], 1.0, 1e-12);
      }
      if (d[0] == 0.0 && !shadows)
      {
        // The vertex-normal evaluation lights the side faces' top edge.
        std::vector<double> legacy;
        ASSERT_TRUE(ComputeBoundaryIrradiance(mesh,
          PointRefractiveIndex(mesh, material.RefractiveIndex), { light }, 0.0, 0, false,
          legacy));
        const std::vector<double> zero(legacy.size(), 0.0);
        const PowerBalance old = ComputePowerBalance(mesh, material, zero, &legacy);
        EXPECT_GT(old.BoundaryInjected[0] / total[0], 1.01);
      }
    }
  }
  std::vector<double> corner;
  EXPECT_THROW(ComputeTriangleCornerIrradiance(mesh, { 1.3 }, {}, 1.0, 0, false, corner), Error);
  EXPECT_THROW(ProjectCornerIrradiance(mesh, std::vector<double>(5, 0.0), corner), Error);
}

// ---- (B) The extended source.

// Face-on beam into the homogeneous box: E_c = E F_t exp(-mu_t' depth) at
// every point (exact: the refracted path is the depth), the transmitted
// power is E F_t S, and the 32-point rule's scattered + absorbed power plus
// the unscattered beam leaving the bottom equals it (to the error of the
// composite rule, 1e-3; the test prints it).
TEST(CollimatedSource, UnscatteredBeamAndItsPower)
{
  const TetMesh mesh = Box(8, 4, 0.3);
  const double muA[3] = { 0.01, 0.1, 0.3 }, muS[3] = { 1.0, 0.5, 2.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, muS, BoxEta);
  const std::array<double, 3> power = { 1.0, 2.0, 0.5 };
  LightSource point;
  point.Type = LightSource::Kind::Point;
  point.Position = { 10.0, 10.0, 30.0 };
  const std::vector<LightSource> lights = { Directional(0, 0, -1, power[0], power[1], power[2]),
    point };
  for (bool shadows : { false, true })
  {
    const CollimatedSource source = ComputeCollimatedSource(mesh, material, lights, shadows);
    const double ft = Fresnel::Transmittance(1.0, BoxEta);
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      const double depth = 10.0 - mesh.GetPoint(i)[2];
      for (int c = 0; c < 3; ++c)
      {
        const double expected = power[c] * ft * std::exp(-(muA[c] + muS[c]) * depth);
        ASSERT_NEAR(source.Fluence[3 * static_cast<size_t>(i) + c], expected, 1e-12 * expected)
          << "point " << i << ", channel " << c;
      }
    }
    for (int c = 0; c < 3; ++c)
    {
      const double entering = 400.0 * power[c] * ft;
      EXPECT_NEAR(source.Entering[c] / entering, 1.0, 1e-12);
      const double leaving = entering * std::exp(-(muA[c] + muS[c]) * 10.0);
      const double ratio = (source.Scattered[c] + source.Absorbed[c] + leaving) / entering;
      std::cout << "collimated power, channel " << c << ": (scattered + absorbed + leaving) / "
                << "entering - 1 = " << ratio - 1.0 << "\n";
      EXPECT_NEAR(ratio, 1.0, 1e-3) << "channel " << c;
      EXPECT_NEAR(source.Absorbed[c] / source.Scattered[c], muA[c] / muS[c], 1e-12);
    }
  }
  EXPECT_EQ(NonCollimatedLights(lights).size(), 1u);
}

// Power balance with the extended model, both discretisations: absorbed
// (of phi_d) + escaped = boundary injected (the point light, still a
// boundary irradiance) + the beam's scattered power, to the solver
// tolerance; the returned fluence is phi_d + E_c.
TEST(CollimatedSource, PowerBalanceHolds)
{
  const TetMesh mesh = Box(8, 4, 0.3);
  const double muA[3] = { 0.01, 0.1, 0.3 }, muS[3] = { 1.0, 0.5, 2.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, muS, BoxEta);
  LightSource point;
  point.Type = LightSource::Kind::Point;
  point.Position = { 10.0, 10.0, 30.0 };
  point.Power = { 100.0, 100.0, 100.0 };
  const std::vector<LightSource> lights = { Directional(-0.3, 0.2, -1, 1.0, 2.0, 0.5), point };
  std::vector<double> q;
  ASSERT_TRUE(ComputeProjectedIrradiance(
    mesh, material.RefractiveIndex, NonCollimatedLights(lights), 0.0, 0, true, q));
  for (const char* name : { "divergence", "fem" })
  for (CollimatedModel model : { CollimatedModel::Extended, CollimatedModel::ExtendedMoments })
  {
    SCOPED_TRACE(model == CollimatedModel::Extended ? "extended" : "extended-moments");
    std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver(name);
    solver->SetRelTol(1e-12);
    solver->SetMaxIter(20000);
    DiffusionProblem problem = MakeProblem(mesh, material, q);
    problem.Lights = lights;
    problem.Collimated = model;
    std::vector<double> fluence;
    SolverReport report;
    ASSERT_TRUE(solver->Solve(problem, fluence, report));
    ASSERT_EQ(report.CollimatedFluence.size(), fluence.size());
    std::vector<double> diffuse(fluence);
    for (size_t k = 0; k < diffuse.size(); ++k)
    {
      diffuse[k] -= report.CollimatedFluence[k];
    }
    // The read-out with the Robin coefficients the solve used.
    const PowerBalance balance = ComputePowerBalance(mesh, material, diffuse, &q,
      model == CollimatedModel::ExtendedMoments ? Fresnel::BoundaryRule::Moments
                                                : Fresnel::BoundaryRule::Fit);
    for (int c = 0; c < 3; ++c)
    {
      ASSERT_TRUE(report.Converged[c]);
      const double in = balance.BoundaryInjected[c] + report.CollimatedScattered[c];
      EXPECT_GT(report.CollimatedScattered[c], 0.3 * in);
      EXPECT_GT(balance.BoundaryInjected[c], 0.05 * in);
      EXPECT_NEAR((balance.Absorbed[c] + balance.Escaped[c]) / in, 1.0, 1e-9)
        << name << ", channel " << c;
      EXPECT_GT(report.CollimatedEntering[c], 0.0);
      // Informative: the local-slab approximation at 20 degrees incidence
      // (DiffuseOptics.md quotes these numbers).
      std::cout << name << ", channel " << c << ": beam (scattered + absorbed) / entering - 1 = "
                << (report.CollimatedScattered[c] + report.CollimatedAbsorbed[c]) /
            report.CollimatedEntering[c] - 1.0
                << "\n";
    }
  }
  // The solvers without the model say so; the frequency domain too.
  for (const char* name : { "quadgraph", "grid" })
  for (CollimatedModel model : { CollimatedModel::Extended, CollimatedModel::ExtendedMoments })
  {
    std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver(name);
    DiffusionProblem problem = MakeProblem(mesh, material, q);
    problem.Lights = lights;
    problem.Collimated = model;
    std::vector<double> fluence;
    SolverReport report;
    EXPECT_THROW(solver->Solve(problem, fluence, report), Error) << name;
  }
}

// The Robin coefficients follow the problem's model on a reused solver:
// extended -> extended-moments -> extended -> the frequency domain (fit)
// give what fresh solvers give (a stale rule would keep A = 2.34 or 2.60),
// and the two rules give different fluences (by more than 1 % at the lit
// face: A is 10 % lower with the moments). The moment rule's power
// balance with the fit's read-out does not close, with its own it does
// (PowerBalanceHolds).
TEST(CollimatedSource, BoundaryRuleFollowsTheModel)
{
  const TetMesh mesh = Box(6, 3, 0.3);
  const double muA[3] = { 0.01, 0.1, 0.3 }, muS[3] = { 1.0, 0.5, 2.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, muS, BoxEta);
  LightSource point;
  point.Type = LightSource::Kind::Point;
  point.Position = { 10.0, 10.0, 30.0 };
  point.Power = { 100.0, 100.0, 100.0 };
  const std::vector<LightSource> lights = { Directional(0, 0, -1, 1.0, 2.0, 0.5), point };
  std::vector<double> q;
  ASSERT_TRUE(ComputeProjectedIrradiance(
    mesh, material.RefractiveIndex, NonCollimatedLights(lights), 0.0, 0, true, q));
  for (const char* name : { "divergence", "fem" })
  {
    SCOPED_TRACE(name);
    DiffusionProblem problem = MakeProblem(mesh, material, q);
    problem.Lights = lights;
    const auto solve = [&](DiffusionSolver& solver, CollimatedModel model) {
      solver.SetRelTol(1e-12);
      solver.SetMaxIter(20000);
      DiffusionProblem p = problem;
      p.Collimated = model;
      std::vector<double> fluence;
      SolverReport report;
      EXPECT_TRUE(solver.Solve(p, fluence, report));
      return fluence;
    };
    std::unique_ptr<DiffusionSolver> reused = CreateDiffusionSolver(name);
    std::vector<std::vector<double>> fresh;
    const CollimatedModel sequence[3] = { CollimatedModel::Extended,
      CollimatedModel::ExtendedMoments, CollimatedModel::Extended };
    for (CollimatedModel model : sequence)
    {
      std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver(name);
      fresh.push_back(solve(*solver, model));
    }
    for (int k = 0; k < 3; ++k)
    {
      const std::vector<double> fluence = solve(*reused, sequence[k]);
      ASSERT_EQ(fluence.size(), fresh[k].size());
      // The warm start changes the last digits: 1e-8 of the largest value
      // (a stale rule moves the lit face by about 10 %).
      const double largest = *std::max_element(fresh[k].begin(), fresh[k].end());
      for (size_t i = 0; i < fluence.size(); ++i)
      {
        ASSERT_NEAR(fluence[i], fresh[k][i], 1e-8 * largest) << "step " << k;
      }
    }
    // The rules differ: the top (lit) face reads lower with the smaller A.
    double top[2] = { 0.0, 0.0 };
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      if (mesh.GetPoint(i)[2] > 10.0 - 1e-9)
      {
        top[0] += fresh[0][3 * static_cast<size_t>(i)];
        top[1] += fresh[1][3 * static_cast<size_t>(i)];
      }
    }
    EXPECT_LT(top[1], 0.99 * top[0]);
    // The frequency domain (surface model only) after extended-moments:
    // the fit's coefficients again, as a fresh solver.
    auto* vertex = dynamic_cast<VertexDiffusionSolver*>(reused.get());
    ASSERT_NE(vertex, nullptr);
    std::vector<double> surfaceQ;
    ASSERT_TRUE(
      ComputeProjectedIrradiance(mesh, material.RefractiveIndex, lights, 0.0, 0, true, surfaceQ));
    DiffusionProblem surface = problem;
    surface.Irradiance = &surfaceQ;
    std::vector<std::complex<double>> afterMoments, clean;
    SolverReport report;
    solve(*reused, CollimatedModel::ExtendedMoments);
    vertex->SetRelTol(1e-12);
    ASSERT_TRUE(vertex->SolveFrequencyDomain(surface, 1e8, afterMoments, report));
    std::unique_ptr<DiffusionSolver> other = CreateDiffusionSolver(name);
    auto* fresh2 = dynamic_cast<VertexDiffusionSolver*>(other.get());
    fresh2->SetRelTol(1e-12);
    fresh2->SetMaxIter(20000);
    ASSERT_TRUE(fresh2->SolveFrequencyDomain(surface, 1e8, clean, report));
    ASSERT_EQ(afterMoments.size(), clean.size());
    for (size_t i = 0; i < clean.size(); ++i)
    {
      ASSERT_NEAR(std::abs(afterMoments[i] - clean[i]), 0.0, 1e-9 * std::abs(clean[i]));
    }
  }
}

// A relight and a paint under the extended models (issues 32 and 33): the
// matrices and the linear solver's set-up are kept, only the right-hand side
// (boundary q and the beam's volume load) is rebuilt, and the system equals
// a full assembly's bit for bit (the independent reference: a new solver
// that assembles everything), so the fluence equals the fresh solve within
// the solve's tolerance.
TEST(CollimatedSource, RelightAndPaintUnderTheExtendedModelsKeepTheMatrices)
{
  const TetMesh mesh = Box(6, 3, 0.3);
  const double muA[3] = { 0.01, 0.1, 0.3 }, muS[3] = { 1.0, 0.5, 2.0 };
  OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, muS, BoxEta);
  LightSource point;
  point.Type = LightSource::Kind::Point;
  point.Position = { 10.0, 10.0, 30.0 };
  point.Power = { 100.0, 100.0, 100.0 };
  const std::vector<LightSource> first = { Directional(0, 0, -1, 1.0, 2.0, 0.5), point };
  const std::vector<LightSource> second = { Directional(0.3, -0.2, -1, 0.7, 1.0, 1.5), point };
  std::vector<double> q;
  ASSERT_TRUE(ComputeProjectedIrradiance(
    mesh, material.RefractiveIndex, NonCollimatedLights(first), 0.0, 0, true, q));
  std::vector<double> secondQ;
  LightSource dimmer = point;
  dimmer.Power = { 40.0, 50.0, 60.0 };
  ASSERT_TRUE(ComputeProjectedIrradiance(
    mesh, material.RefractiveIndex, { dimmer }, 0.0, 0, true, secondQ));
  for (CollimatedModel model : { CollimatedModel::Extended, CollimatedModel::ExtendedMoments })
  {
    SCOPED_TRACE(static_cast<int>(model));
    auto solver = CreateDiffusionSolver("divergence");
    auto* vertex = dynamic_cast<VertexDiffusionSolver*>(solver.get());
    ASSERT_NE(vertex, nullptr);
    const auto configure = [](DiffusionSolver& s) {
      s.SetRelTol(1e-12);
      s.SetMaxIter(20000);
      s.SetLinearSolver("multigrid-agg");
    };
    configure(*solver);
    // A fresh solver's solve: its system and fluence.
    const auto fresh = [&](const DiffusionProblem& p, DiffusionSystem& system) {
      auto other = CreateDiffusionSolver("divergence");
      configure(*other);
      std::vector<double> fluence;
      SolverReport report;
      EXPECT_TRUE(other->Solve(p, fluence, report));
      EXPECT_EQ(report.Assembly, "full");
      system = dynamic_cast<VertexDiffusionSolver&>(*other).GetSystem();
      return fluence;
    };
    const auto check = [&](const DiffusionProblem& p, const std::vector<double>& fluence,
                         const char* step) {
      DiffusionSystem system;
      const std::vector<double> expected = fresh(p, system);
      const DiffusionSystem& kept = vertex->GetSystem();
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        EXPECT_EQ(kept.Values[c], system.Values[c]) << step << ", matrix channel " << c;
        EXPECT_EQ(kept.RightHandSide[c], system.RightHandSide[c])
          << step << ", right-hand side channel " << c;
      }
      ASSERT_EQ(fluence.size(), expected.size());
      const double largest = *std::max_element(expected.begin(), expected.end());
      for (size_t i = 0; i < fluence.size(); ++i)
      {
        ASSERT_NEAR(fluence[i], expected[i], 1e-8 * largest) << step << ", value " << i;
      }
    };
    DiffusionProblem problem = MakeProblem(mesh, material, q);
    problem.Lights = first;
    problem.Collimated = model;
    std::vector<double> fluence;
    SolverReport report;
    ASSERT_TRUE(solver->Solve(problem, fluence, report));
    EXPECT_EQ(report.Assembly, "full");
    EXPECT_EQ(report.LinearSetup, "rebuilt");

    // Relight: another directional light, another point light (its q).
    DiffusionProblem relit = MakeProblem(mesh, material, secondQ);
    relit.Lights = second;
    relit.Collimated = model;
    vertex->SetChangedTets({}, true);
    ASSERT_TRUE(solver->Solve(relit, fluence, report));
    EXPECT_EQ(report.Assembly, "right-hand side");
    EXPECT_EQ(report.LinearSetup, "kept");
    check(relit, fluence, "relight");

    // Only the beam changed (q the same: the directional light is not in it).
    relit.Lights = first;
    vertex->SetChangedTets({}, false);
    ASSERT_TRUE(solver->Solve(relit, fluence, report));
    EXPECT_EQ(report.Assembly, "right-hand side");
    EXPECT_EQ(report.LinearSetup, "kept");
    check(relit, fluence, "beam only");

    // Paint: three tets' coefficients (the beam's load changes with mu_s').
    OpticalProperties painted = material;
    std::vector<int> changed = { 3, 40, 41 };
    for (int t : changed)
    {
      painted.AbsorptionCoefficient[3 * static_cast<size_t>(t)] *= 5.0;
      painted.ReducedScatteringCoefficient[3 * static_cast<size_t>(t) + 1] *= 2.0;
    }
    DiffusionProblem paint = MakeProblem(mesh, painted, secondQ);
    paint.Lights = first;
    paint.Collimated = model;
    vertex->SetChangedTets(changed, false);
    ASSERT_TRUE(solver->Solve(paint, fluence, report));
    EXPECT_EQ(report.Assembly, "incremental");
    EXPECT_EQ(report.LinearSetup, "rows");
    check(paint, fluence, "paint");
  }
}

} // namespace translucency

namespace translucency
{

// The issue's box (20 x 20 x 10 mm, mu_a 0.01/mm, mu_s' 1/mm, eta 1.3) lit
// face-on: the mean fluence over the vertices 2-7 mm deep within 4 mm of the
// axis, of divergence and fem with the surface and the extended model,
// against our Monte Carlo (isotropic scattering, mu_s = mu_s'; it agrees
// with an independent transport code within 1 %; here 4 x 100k photons,
// the standard error of the mean printed). The surface and extended models
// miss by 6-8 %; the issue's target (halve the gap) is reached by
// extended-moments, see below and DiffuseOptics.md.
TEST(CollimatedSource, GapToMonteCarloOnTheIssuesBox)
{
  const auto data = BoxMesh(10, 10, 10, 20.0, 20.0, 10.0);
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  const double muA[3] = { 0.01, 0.01, 0.01 }, muS[3] = { 1.0, 1.0, 1.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, muS, BoxEta);
  const std::vector<LightSource> lights = { Directional(0, 0, -1, 1.0, 1.0, 1.0) };
  std::vector<int> column;
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    const double* x = mesh.GetPoint(i);
    const double depth = 10.0 - x[2];
    if (depth >= 2.0 - 1e-9 && depth <= 7.0 + 1e-9 && std::abs(x[0] - 10.0) <= 4.0 + 1e-9 &&
      std::abs(x[1] - 10.0) <= 4.0 + 1e-9)
    {
      column.push_back(i);
    }
  }
  ASSERT_GT(column.size(), 100u);
  auto mean = [&](const std::vector<double>& fluence) {
    double sum = 0.0;
    for (int i : column)
    {
      sum += fluence[3 * static_cast<size_t>(i)];
    }
    return sum / column.size();
  };

  DiffusionProblem problem = MakeProblem(mesh, material);
  problem.Lights = lights;
  problem.Shadows = false;
  std::vector<double> q;
  ASSERT_TRUE(ComputeProjectedIrradiance(mesh, material.RefractiveIndex, lights, 0.0, 0, false, q));
  problem.Irradiance = &q;

  // The reference: 4 runs of 100k photons with different seeds; the
  // standard error of the mean from their spread (the vertex errors are
  // correlated through shared tets, so they are not summed).
  double runs[4], mcMean = 0.0;
  for (int run = 0; run < 4; ++run)
  {
    MonteCarloSolver monteCarlo;
    monteCarlo.SetNumberOfPhotons(100000);
    monteCarlo.SetSeed(11 + run);
    std::vector<double> reference;
    SolverReport mcReport;
    ASSERT_TRUE(monteCarlo.Solve(problem, reference, mcReport));
    runs[run] = mean(reference);
    mcMean += 0.25 * runs[run];
  }
  double spread = 0.0;
  for (double r : runs)
  {
    spread += (r - mcMean) * (r - mcMean);
  }
  const double mcError = std::sqrt(spread / 3.0) / 2.0; // sample std / sqrt(4)
  std::cout << "Monte Carlo mean fluence " << mcMean << " W/mm^2, standard error " << mcError
            << " (" << 100.0 * mcError / mcMean << " %), " << column.size() << " vertices\n";

  const std::vector<double> zero(q.size(), 0.0);
  for (const char* name : { "divergence", "fem" })
  {
    double gap[3];
    const char* modelNames[3] = { "surface", "extended", "extended-moments" };
    for (int model = 0; model < 3; ++model)
    {
      std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver(name);
      solver->SetRelTol(1e-10);
      solver->SetMaxIter(20000);
      DiffusionProblem diffusion = problem;
      if (model > 0)
      {
        diffusion.Collimated =
          model == 1 ? CollimatedModel::Extended : CollimatedModel::ExtendedMoments;
        diffusion.Irradiance = &zero; // the only light is the beam
      }
      std::vector<double> fluence;
      SolverReport report;
      ASSERT_TRUE(solver->Solve(diffusion, fluence, report));
      gap[model] = mean(fluence) / mcMean - 1.0;
      std::cout << name << ", " << modelNames[model] << ": mean " << mean(fluence)
                << ", gap to Monte Carlo " << 100.0 * gap[model] << " %\n";
    }
    // Measured (DiffuseOptics.md): surface -7.7 % (divergence) / -7.3 %
    // (fem), extended +6.1 % / +6.9 % (MC standard error 0.3 %): the
    // extended model overshoots by about as much as the surface model
    // undershoots, so the issue's target (halve the gap) is NOT reached:
    // this is the P1 error of a source within one transport length of the
    // surface (the 1D half-space solutions of the two models differ by the
    // same 9-16 %). The test pins the signs and sizes.
    EXPECT_LT(gap[0], -0.05) << name << ": the surface model reads low";
    EXPECT_GT(gap[1], 0.03) << name << ": the extended model reads high";
    EXPECT_GT((1.0 + gap[1]) / (1.0 + gap[0]), 1.09) << name;
    EXPECT_LT((1.0 + gap[1]) / (1.0 + gap[0]), 1.20) << name;
    EXPECT_LT(gap[1], 0.08) << name;
    // The issue's target, met by extended-moments (the same volume source,
    // the Robin condition with the Fresnel moments' A = 2.34 instead of the
    // fit's 2.60; DiffuseOptics.md): at most half the gap of either other
    // model, and within +-3.6 % (half the smaller of the two gaps measured
    // before, -7.3 % / +6.1 %: 13 MC standard errors). Measured +1.2 % /
    // +2.0 % (divergence / fem); the 1D slab (discrete ordinates against
    // P1) gives +0.25 %, the rest is the mesh (h = 2 mm), as for the other
    // two models.
    EXPECT_LT(std::abs(gap[2]), 0.036) << name << ": extended-moments";
    EXPECT_LT(std::abs(gap[2]), 0.5 * std::abs(gap[0])) << name << ": half the surface gap";
    EXPECT_LT(std::abs(gap[2]), 0.5 * std::abs(gap[1])) << name << ": half the extended gap";
    // The default model of a directional light (the core's default table,
    // which the filter, the plugin and the CLI read; issue 33) is nearer
    // Monte Carlo than the surface model (the independent reference:
    // transport, not diffusion).
    const int byDefault = static_cast<int>(DefaultCollimatedModel(LightKind::Directional));
    EXPECT_LT(std::abs(gap[byDefault]), std::abs(gap[0]))
      << name << ": the default model " << modelNames[byDefault];
  }
}

} // namespace translucency
