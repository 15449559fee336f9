// DiffusionFrontEnd: the changed-tet detection after a paint (TransCut
// Sec. 5.2) and the warm-start bookkeeping that vtkSolveDiffusion delegates.
#include "DiffusionFrontEnd.h"
#include "DiffusionSolverFactory.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TestRandomProblems.h"
#include "TetMesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <limits>
#include <memory>

using namespace translucency;
using translucency::testing::Contains;
using translucency::testing::ErrorMessage;
using translucency::testing::MakeProblem;

namespace
{

struct Scene
{
  std::shared_ptr<const TetMesh> Mesh;
  OpticalProperties Material;
  std::vector<double> Irradiance;
};

Scene MakeScene(int cells)
{
  auto mesh = std::make_shared<TetMesh>();
  const translucency::testing::MeshData data = translucency::testing::CubeMesh(cells, 5.0, 0.2, 3);
  mesh->SetGeometry(data.Points, data.Tets);
  Scene s;
  s.Material = translucency::testing::RandomMaterial(mesh->GetNumberOfTets(), 11);
  s.Irradiance = translucency::testing::RandomIrradiance(*mesh, 12);
  s.Mesh = mesh;
  return s;
}

/// Paints tets first, first + stride, ... (n of them): new sigma_s' and eta.
std::vector<int> Paint(OpticalProperties& m, int first, int stride, int n)
{
  std::vector<int> painted;
  for (int k = 0; k < n; ++k)
  {
    const int t = first + k * stride;
    for (int c = 0; c < 3; ++c)
    {
      m.ReducedScatteringCoefficient[3 * t + c] *= 1.5;
    }
    m.RefractiveIndex[t] = 1.45;
    painted.push_back(t);
  }
  return painted;
}

double MaxRelativeDifference(const std::vector<double>& a, const std::vector<double>& b)
{
  double maxRef = 0.0, maxDiff = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k)
  {
    maxRef = std::max(maxRef, std::abs(b[k]));
    maxDiff = std::max(maxDiff, std::abs(a[k] - b[k]));
  }
  return maxDiff / maxRef;
}

} // namespace

TEST(DiffusionFrontEnd, FindChangedTetsComparesBits)
{
  Scene s = MakeScene(3);
  OpticalProperties painted = s.Material;
  const std::vector<int> changed = Paint(painted, 2, 7, 4);
  EXPECT_EQ(DiffusionFrontEnd::FindChangedTets(s.Material, painted, 100), changed);
  EXPECT_TRUE(DiffusionFrontEnd::FindChangedTets(s.Material, s.Material, 100).empty());
  // It stops once more than the limit are found.
  EXPECT_EQ(DiffusionFrontEnd::FindChangedTets(s.Material, painted, 1).size(), 2u);
  // A NaN that stays a NaN is no change; -0 for +0 is one.
  OpticalProperties a = s.Material, b = s.Material;
  a.AbsorptionCoefficient[4] = b.AbsorptionCoefficient[4] =
    std::numeric_limits<double>::quiet_NaN();
  b.ReducedScatteringCoefficient[3 * 5] = -0.0;
  a.ReducedScatteringCoefficient[3 * 5] = 0.0;
  EXPECT_EQ(DiffusionFrontEnd::FindChangedTets(a, b, 100), std::vector<int>{ 5 });
}

TEST(DiffusionFrontEnd, PaintIsIncrementalAndEqualsAFullAssembly)
{
  Scene s = MakeScene(6); // 1296 tets
  const double tol = 1e-11;
  DiffusionFrontEnd front;
  EXPECT_EQ(front.GetSolverName(), "divergence");
  front.GetSolver().SetRelTol(tol);
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, s.Irradiance, {}, fluence, report));
  EXPECT_EQ(report.Assembly, "full");
  EXPECT_EQ(front.GetNumberOfChangedTets(), -1); // nothing cached yet
  const int cold = report.Iterations[0];

  // A stroke over 1 % of the tets: found, incremental, warm.
  OpticalProperties painted = s.Material;
  const std::vector<int> changed = Paint(painted, 10, 97, 13);
  ASSERT_TRUE(front.Solve(s.Mesh, painted, s.Irradiance, {}, fluence, report));
  EXPECT_EQ(report.Assembly, "incremental");
  EXPECT_EQ(front.GetNumberOfChangedTets(), static_cast<long long>(changed.size()));
  EXPECT_LT(report.Iterations[0], cold);

  // The same fluence as a full assembly from scratch, to the solver tolerance.
  const std::unique_ptr<DiffusionSolver> fresh = CreateDiffusionSolver("divergence");
  fresh->SetRelTol(tol);
  DiffusionProblem problem = MakeProblem(*s.Mesh, painted, s.Irradiance);
  std::vector<double> reference;
  SolverReport freshReport;
  ASSERT_TRUE(fresh->Solve(problem, reference, freshReport));
  EXPECT_EQ(freshReport.Assembly, "full");
  ASSERT_EQ(reference.size(), fluence.size());
  EXPECT_LT(MaxRelativeDifference(fluence, reference), 1e-7);

  // Nothing changed: incremental with no changed tet.
  ASSERT_TRUE(front.Solve(s.Mesh, painted, s.Irradiance, {}, fluence, report));
  EXPECT_EQ(report.Assembly, "incremental");
  EXPECT_EQ(front.GetNumberOfChangedTets(), 0);

  // Beyond MaximumChangedFraction (5 %): a full assembly, the same result.
  OpticalProperties wide = painted;
  Paint(wide, 0, 3, 200); // 15 % of the tets
  ASSERT_TRUE(front.Solve(s.Mesh, wide, s.Irradiance, {}, fluence, report));
  EXPECT_EQ(report.Assembly, "full");
  EXPECT_EQ(front.GetNumberOfChangedTets(), -1);
  problem.Material = &wide;
  ASSERT_TRUE(fresh->Solve(problem, reference, freshReport));
  EXPECT_LT(MaxRelativeDifference(fluence, reference), 1e-7);
  // ... unless the fraction allows it.
  front.SetMaximumChangedFraction(0.5);
  OpticalProperties wider = wide;
  Paint(wider, 1, 3, 200);
  ASSERT_TRUE(front.Solve(s.Mesh, wider, s.Irradiance, {}, fluence, report));
  EXPECT_EQ(report.Assembly, "incremental");
  EXPECT_EQ(front.GetNumberOfChangedTets(), 200);

  // Another irradiance (relight): only the right-hand side is rebuilt, the
  // fluence is a solve from scratch of the relit scene.
  std::vector<double> relit = s.Irradiance;
  relit[3 * s.Mesh->GetBoundaryPoints()[0]] += 0.5;
  for (int i : s.Mesh->GetBoundaryPoints())
    relit[3 * static_cast<size_t>(i) + 1] *= 0.7;
  ASSERT_TRUE(front.Solve(s.Mesh, wider, relit, {}, fluence, report));
  EXPECT_EQ(front.GetNumberOfChangedTets(), 0);
  EXPECT_EQ(report.Assembly, "right-hand side");
  problem.Material = &wider;
  problem.Irradiance = &relit;
  ASSERT_TRUE(fresh->Solve(problem, reference, freshReport));
  EXPECT_LT(MaxRelativeDifference(fluence, reference), 1e-7);
  // Relit and painted at once: the changed rows and the right-hand side.
  OpticalProperties widest = wider;
  const std::vector<int> more = Paint(widest, 2, 41, 20);
  std::vector<double> relit2 = relit;
  for (int i : s.Mesh->GetBoundaryPoints())
    relit2[3 * static_cast<size_t>(i)] *= 1.3;
  ASSERT_TRUE(front.Solve(s.Mesh, widest, relit2, {}, fluence, report));
  EXPECT_EQ(front.GetNumberOfChangedTets(), static_cast<long long>(more.size()));
  EXPECT_EQ(report.Assembly, "incremental");
  problem.Material = &widest;
  problem.Irradiance = &relit2;
  ASSERT_TRUE(fresh->Solve(problem, reference, freshReport));
  EXPECT_LT(MaxRelativeDifference(fluence, reference), 1e-7);

  // Another mesh object (a cut, even with the same geometry): full, cold.
  Scene other = MakeScene(6);
  ASSERT_TRUE(front.Solve(other.Mesh, wider, relit, {}, fluence, report));
  EXPECT_EQ(front.GetNumberOfChangedTets(), -1);
  EXPECT_EQ(report.Assembly, "full");

  // IncrementalAssembly off: never looks.
  front.SetIncrementalAssembly(false);
  ASSERT_TRUE(front.Solve(other.Mesh, wider, relit, {}, fluence, report));
  ASSERT_TRUE(front.Solve(other.Mesh, wider, relit, {}, fluence, report));
  EXPECT_EQ(front.GetNumberOfChangedTets(), -1);
  EXPECT_EQ(report.Assembly, "full");
}

// Issue 31: a relight with the material kept from the last solve (no copy,
// comparison or validation of it) gives the fluence of a solve from scratch;
// without a kept material on this mesh it is refused.
TEST(DiffusionFrontEnd, KeptMaterialRelightEqualsASolveFromScratch)
{
  Scene s = MakeScene(6);
  const double tol = 1e-11;
  DiffusionFrontEnd front;
  front.GetSolver().SetRelTol(tol);
  SolveResult result;
  EXPECT_FALSE(front.HasKeptMaterial(s.Mesh));
  EXPECT_TRUE(Contains(
    ErrorMessage([&] { front.SolveKeptMaterial(s.Mesh, s.Irradiance, {}, SolveRequest(), result); }),
    "no material kept"));
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, s.Irradiance, {}, SolveRequest(), result));
  ASSERT_TRUE(front.HasKeptMaterial(s.Mesh));
  EXPECT_EQ(front.GetNumberOfMaterialComparisons(), 0);
  std::vector<double> relit = s.Irradiance;
  for (int i : s.Mesh->GetBoundaryPoints())
    relit[3 * static_cast<size_t>(i) + 2] *= 0.6;
  ASSERT_TRUE(front.SolveKeptMaterial(s.Mesh, relit, {}, SolveRequest(), result));
  EXPECT_EQ(result.Report.Assembly, "right-hand side");
  EXPECT_EQ(front.GetNumberOfChangedTets(), 0);
  EXPECT_EQ(front.GetNumberOfMaterialComparisons(), 0);
  ASSERT_TRUE(front.HasKeptMaterial(s.Mesh)); // kept again for the next relight
  const std::unique_ptr<DiffusionSolver> fresh = CreateDiffusionSolver("divergence");
  fresh->SetRelTol(tol);
  const DiffusionProblem problem = MakeProblem(*s.Mesh, s.Material, relit);
  std::vector<double> reference;
  SolverReport freshReport;
  ASSERT_TRUE(fresh->Solve(problem, reference, freshReport));
  EXPECT_LT(MaxRelativeDifference(result.Fluence, reference), 1e-7);
  // A material passed in is compared with the kept one.
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, relit, {}, SolveRequest(), result));
  EXPECT_EQ(front.GetNumberOfMaterialComparisons(), 1);
  // Another mesh object: nothing kept for it.
  Scene other = MakeScene(6);
  EXPECT_FALSE(front.HasKeptMaterial(other.Mesh));
}

// Issue 31: a paint written into the kept material in place
// (UpdateKeptMaterial) is the paint Solve finds by comparing copies: the
// same changed tets, the same assembly, the same fluence bit for bit; an
// invalid painted value is Validate's error and leaves the kept material as
// it was; beyond MaximumChangedFraction it is a full assembly.
TEST(DiffusionFrontEnd, PaintInPlaceEqualsAPaintByCopy)
{
  Scene s = MakeScene(6); // 1296 tets
  DiffusionFrontEnd inPlace, byCopy;
  SolveResult a, b;
  ASSERT_TRUE(inPlace.Solve(s.Mesh, s.Material, s.Irradiance, {}, SolveRequest(), a));
  ASSERT_TRUE(byCopy.Solve(s.Mesh, s.Material, s.Irradiance, {}, SolveRequest(), b));
  ASSERT_EQ(a.Fluence, b.Fluence);

  // Nothing kept for another mesh: refused, nothing done.
  Scene other = MakeScene(6);
  EXPECT_FALSE(inPlace.UpdateKeptMaterial(other.Mesh, s.Material.AbsorptionCoefficient.data(),
    s.Material.ReducedScatteringCoefficient.data(), s.Material.RefractiveIndex.data()));

  // A stroke over 1 % of the tets, with a relight.
  OpticalProperties painted = s.Material;
  const std::vector<int> changed = Paint(painted, 10, 97, 13);
  std::vector<double> relit = s.Irradiance;
  for (int i : s.Mesh->GetBoundaryPoints())
    relit[3 * static_cast<size_t>(i) + 1] *= 0.8;
  ASSERT_TRUE(inPlace.UpdateKeptMaterial(s.Mesh, painted.AbsorptionCoefficient.data(),
    painted.ReducedScatteringCoefficient.data(), painted.RefractiveIndex.data()));
  EXPECT_EQ(inPlace.GetNumberOfMaterialComparisons(), 1);
  ASSERT_TRUE(inPlace.SolveKeptMaterial(s.Mesh, relit, {}, SolveRequest(), a));
  ASSERT_TRUE(byCopy.Solve(s.Mesh, painted, relit, {}, SolveRequest(), b));
  EXPECT_EQ(a.Report.Assembly, "incremental");
  EXPECT_EQ(b.Report.Assembly, "incremental");
  EXPECT_EQ(inPlace.GetNumberOfChangedTets(), static_cast<long long>(changed.size()));
  EXPECT_EQ(byCopy.GetNumberOfChangedTets(), static_cast<long long>(changed.size()));
  EXPECT_EQ(a.Fluence, b.Fluence);
  const OpticalProperties* kept = inPlace.GetKeptMaterial();
  ASSERT_NE(kept, nullptr);
  EXPECT_EQ(kept->AbsorptionCoefficient, painted.AbsorptionCoefficient);
  EXPECT_EQ(kept->ReducedScatteringCoefficient, painted.ReducedScatteringCoefficient);
  EXPECT_EQ(kept->RefractiveIndex, painted.RefractiveIndex);

  // An invalid value on a painted tet: Validate's message, the kept material
  // unchanged.
  OpticalProperties bad = painted;
  Paint(bad, 3, 50, 5);
  bad.AbsorptionCoefficient[3 * 103 + 2] = -1.0; // tet 103, channel B
  bad.ReducedScatteringCoefficient[3 * 200] = std::numeric_limits<double>::quiet_NaN();
  const std::string message = ErrorMessage([&] {
    inPlace.UpdateKeptMaterial(s.Mesh, bad.AbsorptionCoefficient.data(),
      bad.ReducedScatteringCoefficient.data(), bad.RefractiveIndex.data());
  });
  EXPECT_TRUE(Contains(message, "AbsorptionCoefficient of tet 103, channel B is -1")) << message;
  EXPECT_EQ(kept->AbsorptionCoefficient, painted.AbsorptionCoefficient);
  EXPECT_EQ(kept->ReducedScatteringCoefficient, painted.ReducedScatteringCoefficient);
  EXPECT_EQ(kept->RefractiveIndex, painted.RefractiveIndex);
  ASSERT_TRUE(inPlace.SolveKeptMaterial(s.Mesh, relit, {}, SolveRequest(), a));
  EXPECT_EQ(inPlace.GetNumberOfChangedTets(), 0);
  EXPECT_EQ(a.Fluence, b.Fluence);

  // Beyond MaximumChangedFraction (5 %): a full assembly of the new values,
  // as Solve does.
  OpticalProperties wide = painted;
  Paint(wide, 0, 3, 200); // 15 % of the tets
  ASSERT_TRUE(inPlace.UpdateKeptMaterial(s.Mesh, wide.AbsorptionCoefficient.data(),
    wide.ReducedScatteringCoefficient.data(), wide.RefractiveIndex.data()));
  ASSERT_TRUE(inPlace.SolveKeptMaterial(s.Mesh, relit, {}, SolveRequest(), a));
  ASSERT_TRUE(byCopy.Solve(s.Mesh, wide, relit, {}, SolveRequest(), b));
  EXPECT_EQ(a.Report.Assembly, "full");
  EXPECT_EQ(b.Report.Assembly, "full");
  EXPECT_EQ(inPlace.GetNumberOfChangedTets(), -1);
  EXPECT_EQ(a.Fluence, b.Fluence);
}

TEST(DiffusionFrontEnd, SolverByNameAndNoIncrementalForOtherSolvers)
{
  Scene s = MakeScene(3);
  DiffusionFrontEnd front;
  front.GetSolver().SetRelTol(1e-9);
  front.SetSolver("DIVERGENCE"); // the same solver: its settings are kept
  EXPECT_EQ(front.GetSolver().GetRelTol(), 1e-9);
  EXPECT_EQ(ErrorMessage([&] { front.SetSolver("voxels"); }),
    "unknown solver 'voxels' (known solvers: divergence, fem, quadgraph, grid, montecarlo, sp3)");
  EXPECT_EQ(front.GetSolverName(), "divergence");

  front.SetSolver("quadgraph"); // a new solver, default settings
  EXPECT_EQ(front.GetSolver().GetName(), "quadgraph");
  EXPECT_EQ(front.GetSolver().GetRelTol(), 1e-6);
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, s.Irradiance, {}, fluence, report));
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, s.Irradiance, {}, fluence, report));
  EXPECT_EQ(front.GetNumberOfChangedTets(), -1);
  EXPECT_EQ(report.Assembly, "");

  // An error forgets the cache: the next solve is full.
  front.SetSolver("divergence");
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, s.Irradiance, {}, fluence, report));
  EXPECT_FALSE(ErrorMessage([&] {
    front.Solve(s.Mesh, s.Material, std::vector<double>(3), {}, fluence, report);
  }).empty());
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, s.Irradiance, {}, fluence, report));
  EXPECT_EQ(front.GetNumberOfChangedTets(), -1);
  EXPECT_EQ(report.Assembly, "full");
}

// ---- One front end for every domain, decided by the registry traits.

TEST(DiffusionFrontEnd, DomainsAreRefusedByTraitsNamingTheSolversWithThem)
{
  Scene s = MakeScene(3);
  DiffusionFrontEnd front;
  SolveRequest frequency;
  frequency.Domain = SolveDomain::Frequency;
  frequency.Frequency = 1e8;
  SolveRequest time;
  time.Domain = SolveDomain::Time;
  time.Gates.Start = 0.0;
  time.Gates.End = 1.0;
  time.Gates.Count = 4;
  SolveResult result;
  for (const auto& entry : GetDiffusionSolverRegistry().GetEntries())
  {
    SCOPED_TRACE(entry.Name);
    front.SetSolver(entry.Name);
    const std::string f = ErrorMessage([&] { front.CheckDomain(frequency); });
    const std::string t = ErrorMessage([&] { front.CheckDomain(time); });
    EXPECT_EQ(f.empty(), entry.Properties.SupportsFrequency) << f;
    EXPECT_EQ(t.empty(), entry.Properties.SupportsTime) << t;
    if (!f.empty())
    {
      EXPECT_EQ(f,
        "the " + entry.Name +
          " solver has no frequency domain (modulation frequency 1e+08 Hz): solvers with one: "
          "divergence, fem, sp3");
      // The solve refuses it before any work, and so does the interface.
      EXPECT_EQ(ErrorMessage([&] {
        front.Solve(s.Mesh, s.Material, s.Irradiance, {}, frequency, result);
      }),
        f);
      std::vector<std::complex<double>> phi;
      SolverReport report;
      DiffusionProblem problem;
      EXPECT_TRUE(Contains(ErrorMessage([&] {
        entry.Create()->SolveFrequencyDomain(problem, 1e8, phi, report);
      }),
        "the " + entry.Name + " solver has no frequency domain"));
    }
    if (!t.empty())
    {
      EXPECT_TRUE(Contains(t, "the " + entry.Name + " solver has no frequency domain or time gates"));
      EXPECT_TRUE(Contains(t, "time gates are implemented by divergence, fem, montecarlo"));
    }
    // Distributed: a variant registered by the Parallel layer (TestParallel).
    EXPECT_EQ(entry.Properties.Distributed, static_cast<bool>(entry.Properties.CreateDistributed));
  }
}

TEST(DiffusionFrontEnd, EveryDomainThroughTheFrontEndEqualsTheSolverItself)
{
  Scene s = MakeScene(4);
  DiffusionProblem problem;
  problem.Mesh = s.Mesh.get();
  problem.Material = &s.Material;
  problem.Irradiance = &s.Irradiance;
  std::vector<Detector> detectors(1);
  const double* x = s.Mesh->GetPoint(s.Mesh->GetBoundaryPoints()[5]);
  detectors[0].Position = { x[0], x[1], x[2] };
  detectors[0].Radius = 0.5;

  DiffusionFrontEnd front;
  front.GetSolver().SetRelTol(1e-10);
  auto direct = CreateDiffusionSolver("divergence");
  direct->SetRelTol(1e-10);

  // Continuous wave: the detectors read the solver's fluence.
  SolveRequest cw;
  cw.Detectors = detectors;
  SolveResult result;
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, s.Irradiance, {}, cw, result));
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(direct->Solve(problem, fluence, report));
  EXPECT_LT(MaxRelativeDifference(result.Fluence, fluence), 1e-8);
  const auto readings = ReadDetectors(*s.Mesh, s.Material, detectors, fluence, &s.Irradiance,
    Fresnel::BoundaryRule::Fit);
  ASSERT_EQ(result.Readings.size(), 1u);
  ASSERT_EQ(result.FluencePhase.size(), 1u);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_NEAR(result.Readings[0].Fluence[c], readings[0].Fluence[c],
      1e-7 * std::abs(readings[0].Fluence[c]));
    EXPECT_EQ(result.FluencePhase[0][c], 0.0);
  }

  // Frequency domain: amplitude and phase of the solver's complex fluence.
  SolveRequest fd;
  fd.Domain = SolveDomain::Frequency;
  fd.Frequency = 2e8;
  fd.Detectors = detectors;
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, s.Irradiance, {}, fd, result));
  std::vector<std::complex<double>> phi;
  ASSERT_TRUE(direct->SolveFrequencyDomain(problem, 2e8, phi, report));
  ASSERT_EQ(result.Amplitude.size(), phi.size());
  for (std::size_t i = 0; i < phi.size(); i += 17)
  {
    EXPECT_NEAR(result.Amplitude[i], std::abs(phi[i]), 1e-7 * std::abs(phi[i]));
    EXPECT_NEAR(result.Phase[i], std::arg(phi[i]), 1e-6);
    EXPECT_EQ(result.Fluence[i], result.Amplitude[i]); // no beam: Fluence is the amplitude
  }
  EXPECT_LT(result.FluencePhase[0][0], 0.0); // the detector lags the source

  // Time domain: the readings are the integrals of the gate readings.
  SolveRequest td;
  td.Domain = SolveDomain::Time;
  td.Gates.Start = 0.0;
  td.Gates.End = 0.5;
  td.Gates.Count = 5;
  td.Snapshots = { 2 };
  td.Detectors = detectors;
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, s.Irradiance, {}, td, result));
  ASSERT_EQ(result.Time.Readings.size(), 5u);
  ASSERT_EQ(result.Time.Snapshots.size(), 1u);
  EXPECT_EQ(result.Fluence, result.Time.IntegratedFluence);
  double integral = 0.0;
  for (const auto& gate : result.Time.Readings)
  {
    integral += td.Gates.GetWidth() * gate[0].Fluence[1];
  }
  EXPECT_NEAR(result.Readings[0].Fluence[1], integral, 1e-12 * std::abs(integral));

  // Snapshots need time gates.
  cw.Snapshots = { 0 };
  EXPECT_EQ(ErrorMessage([&] { front.CheckDomain(cw); }), "time snapshots without time gates");
}

// Issue 32: a solve that does not converge is solved again after a full
// set-up; if that fails too, no result (an error naming the numbers).
TEST(DiffusionFrontEnd, NeverHandsOnANonConvergedSolve)
{
  Scene s = MakeScene(4);
  DiffusionFrontEnd front;
  front.GetSolver().SetRelTol(1e-12);
  front.GetSolver().SetMaxIter(2);
  SolveResult result;
  const std::string message =
    ErrorMessage([&] { front.Solve(s.Mesh, s.Material, s.Irradiance, {}, SolveRequest(), result); });
  EXPECT_TRUE(Contains(message, "the divergence solve did not converge, also after a full set-up"))
    << message;
  EXPECT_TRUE(Contains(message, "channel R: relative residual")) << message;
  EXPECT_TRUE(Contains(message, "after 2 iterations")) << message;
  EXPECT_TRUE(Contains(message, "MaxIter 2")) << message;

  // For convergence studies only: kept, and marked as the re-solve.
  SolveRequest study;
  study.AcceptUnconverged = true;
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, s.Irradiance, {}, study, result));
  EXPECT_TRUE(result.Report.Resolved);
  EXPECT_FALSE(result.Report.Converged[0]);
  EXPECT_EQ(result.Report.Iterations[0], 2);

  // A converged solve is not solved twice, and equals the solver's own.
  front.GetSolver().SetMaxIter(2000);
  ASSERT_TRUE(front.Solve(s.Mesh, s.Material, s.Irradiance, {}, SolveRequest(), result));
  EXPECT_FALSE(result.Report.Resolved);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(result.Report.Converged[c]);
  }

  // Every solver with a linear solver obeys the rule (the stochastic one
  // has no iterations to converge).
  for (const std::string name : { "fem", "quadgraph", "grid" })
  {
    SCOPED_TRACE(name);
    front.SetSolver(name);
    front.GetSolver().SetRelTol(1e-13);
    front.GetSolver().SetMaxIter(1);
    EXPECT_TRUE(Contains(ErrorMessage([&] {
      front.Solve(s.Mesh, s.Material, s.Irradiance, {}, SolveRequest(), result);
    }),
      "solve did not converge, also after a full set-up"));
  }
}
