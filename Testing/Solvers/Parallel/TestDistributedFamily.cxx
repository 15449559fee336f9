// Serial and distributed are one family (issue 30, item 3): the distributed
// vertex solver is the registry's distributed variant of divergence and fem
// (trait Distributed), chosen by DiffusionFrontEnd::SetCommunicator, and on
// a communicator of size one (MPI_COMM_SELF: no mpiexec) it gives the serial
// solve's fluence, detector readings and power balance to the solver
// tolerance (the independent reason: the serial solver on the same tets).
#include "DiffusionFrontEnd.h"
#include "DiffusionSolverFactory.h"
#include "DistributedLinearSolver.h"
#include "DistributedVertexSolver.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TestRandomProblems.h"
#include "TetMesh.h"
#include "VertexDiffusionSolver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

using namespace translucency;
using translucency::testing::RelativeDifference;
using translucency::testing::Contains;
using translucency::testing::ErrorMessage;

namespace
{

Communicator Self()
{
  return MakeCommunicator(GetSelfCommunicator());
}


double Relative(double a, double b)
{
  return std::abs(a - b) / std::max(std::abs(b), 1e-300);
}

struct Scene
{
  std::shared_ptr<const TetMesh> Mesh;
  OpticalProperties Material;
  std::vector<double> Irradiance;
  std::vector<PointKey> Keys;
  Sources InteriorSources;
  std::vector<Detector> Detectors;
};

Scene MakeScene()
{
  Scene s;
  const translucency::testing::MeshData data = translucency::testing::CubeMesh(6, 5.0, 0.2, 7);
  auto mesh = std::make_shared<TetMesh>();
  mesh->SetGeometry(data.Points, data.Tets);
  s.Material = translucency::testing::RandomMaterial(mesh->GetNumberOfTets(), 21);
  s.Irradiance = translucency::testing::RandomIrradiance(*mesh, 22);
  for (int i = 0; i < mesh->GetNumberOfPoints(); ++i)
  {
    s.Keys.push_back(PointKeyFromId(i));
  }
  PointSource source;
  source.Position = { 2.4, 2.6, 2.5 };
  source.Power = { 1.0, 0.5, 2.0 };
  s.InteriorSources.AddPointSource(source);
  const double* x = mesh->GetPoint(mesh->GetBoundaryPoints()[7]);
  Detector detector;
  detector.Position = { x[0], x[1], x[2] };
  detector.Radius = 0.6;
  s.Detectors.push_back(detector);
  s.Mesh = mesh;
  return s;
}

/// One continuous-wave solve through `front` of scene `s` (with its
/// sources, detectors and, when distributed, its point keys).
SolveResult SolveScene(DiffusionFrontEnd& front, const Scene& s, const std::vector<double>& q)
{
  DiffusionProblem light;
  light.InteriorSources = &s.InteriorSources;
  light.PointKeys = &s.Keys;
  SolveRequest request;
  request.Detectors = s.Detectors;
  SolveResult result;
  EXPECT_TRUE(front.Solve(s.Mesh, s.Material, q, light, request, result));
  return result;
}

} // namespace

TEST(DistributedFamily, TheFrontEndPicksTheDistributedVariantByTrait)
{
  // The registry: divergence and fem have a distributed variant on pieces,
  // montecarlo one on the replicated problem (registered by the Parallel
  // layer), the others none.
  EXPECT_EQ(GetDiffusionSolverNamesWith(DiffusionTrait::Distributed),
    (std::vector<std::string>{ "divergence", "fem", "montecarlo" }));
  for (const auto& entry : GetDiffusionSolverRegistry().GetEntries())
  {
    SCOPED_TRACE(entry.Name);
    EXPECT_EQ(static_cast<bool>(entry.Properties.CreateDistributed), entry.Properties.Distributed);
    EXPECT_EQ(entry.Properties.Replicated, entry.Name == "montecarlo");
  }

  DiffusionFrontEnd front;
  front.SetSolver("fem");
  EXPECT_NE(dynamic_cast<VertexDiffusionSolver*>(&front.GetSolver()), nullptr);
  front.SetCommunicator(Self());
  EXPECT_TRUE(front.GetCommunicator().IsMPI());
  EXPECT_EQ(front.GetCommunicator().GetSize(), 1);
  EXPECT_EQ(front.GetSolverName(), "fem");
  EXPECT_EQ(front.GetSolver().GetName(), "fem");
  EXPECT_NE(dynamic_cast<DistributedVertexSolver*>(&front.GetSolver()), nullptr);
  front.SetSolver("divergence"); // the variant again
  EXPECT_NE(dynamic_cast<DistributedVertexSolver*>(&front.GetSolver()), nullptr);
  EXPECT_EQ(front.GetSolver().GetName(), "divergence");

  // A solver without one is refused, naming those with one; the front end
  // keeps its solver.
  EXPECT_EQ(ErrorMessage([&] { front.SetSolver("quadgraph"); }),
    "the quadgraph solver has no distributed variant (solvers with one: divergence, fem, "
    "montecarlo)");
  EXPECT_EQ(front.GetSolverName(), "divergence");
  EXPECT_NE(dynamic_cast<DistributedVertexSolver*>(&front.GetSolver()), nullptr);
  // and the distributed solve is continuous wave only.
  SolveRequest frequency;
  frequency.Domain = SolveDomain::Frequency;
  frequency.Frequency = 1e8;
  EXPECT_TRUE(Contains(ErrorMessage([&] { front.CheckDomain(frequency); }),
    "the distributed divergence solve is continuous wave only"));

  // No communicator: the in-process solver again.
  front.SetCommunicator(Communicator());
  EXPECT_NE(dynamic_cast<VertexDiffusionSolver*>(&front.GetSolver()), nullptr);
  EXPECT_TRUE(ErrorMessage([&] { front.CheckDomain(frequency); }).empty());

  // The in-process solvers refuse an MPI communicator themselves.
  EXPECT_TRUE(Contains(ErrorMessage([&] { CreateDiffusionSolver("grid")->SetCommunicator(Self()); }),
    "the grid solver runs in one process"));
  DiffusionFrontEnd grid;
  grid.SetSolver("grid");
  EXPECT_TRUE(Contains(ErrorMessage([&] { grid.SetCommunicator(Self()); }),
    "the grid solver has no distributed variant"));
  EXPECT_FALSE(grid.GetCommunicator().IsMPI());
}

TEST(DistributedFamily, OneRankEqualsTheSerialSolve)
{
  // One hierarchy per channel (the default; SharedAndOwnHierarchiesAgree
  // compares it with one shared by the three).
  const Scene s = MakeScene();
  // The relight's irradiance: another field on the same boundary points.
  std::vector<double> relit = s.Irradiance;
  for (std::size_t k = 0; k < relit.size(); ++k)
  {
    relit[k] *= 0.5 + 0.1 * static_cast<double>(k % 7);
  }
  const double tol = 1e-12;
  // The default distributed linear solver (cg/boomeramg) and the
  // distributed multigrid-agg (cg/aggregation, SchwarzAggregation.h).
  for (const std::string linear : { "", "cg/aggregation" })
  for (const std::string name : { "divergence", "fem" })
  {
    SCOPED_TRACE(name + " " + linear);
    DiffusionFrontEnd serial, distributed;
    serial.SetSolver(name);
    distributed.SetSolver(name);
    distributed.SetCommunicator(Self());
    if (!linear.empty())
      distributed.GetSolver().SetLinearSolver(linear);
    serial.GetSolver().SetRelTol(tol);
    distributed.GetSolver().SetRelTol(tol);

    for (const std::vector<double>* q : { &s.Irradiance, static_cast<const std::vector<double>*>(&relit) })
    {
      const SolveResult a = SolveScene(serial, s, *q);
      const SolveResult b = SolveScene(distributed, s, *q);
      EXPECT_EQ(b.Report.Solver, name);
      EXPECT_EQ(b.Report.LinearSolver,
        (linear.empty() ? std::string("cg/boomeramg") : linear) + " (distributed)");
      EXPECT_EQ(b.Report.NumberOfUnknowns, s.Mesh->GetNumberOfPoints());
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        EXPECT_TRUE(b.Report.Converged[c]);
        EXPECT_LE(b.Report.Residual[c], tol);
      }
      // Both stop at ||r|| <= 1e-12 ||b||: the fields agree far below the
      // 1e-8 asked here (the condition number of these small systems is
      // below 1e3).
      EXPECT_LT(RelativeDifference(b.Fluence, a.Fluence), 1e-8);
      ASSERT_EQ(b.Readings.size(), a.Readings.size());
      ASSERT_EQ(b.Readings.size(), 1u);
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        EXPECT_LT(Relative(b.Readings[0].Fluence[c], a.Readings[0].Fluence[c]), 1e-8);
        EXPECT_LT(Relative(b.Readings[0].Exitance[c], a.Readings[0].Exitance[c]), 1e-8);
      }
      // The power balance: the serial one from its fluence, the
      // distributed one summed over the ranks by the solver (its tallies).
      std::array<double, NumberOfChannels> in1{}, abs1{}, esc1{}, in2{}, abs2{}, esc2{};
      DiffusionFrontEnd::ComputePowerBalance(*s.Mesh, s.Material, a.Fluence, *q,
        &s.InteriorSources, a, SolveDomain::ContinuousWave, in1, abs1, esc1);
      EXPECT_TRUE(b.HasTalliedBalance);
      DiffusionFrontEnd::ComputePowerBalance(*s.Mesh, s.Material, b.Fluence, *q,
        &s.InteriorSources, b, SolveDomain::ContinuousWave, in2, abs2, esc2);
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        EXPECT_LT(Relative(in2[c], in1[c]), 1e-12); // no solve in it: sums in another order
        EXPECT_LT(Relative(abs2[c], abs1[c]), 1e-8);
        EXPECT_LT(Relative(esc2[c], esc1[c]), 1e-8);
      }
    }
  }
}

// Issue 32: the extended collimated models on the distributed path (the
// beam cast against the gathered boundary, DistributedCollimatedSource; the
// moments' Robin rule in the hypre system) give the serial solve's fluence,
// collimated fluence, detector readings and power balance, cold and relit
// (another light direction: the matrices kept), shadows on and off.
TEST(DistributedFamily, TheExtendedModelsEqualTheSerialSolve)
{
  const Scene s = MakeScene();
  const double tol = 1e-12;
  for (const CollimatedModel model : { CollimatedModel::Extended, CollimatedModel::ExtendedMoments })
  {
    for (const std::string name : { "divergence", "fem" })
    {
      SCOPED_TRACE(name + (model == CollimatedModel::Extended ? " extended" : " extended-moments"));
      DiffusionFrontEnd serial, distributed;
      serial.SetSolver(name);
      distributed.SetSolver(name);
      distributed.SetCommunicator(Self());
      serial.GetSolver().SetRelTol(tol);
      distributed.GetSolver().SetRelTol(tol);
      int step = 0;
      for (const std::array<double, 3>& direction :
        { std::array<double, 3>{ 0.13, -1.0, -0.77 }, std::array<double, 3>{ -0.4, 0.3, -1.0 } })
      {
        SCOPED_TRACE(step++);
        DiffusionProblem light;
        light.InteriorSources = &s.InteriorSources;
        light.PointKeys = &s.Keys;
        light.Lights = { DirectionalLight(direction, { 1.0, 0.7, 0.4 }) };
        light.Shadows = step == 2;
        light.Collimated = model;
        SolveRequest request;
        request.Detectors = s.Detectors;
        SolveResult a, b;
        ASSERT_TRUE(serial.Solve(s.Mesh, s.Material, s.Irradiance, light, request, a));
        ASSERT_TRUE(distributed.Solve(s.Mesh, s.Material, s.Irradiance, light, request, b));
        if (step == 2)
        {
          EXPECT_EQ(b.Report.Assembly, "unchanged"); // a relight: the matrices kept
        }
        EXPECT_EQ(b.Rule, a.Rule);
        // The beam: the same rays on the same surface (another triangle order).
        EXPECT_LT(RelativeDifference(b.Report.CollimatedFluence, a.Report.CollimatedFluence), 1e-12);
        double beamMax = 0.0;
        for (double e : a.Report.CollimatedFluence)
          beamMax = std::max(beamMax, e);
        EXPECT_GT(beamMax, 0.1);
        EXPECT_LT(RelativeDifference(b.Fluence, a.Fluence), 1e-8);
        ASSERT_EQ(b.Readings.size(), 1u);
        ASSERT_EQ(a.Readings.size(), 1u);
        std::array<double, NumberOfChannels> in1{}, abs1{}, esc1{}, in2{}, abs2{}, esc2{};
        DiffusionFrontEnd::ComputePowerBalance(*s.Mesh, s.Material, a.Fluence, s.Irradiance,
          &s.InteriorSources, a, SolveDomain::ContinuousWave, in1, abs1, esc1);
        EXPECT_TRUE(b.HasTalliedBalance);
        DiffusionFrontEnd::ComputePowerBalance(*s.Mesh, s.Material, b.Fluence, s.Irradiance,
          &s.InteriorSources, b, SolveDomain::ContinuousWave, in2, abs2, esc2);
        for (int c = 0; c < NumberOfChannels; ++c)
        {
          EXPECT_LT(Relative(b.Readings[0].Fluence[c], a.Readings[0].Fluence[c]), 1e-8);
          EXPECT_LT(Relative(b.Readings[0].Exitance[c], a.Readings[0].Exitance[c]), 1e-8);
          // Entering: per surface point instead of per triangle corner (1e-13).
          EXPECT_LT(Relative(in2[c], in1[c]), 1e-10);
          EXPECT_LT(Relative(abs2[c], abs1[c]), 1e-8);
          EXPECT_LT(Relative(esc2[c], esc1[c]), 1e-8);
        }
      }
    }
  }
}

// Issue 32: one BoomerAMG hierarchy for the three channels (SetSharedHierarchy)
// gives the fluence of one hierarchy per channel (the default) (both to RelTol 1e-12 of
// the same systems); counted set-ups: a cold solve numbers once and sets up
// one hierarchy (three without sharing), a relight (same mesh and
// material) sets up nothing and assembles the right-hand side only, a paint
// with the values-only set-up nothing, a full set-up one again.
TEST(DistributedFamily, SharedAndOwnHierarchiesAgree)
{
  // The channels of a measured material are alike (sigma_s' and mu_a grow
  // with the channel by the same factors everywhere): the random R channel
  // of the scene scaled so.
  Scene s = MakeScene();
  for (std::size_t t = 0; t < s.Material.RefractiveIndex.size(); ++t)
  {
    for (int c = 1; c < NumberOfChannels; ++c)
    {
      s.Material.AbsorptionCoefficient[3 * t + c] = s.Material.AbsorptionCoefficient[3 * t] * (1.0 + 0.5 * c);
      s.Material.ReducedScatteringCoefficient[3 * t + c] =
        s.Material.ReducedScatteringCoefficient[3 * t] * (1.0 + 0.15 * c);
    }
  }
  std::vector<double> relit = s.Irradiance;
  for (std::size_t k = 0; k < relit.size(); ++k)
    relit[k] *= 0.5 + 0.1 * static_cast<double>(k % 7);
  OpticalProperties painted = s.Material;
  for (std::size_t k = 0; k < painted.AbsorptionCoefficient.size(); k += 11)
    painted.AbsorptionCoefficient[k] *= 3.0;
  // BoomerAMG (the default) and cg/aggregation (whose sharers share the
  // block aggregation, each with its own values).
  for (const std::string linear : { "", "cg/aggregation" })
  for (const std::string name : { "divergence", "fem" })
  {
    SCOPED_TRACE(name + " " + linear);
    auto configure = [&linear](DistributedVertexSolver& solver, bool shared) {
      if (!linear.empty())
        solver.SetLinearSolver(linear);
      solver.SetSharedHierarchy(shared);
      solver.SetRelTol(1e-12);
    };
    auto problemOf = [](const Scene& scene) {
      DiffusionProblem problem;
      problem.Mesh = scene.Mesh.get();
      problem.Material = &scene.Material;
      problem.Irradiance = &scene.Irradiance;
      problem.PointKeys = &scene.Keys;
      return problem;
    };
    std::vector<double> fluence[2][3];
    for (const bool shared : { true, false })
    {
      DistributedVertexSolver solver(name);
      configure(solver, shared);
      SolverReport report;
      DiffusionProblem problem = problemOf(s);
      std::vector<double>* out = fluence[shared ? 0 : 1];
      const long long own = shared ? 1 : 3;
      ASSERT_TRUE(solver.Solve(problem, out[0], report));
      EXPECT_EQ(report.Assembly, "full");
      EXPECT_EQ(report.LinearSetup,
        "rebuilt (numberings 1, hierarchies " + std::to_string(own) + ")");
      for (int c = 0; c < NumberOfChannels; ++c)
        EXPECT_LE(report.Residual[c], 1e-12);
      EXPECT_FALSE(report.Resolved);
      problem.Irradiance = &relit;
      ASSERT_TRUE(solver.Solve(problem, out[1], report));
      EXPECT_EQ(report.Assembly, "unchanged");
      EXPECT_EQ(report.LinearSetup,
        "kept (numberings 1, hierarchies " + std::to_string(own) + ")");
      EXPECT_EQ(solver.GetNumberOfNumberings(), 1);
      EXPECT_EQ(solver.GetNumberOfHierarchySetups(), own);
      problem.Material = &painted;
      ASSERT_TRUE(solver.Solve(problem, out[2], report));
      EXPECT_EQ(report.Assembly, "values-only");
      EXPECT_EQ(solver.GetNumberOfHierarchySetups(), own + (report.Resolved ? 1 : 0));
      for (int c = 0; c < NumberOfChannels; ++c)
        EXPECT_LE(report.Residual[c], 1e-12);
      solver.SetValuesOnlySetup(false);
      problem.Material = &s.Material;
      std::vector<double> again;
      ASSERT_TRUE(solver.Solve(problem, again, report));
      EXPECT_EQ(report.Assembly, "full");
      EXPECT_EQ(report.LinearSetup.rfind("rebuilt (numberings 1, ", 0), 0u) << report.LinearSetup;
      EXPECT_LT(RelativeDifference(again, out[1]), 1e-8);
    }
    for (int k = 0; k < 3; ++k)
      EXPECT_LT(RelativeDifference(fluence[0][k], fluence[1][k]), 1e-8) << "solve " << k;

    // Channels unlike each other (the scene's independent random channels:
    // diagonals several times apart) share the coarsening too: each has its
    // own Galerkin levels and smoother norms, so each converges to RelTol
    // without a second set-up, to the field of a hierarchy per channel.
    const Scene random = MakeScene();
    std::vector<double> unlike[2];
    for (const bool shared : { true, false })
    {
      DistributedVertexSolver solver(name);
      configure(solver, shared);
      const DiffusionProblem problem = problemOf(random);
      SolverReport report;
      ASSERT_TRUE(solver.Solve(problem, unlike[shared ? 0 : 1], report));
      EXPECT_EQ(report.LinearSetup,
        std::string("rebuilt (numberings 1, hierarchies ") + (shared ? "1)" : "3)"));
      for (int c = 0; c < NumberOfChannels; ++c)
        EXPECT_LE(report.Residual[c], 1e-12);
      EXPECT_FALSE(report.Resolved);
    }
    EXPECT_LT(RelativeDifference(unlike[0], unlike[1]), 1e-8);
  }
}

// At the interactive tolerance a small paint leaves the warm start within
// RelTol: the distributed solve must still iterate, as the serial path does
// (LinearSolver::SetMinIter), so the stroke shows in the fluence. hypre's
// PCG checks convergence only after its first iteration, so the distributed
// path needs no guard of its own; this test keeps it so for any distributed
// linear solver of the registry.
TEST(DistributedFamily, APaintIteratesTheWarmStartAtLeastOnce)
{
  const Scene s = MakeScene();
  DiffusionFrontEnd front;
  front.SetCommunicator(Self());
  // The field before the stroke solved tightly, the stroke at the
  // interactive tolerance: the warm start's residual is then far below it.
  front.GetSolver().SetRelTol(1e-8);
  const SolveResult before = SolveScene(front, s, s.Irradiance);
  front.GetSolver().SetRelTol(1e-2);
  Scene painted = s;
  // One tet's absorption 1 % up in every channel: a stroke whose change of
  // the residual stays far below 1e-2 of ||b||.
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    painted.Material.AbsorptionCoefficient[3 * 10 + c] *= 1.01;
  }
  const SolveResult after = SolveScene(front, painted, s.Irradiance);
  double change = 0.0;
  for (std::size_t k = 0; k < after.Fluence.size(); ++k)
  {
    change = std::max(change, std::abs(after.Fluence[k] - before.Fluence[k]));
  }
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    SCOPED_TRACE(c);
    EXPECT_GE(after.Report.Iterations[c], 1);
    EXPECT_TRUE(after.Report.Converged[c]);
  }
  EXPECT_GT(change, 0.0);
}

TEST(DistributedFamily, NeverANonConvergedResult)
{
  const Scene s = MakeScene();
  for (const std::string linear : { "", "cg/aggregation" })
  {
    SCOPED_TRACE(linear);
    DiffusionFrontEnd front;
    front.SetCommunicator(Self());
    if (!linear.empty())
      front.GetSolver().SetLinearSolver(linear);
    front.GetSolver().SetRelTol(1e-12);
    front.GetSolver().SetMaxIter(1);
    const std::string message = ErrorMessage([&] { SolveScene(front, s, s.Irradiance); });
    EXPECT_TRUE(Contains(message,
      "the distributed divergence solve did not converge, also after a full set-up"))
      << message;
    EXPECT_TRUE(Contains(message, "MaxIter 1")) << message;
  }
  DiffusionFrontEnd front;
  front.SetCommunicator(Self());
  front.GetSolver().SetRelTol(1e-12);
  // The problem's point keys are required.
  front.GetSolver().SetMaxIter(2000);
  SolveResult result;
  EXPECT_TRUE(Contains(ErrorMessage([&] {
    front.Solve(s.Mesh, s.Material, s.Irradiance, DiffusionProblem(), SolveRequest(), result);
  }),
    "needs the points' global keys"));
}

// hypre comes from the linear-solver registry: "cg/boomeramg" (alias
// "hypre-amg") has a distributed variant, the other compositions not.
TEST(DistributedFamily, BoomerAMGCGIsARegistryComposition)
{
  auto solver = CreateDistributedLinearSolver("cg/boomeramg", Self());
  EXPECT_EQ(solver->GetName(), "cg/boomeramg");
  EXPECT_EQ(CreateDistributedLinearSolver("HYPRE-AMG", Self())->GetName(), "cg/boomeramg");
  EXPECT_EQ(ErrorMessage([] { CreateDistributedLinearSolver("cg/jacobi", Self()); }),
    "linear solver 'cg/jacobi' has no distributed variant (those with one: cg/aggregation, "
    "cg/boomeramg)");
  EXPECT_TRUE(Contains(ErrorMessage([] { CreateDistributedLinearSolver("gmres", Self()); }),
    "linear solver 'gmres' has no distributed variant"));
  // An option it reads is checked.
  SolverOptions bad;
  bad.Set("amg-strong-threshold", 1.5);
  EXPECT_TRUE(Contains(ErrorMessage([&] { solver->SetOptions(bad); }), "amg-strong-threshold"));
  SolverOptions badDown;
  badDown.Set("amg-relaxation-down", -2.0); // -1 (amg-relaxation) or a hypre code
  EXPECT_TRUE(Contains(ErrorMessage([&] { solver->SetOptions(badDown); }), "amg-relaxation-down"));

  // A 1-D Laplacian (+ identity) of 60 rows on one rank: the solve meets its
  // tolerance on the residual computed here; after a values-only update
  // (the diagonal 3 -> 3.3, the hierarchy kept: a paint-sized change) the
  // solve meets it on the new matrix, computed here too.
  const int n = 60;
  std::vector<int> offsets(1, 0), columns;
  std::vector<double> values, b(n);
  for (int i = 0; i < n; ++i)
  {
    for (int j = std::max(0, i - 1); j <= std::min(n - 1, i + 1); ++j)
    {
      columns.push_back(j);
      values.push_back(i == j ? 3.0 : -1.0);
    }
    offsets.push_back(static_cast<int>(columns.size()));
    b[i] = std::sin(0.3 * i) + 1.0;
  }
  auto relativeResidual = [&](const std::vector<double>& a, const std::vector<double>& x) {
    double r2 = 0.0, b2 = 0.0;
    for (int i = 0; i < n; ++i)
    {
      double ax = 0.0;
      for (int k = offsets[i]; k < offsets[i + 1]; ++k)
        ax += a[k] * x[columns[k]];
      r2 += (b[i] - ax) * (b[i] - ax);
      b2 += b[i] * b[i];
    }
    return std::sqrt(r2 / b2);
  };
  solver->Setup(0, n, offsets.data(), columns.data(), values.data());
  std::vector<double> x(n, 0.0), y(n, 0.0);
  double residual = 1.0;
  EXPECT_GT(solver->Solve(b.data(), x.data(), false, 1e-12, 100, residual), 0);
  EXPECT_LE(residual, 1e-12);
  EXPECT_LE(relativeResidual(values, x), 1e-11);
  std::vector<double> shifted(values);
  for (int i = 0; i < n; ++i)
    for (int k = offsets[i]; k < offsets[i + 1]; ++k)
      if (columns[k] == i)
        shifted[k] = 3.3;
  solver->UpdateValues(offsets.data(), columns.data(), shifted.data());
  EXPECT_EQ(solver->GetHierarchyMilliseconds(), 0.0); // kept
  solver->Solve(b.data(), y.data(), false, 1e-12, 100, residual);
  EXPECT_LE(residual, 1e-12);
  EXPECT_LE(relativeResidual(shifted, y), 1e-11);
  EXPECT_GT(relativeResidual(values, y), 1e-2); // the new matrix, not the old one
  // A pattern change is refused.
  std::vector<int> moved(columns);
  moved[1] = 5;
  EXPECT_TRUE(Contains(
    ErrorMessage([&] { solver->UpdateValues(offsets.data(), moved.data(), shifted.data()); }),
    "not in the matrix of the last Setup"));

  // Issue 32: a second solver on the first one's coarsening (one BoomerAMG
  // set-up for the three channels, each channel its own Galerkin levels)
  // solves its own matrix (the residual computed here); a donor without a
  // set-up is refused (false: nothing built).
  auto sharer = CreateDistributedLinearSolver("cg/boomeramg", Self());
  auto unset = CreateDistributedLinearSolver("cg/boomeramg", Self());
  EXPECT_FALSE(sharer->SetupShared(0, n, offsets.data(), columns.data(), values.data(), *unset));
  std::vector<double> other(values);
  for (double& v : other)
    v *= 1.7; // another channel: kappa and mu_a scaled
  for (int i = 0; i < n; ++i)
    for (int k = offsets[i]; k < offsets[i + 1]; ++k)
      if (columns[k] == i)
        other[k] += 0.4;
  ASSERT_TRUE(sharer->SetupShared(0, n, offsets.data(), columns.data(), other.data(), *solver));
  EXPECT_EQ(sharer->GetNumberOfLevels(), solver->GetNumberOfLevels());
  std::vector<double> z(n, 0.0);
  EXPECT_GT(sharer->Solve(b.data(), z.data(), false, 1e-12, 100, residual), 0);
  EXPECT_LE(residual, 1e-12);
  EXPECT_LE(relativeResidual(other, z), 1e-11);
  EXPECT_GT(relativeResidual(shifted, z), 1e-2); // its own matrix, not the donor's

  // Its levels are its own: on a donor's coarsening, the matrix 2.5 A has
  // the Galerkin levels 2.5 A_l and the l1 norms 2.5 d_l, so its V-cycle is
  // the donor's divided by 2.5 and PCG takes the donor's iterations to
  // x / 2.5 (an identity; with the donor's own coarse levels and norms, as
  // before issue 32's Galerkin sharing, the cycle mixes the two scales).
  auto donor = CreateDistributedLinearSolver("cg/boomeramg", Self());
  donor->Setup(0, n, offsets.data(), columns.data(), values.data());
  ASSERT_GT(donor->GetNumberOfLevels(), 2); // coarse levels and a coarsest to eliminate
  std::vector<double> scaled(values), xd(n, 0.0), xs(n, 0.0);
  for (double& v : scaled)
    v *= 2.5;
  auto scaledSharer = CreateDistributedLinearSolver("cg/boomeramg", Self());
  ASSERT_TRUE(
    scaledSharer->SetupShared(0, n, offsets.data(), columns.data(), scaled.data(), *donor));
  double rd = 1.0, rs = 1.0;
  const int itd = donor->Solve(b.data(), xd.data(), false, 1e-10, 100, rd);
  const int its = scaledSharer->Solve(b.data(), xs.data(), false, 1e-10, 100, rs);
  EXPECT_GT(itd, 1);
  EXPECT_EQ(its, itd);
  double d2 = 0.0, x2 = 0.0;
  for (int i = 0; i < n; ++i)
  {
    d2 += (2.5 * xs[i] - xd[i]) * (2.5 * xs[i] - xd[i]);
    x2 += xd[i] * xd[i];
  }
  EXPECT_LE(std::sqrt(d2 / x2), 1e-12);
  // The three-channel PCG applies the same cycles: the donor's and the
  // sharer's solutions again, from zero.
  std::array<DistributedLinearSolver*, NumberOfChannels> pair{ donor.get(), scaledSharer.get(),
    nullptr };
  std::vector<double> yd(n, 0.0), ys(n, 0.0);
  std::array<const double*, NumberOfChannels> bs{ b.data(), b.data(), nullptr };
  std::array<double*, NumberOfChannels> xs2{ yd.data(), ys.data(), nullptr };
  DistributedSolveControl control;
  control.RelTol = 1e-10;
  control.MaxIter = 100;
  std::array<DistributedChannelStats, NumberOfChannels> stats{};
  donor->SolveChannels(pair, bs, xs2, { false, false, false }, control, stats);
  EXPECT_EQ(stats[0].Iterations, stats[1].Iterations);
  for (int i = 0; i < n; ++i)
    EXPECT_NEAR(2.5 * ys[i], yd[i], 1e-10 * std::sqrt(x2)) << i;
  // A donor whose smoother's set-up data the sharer does not rebuild (6:
  // hybrid symmetric Gauss-Seidel without l1 norms, which is not refused
  // by hypre) is refused: false, nothing built (the channel then gets its own).
  auto plain = CreateDistributedLinearSolver("cg/boomeramg", Self());
  SolverOptions gaussSeidel;
  gaussSeidel.Set("amg-relaxation", 6.0);
  gaussSeidel.Set("amg-relaxation-down", -1.0); // both ways the relaxation above
  gaussSeidel.Set("amg-relaxation-up", -1.0);
  plain->SetOptions(gaussSeidel);
  plain->Setup(0, n, offsets.data(), columns.data(), values.data());
  auto refused = CreateDistributedLinearSolver("cg/boomeramg", Self());
  EXPECT_FALSE(refused->SetupShared(0, n, offsets.data(), columns.data(), scaled.data(), *plain));
  EXPECT_TRUE(Contains(ErrorMessage([&] {
    double r = 0.0;
    refused->Solve(b.data(), xs.data(), false, 1e-10, 100, r);
  }),
    "Solve() called before Setup()"));

  // The distributed diffusion solver names the composition it used.
  const Scene s = MakeScene();
  DiffusionFrontEnd front;
  front.SetCommunicator(Self());
  EXPECT_EQ(SolveScene(front, s, s.Irradiance).Report.LinearSolver, "cg/boomeramg (distributed)");
  front.GetSolver().SetLinearSolver("cg/jacobi");
  EXPECT_TRUE(Contains(ErrorMessage([&] { SolveScene(front, s, s.Irradiance); }),
    "linear solver 'cg/jacobi' has no distributed variant"));
}
