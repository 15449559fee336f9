// DiscreteDivergence::UpdateTets (painting, TransCut Sec. 5.2): rebuilding
// only the rows of the vertices of changed tets gives exactly (bit for bit)
// the system of a full re-assembly with the new material.

#include "DiffusionSolverFactory.h"
#include "DiscreteDivergence.h"
#include "FiniteElement.h"
#include "VertexDiffusionSolver.h"
#include "Error.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TetMesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace
{

using namespace translucency;
using translucency::testing::MakeProblem;

/// Every value of the two systems is the same double (EXPECT_EQ, no tolerance).
void ExpectIdentical(const DiffusionSystem& a, const DiffusionSystem& b)
{
  ASSERT_EQ(a.NumberOfUnknowns, b.NumberOfUnknowns);
  ASSERT_EQ(a.RowOffsets, b.RowOffsets);
  ASSERT_EQ(a.ColumnIndices, b.ColumnIndices);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    ASSERT_EQ(a.Values[c].size(), b.Values[c].size());
    int mismatches = 0;
    for (size_t k = 0; k < a.Values[c].size(); ++k)
    {
      if (a.Values[c][k] != b.Values[c][k] && ++mismatches <= 5)
      {
        ADD_FAILURE() << "channel " << c << ", value " << k << ": " << a.Values[c][k]
                      << " vs " << b.Values[c][k];
      }
      EXPECT_EQ(a.Values[c][k], b.Values[c][k]);
    }
    ASSERT_EQ(a.RightHandSide[c].size(), b.RightHandSide[c].size());
    for (Eigen::Index i = 0; i < a.RightHandSide[c].size(); ++i)
    {
      EXPECT_EQ(a.RightHandSide[c][i], b.RightHandSide[c][i]) << "rhs " << c << ", row " << i;
    }
  }
}

struct Scene
{
  TetMesh Mesh;
  OpticalProperties Material;
  std::vector<double> Irradiance;
};

Scene MakeScene(int cells, std::uint64_t seed)
{
  Scene s;
  const translucency::testing::MeshData box = translucency::testing::CubeMesh(cells, 10.0, 0.2, seed);
  std::vector<int> pointOrder, tetOrder;
  TetMesh::ComputeSpatialOrder(box.Points, box.Tets, pointOrder, tetOrder);
  const translucency::testing::MeshData data = translucency::testing::Permute(box, pointOrder, tetOrder);
  s.Mesh.SetGeometry(data.Points, data.Tets);
  const double muA[3] = { 0.0021, 0.0041, 0.0071 };
  const double sigmaS[3] = { 2.19, 2.62, 3.00 };
  s.Material = OpticalProperties::Uniform(s.Mesh.GetNumberOfTets(), muA, sigmaS, 1.3);
  std::mt19937_64 rng(seed + 7);
  s.Irradiance.resize(3 * static_cast<size_t>(s.Mesh.GetNumberOfPoints()));
  for (double& q : s.Irradiance)
  {
    q = translucency::testing::Uniform01(rng);
  }
  return s;
}

/// Random values for a random subset of tets (the rate is the chance of each tet).
std::vector<int> ChangeRandomTets(Scene& s, std::mt19937_64& rng, double rate, bool eta)
{
  std::vector<int> changed;
  for (int t = 0; t < s.Mesh.GetNumberOfTets(); ++t)
  {
    if (translucency::testing::Uniform01(rng) >= rate)
    {
      continue;
    }
    changed.push_back(t);
    for (int c = 0; c < 3; ++c)
    {
      s.Material.AbsorptionCoefficient[3 * t + c] = 0.1 * translucency::testing::Uniform01(rng);
      s.Material.ReducedScatteringCoefficient[3 * t + c] = 0.5 + 3.0 * translucency::testing::Uniform01(rng);
    }
    if (eta)
    {
      s.Material.RefractiveIndex[t] = 1.0 + translucency::testing::Uniform01(rng);
    }
  }
  return changed;
}

TEST(IncrementalAssembly, EqualsFullAssemblyBitForBit)
{
  for (int threads : { 1, 2 })
  {
    Scene s = MakeScene(8, 3);
    DiscreteDivergence divergence;
    divergence.SetNumberOfThreads(threads);
    DiffusionSystem incremental;
    divergence.Assemble(s.Mesh, s.Material, s.Irradiance, incremental);
    std::mt19937_64 rng(11);
    const double rates[] = { 0.001, 0.01, 0.1, 0.5 };
    for (int round = 0; round < 8; ++round)
    {
      const std::vector<int> changed = ChangeRandomTets(s, rng, rates[round % 4], round % 2 == 1);
      divergence.UpdateTets(s.Mesh, s.Material, s.Irradiance, changed, incremental);
      DiffusionSystem full;
      divergence.Assemble(s.Mesh, s.Material, s.Irradiance, full);
      SCOPED_TRACE(::testing::Message() << "threads " << threads << ", round " << round << ", "
                                      << changed.size() << " changed tets");
      ExpectIdentical(incremental, full);
    }
  }
}

TEST(IncrementalAssembly, LocalisedChangeAndEmptyChange)
{
  Scene s = MakeScene(10, 5);
  DiscreteDivergence divergence;
  DiffusionSystem incremental;
  divergence.Assemble(s.Mesh, s.Material, s.Irradiance, incremental);
  const DiffusionSystem before = incremental;
  divergence.UpdateTets(s.Mesh, s.Material, s.Irradiance, {}, incremental);
  ExpectIdentical(incremental, before);
  // A ball of tets around a corner (boundary rows included), like a paint stroke.
  std::vector<int> changed;
  for (int t = 0; t < s.Mesh.GetNumberOfTets(); ++t)
  {
    const int* tv = s.Mesh.GetTet(t);
    double r2 = 0.0;
    for (int d = 0; d < 3; ++d)
    {
      double x = 0.0;
      for (int a = 0; a < 4; ++a)
      {
        x += 0.25 * s.Mesh.GetPoint(tv[a])[d];
      }
      r2 += (x - 1.0) * (x - 1.0);
    }
    if (r2 < 9.0)
    {
      changed.push_back(t);
      changed.push_back(t); // duplicates are allowed
      s.Material.AbsorptionCoefficient[3 * t] *= 50.0;
      s.Material.RefractiveIndex[t] = 1.5;
    }
  }
  ASSERT_FALSE(changed.empty());
  divergence.UpdateTets(s.Mesh, s.Material, s.Irradiance, changed, incremental);
  DiffusionSystem full;
  divergence.Assemble(s.Mesh, s.Material, s.Irradiance, full);
  ExpectIdentical(incremental, full);
}

TEST(IncrementalAssembly, BadInputThrows)
{
  Scene s = MakeScene(3, 1);
  DiscreteDivergence divergence;
  DiffusionSystem system;
  EXPECT_THROW(divergence.UpdateTets(s.Mesh, s.Material, s.Irradiance, { 0 }, system), Error);
  divergence.Assemble(s.Mesh, s.Material, s.Irradiance, system);
  EXPECT_THROW(
    divergence.UpdateTets(s.Mesh, s.Material, s.Irradiance, { s.Mesh.GetNumberOfTets() }, system),
    Error);
  s.Material.AbsorptionCoefficient[3] = -1.0;
  try
  {
    divergence.UpdateTets(s.Mesh, s.Material, s.Irradiance, { 1 }, system);
    FAIL() << "a negative mu_a must throw";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("tet 1"), std::string::npos) << e.what();
  }
}

// VertexDiffusionSolver::SetChangedTets: a paint followed by a solve that
// only rebuilds the touched rows and warm-starts gives the fluence of a
// from-scratch solve (to the solver tolerance), reports "incremental", and
// falls back to a full assembly on another mesh (topology change).
TEST(IncrementalAssembly, SolverUpdatesOnlyTheChangedRows)
{
  Scene s = MakeScene(8, 9);
  const double tol = 1e-10;
  auto solver = CreateDiffusionSolver("divergence");
  auto* vertex = dynamic_cast<VertexDiffusionSolver*>(solver.get());
  ASSERT_NE(vertex, nullptr);
  solver->SetRelTol(tol);
  DiffusionProblem problem = MakeProblem(s.Mesh, s.Material, s.Irradiance);
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_EQ(report.Assembly, "full");
  const int coldIterations = report.Iterations[0];

  std::mt19937_64 rng(5);
  const std::vector<int> changed = ChangeRandomTets(s, rng, 0.01, true);
  ASSERT_FALSE(changed.empty());
  vertex->SetChangedTets(changed);
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_EQ(report.Assembly, "incremental");
  // The system is the one a full assembly gives (bit for bit).
  DiscreteDivergence divergence;
  DiffusionSystem full;
  divergence.Assemble(s.Mesh, s.Material, s.Irradiance, full);
  ExpectIdentical(vertex->GetSystem(), full);
  // Warm start from the previous fluence: fewer iterations than from zero.
  EXPECT_LT(report.Iterations[0], coldIterations);

  // From scratch with a new solver: same fluence to the solver tolerance.
  auto fresh = CreateDiffusionSolver("divergence");
  fresh->SetRelTol(tol);
  std::vector<double> reference;
  SolverReport freshReport;
  ASSERT_TRUE(fresh->Solve(problem, reference, freshReport));
  EXPECT_EQ(freshReport.Assembly, "full");
  ASSERT_EQ(reference.size(), fluence.size());
  double maxRef = 0.0, maxDiff = 0.0;
  for (size_t k = 0; k < fluence.size(); ++k)
  {
    maxRef = std::max(maxRef, std::abs(reference[k]));
    maxDiff = std::max(maxDiff, std::abs(reference[k] - fluence[k]));
  }
  ASSERT_GT(maxRef, 0.0);
  // Relative residual 1e-10 each; the condition number of these small
  // systems is far below 1e4.
  EXPECT_LT(maxDiff, 1e-6 * maxRef);

  // Moved points on the same mesh object (deformation): full assembly.
  std::vector<double> moved = s.Mesh.GetPoints();
  for (double& x : moved)
  {
    x *= 1.1;
  }
  s.Mesh.UpdatePoints(moved);
  vertex->SetChangedTets({ 0 });
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_EQ(report.Assembly, "full");

  // A request without a previous solve on that mesh: another mesh object
  // (as after a cut) falls back to a full assembly.
  Scene other = MakeScene(7, 9);
  DiffusionProblem otherProblem = MakeProblem(other.Mesh, other.Material, other.Irradiance);
  vertex->SetChangedTets({ 0, 1, 2 });
  ASSERT_TRUE(solver->Solve(otherProblem, fluence, report));
  EXPECT_EQ(report.Assembly, "full");
  // The request is one-shot: the next solve without one assembles in full.
  ASSERT_TRUE(solver->Solve(otherProblem, fluence, report));
  EXPECT_EQ(report.Assembly, "full");
}

// FEM has no incremental update: the request falls back to a full assembly.
TEST(IncrementalAssembly, FemFallsBackToFullAssembly)
{
  Scene s = MakeScene(4, 2);
  auto solver = CreateDiffusionSolver("fem");
  auto* vertex = dynamic_cast<VertexDiffusionSolver*>(solver.get());
  ASSERT_NE(vertex, nullptr);
  DiffusionProblem problem = MakeProblem(s.Mesh, s.Material, s.Irradiance);
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  vertex->SetChangedTets({ 0 });
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_EQ(report.Assembly, "full");
}


// The per-tet geometry cache (TetGeometryCache): a re-assembly from the cache
// gives the bits of an assembly that computes the geometry (a new object), and
// moving the points (UpdatePoints) or resetting the geometry of the same mesh
// object invalidates it.
TEST(IncrementalAssembly, GeometryCacheFollowsTheMesh)
{
  Scene s = MakeScene(6, 4);
  DiscreteDivergence cachedDivergence;
  FiniteElement cachedFem;
  auto check = [&](const char* when) {
    SCOPED_TRACE(when);
    DiffusionSystem a, b;
    cachedDivergence.Assemble(s.Mesh, s.Material, s.Irradiance, a); // may use the cache
    DiscreteDivergence fresh;
    fresh.Assemble(s.Mesh, s.Material, s.Irradiance, b); // computes the geometry
    ExpectIdentical(a, b);
    cachedFem.Assemble(s.Mesh, s.Material, s.Irradiance, a);
    FiniteElement freshFem;
    freshFem.Assemble(s.Mesh, s.Material, s.Irradiance, b);
    ExpectIdentical(a, b);
  };
  check("first assembly (fills the cache)");
  check("second assembly (from the cache)");
  // Move the points: same topology, new geometry.
  std::vector<double> moved = s.Mesh.GetPoints();
  for (size_t k = 0; k < moved.size(); ++k)
  {
    moved[k] = 1.25 * moved[k] + 0.01 * static_cast<double>(k % 7);
  }
  const std::uint64_t before = s.Mesh.GetGeometryRevision();
  s.Mesh.UpdatePoints(moved);
  EXPECT_NE(s.Mesh.GetGeometryRevision(), before);
  check("after UpdatePoints");
  // Same object, same sizes, other geometry through SetGeometry.
  std::vector<double> points = s.Mesh.GetPoints();
  for (double& x : points)
  {
    x *= 0.5;
  }
  s.Mesh.SetGeometry(points, s.Mesh.GetTets());
  check("after SetGeometry");
}

} // namespace
