// The consistent P1 Galerkin discretisation (FiniteElement, the "fem"
// solver): against an independent triplet assembly, the stiffness / lumping
// identities that tie it to the discrete divergence (TransCut Sec. 3), exact
// discrete solutions, a manufactured solution with measured convergence
// orders, determinism, input checks, and the divergence-vs-FEM difference on
// a TetGen tetrahedralisation of the bunny (TransCut Sec. 6.2: about 2 %).

#include "ConjugateGradient.h"
#include "DiffusionSolverFactory.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "FiniteElement.h"
#include "Fresnel.h"
#include "LightSources.h"
#include "Radiance.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TestReferenceAssembly.h"
#include "TetGenMeshes.h"
#include "TetMesh.h"
#include "VertexDiffusionSolver.h"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#ifndef TETLIBRARY
#define TETLIBRARY
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
#include <string>

namespace
{

using namespace translucency;
using namespace translucency::testing;

using ColMatrix = Eigen::SparseMatrix<double>;

TetMesh Build(const MeshData& data)
{
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  return mesh;
}

/// Random heterogeneous material: every tet, channel and index different
/// (uniformEta > 0 gives that index everywhere instead).
OpticalProperties RandomMaterial(int numTets, std::uint64_t seed, double uniformEta = 0.0)
{
  std::mt19937_64 rng(seed);
  OpticalProperties m;
  for (int t = 0; t < numTets; ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      m.AbsorptionCoefficient.push_back(0.01 + 0.5 * Uniform01(rng));
      m.ReducedScatteringCoefficient.push_back(0.2 + 3.0 * Uniform01(rng));
    }
    const double eta = 1.2 + 0.3 * Uniform01(rng);
    m.RefractiveIndex.push_back(uniformEta > 0.0 ? uniformEta : eta);
  }
  return m;
}

std::vector<double> RandomIrradiance(const TetMesh& mesh, std::uint64_t seed)
{
  std::mt19937_64 rng(seed);
  std::vector<double> q(3 * mesh.GetNumberOfPoints(), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    for (int c = 0; c < 3; ++c)
    {
      q[3 * i + c] = 2.0 * Uniform01(rng);
    }
  }
  return q;
}

ColMatrix ToEigen(const DiffusionSystem& system, int c)
{
  return ColMatrix(system.Matrix(c));
}

double FdrOf(double eta)
{
  return -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
}

double AOf(double eta)
{
  const double fdr = FdrOf(eta);
  return (1.0 + fdr) / (1.0 - fdr);
}

/// Largest |entry| of each row (the scale for entrywise comparisons: the
/// diagonal entries are sums with cancellation).
Eigen::VectorXd RowScale(const ColMatrix& m)
{
  Eigen::VectorXd scale = Eigen::VectorXd::Zero(m.rows());
  for (int k = 0; k < m.outerSize(); ++k)
  {
    for (ColMatrix::InnerIterator it(m, k); it; ++it)
    {
      scale[it.row()] = std::max(scale[it.row()], std::abs(it.value()));
    }
  }
  return scale;
}

/// max_ij |a_ij - b_ij| / rowScale_i.
double WorstRelativeDifference(const ColMatrix& a, const ColMatrix& b, const Eigen::VectorXd& scale)
{
  const ColMatrix difference = a - b;
  double worst = 0.0;
  for (int k = 0; k < difference.outerSize(); ++k)
  {
    for (ColMatrix::InnerIterator it(difference, k); it; ++it)
    {
      worst = std::max(worst, std::abs(it.value()) / scale[it.row()]);
    }
  }
  return worst;
}

/// The parts of an independent consistent P1 assembly (not scaled by 4):
/// stiffness from barycentric gradients (inverse of the 3x3 edge matrix),
/// consistent mass, consistent boundary mass and load with A, Fdr of each
/// boundary triangle's owner tet; and the lumped mass / boundary mass (row
/// sums, computed from V_t and S_f directly) for the identities with the
/// divergence matrix.
struct Reference
{
  std::array<ColMatrix, 3> Stiffness, Mass, BoundaryMass, LumpedMass, LumpedBoundary;
  std::array<Eigen::VectorXd, 3> Load;
};

Reference AssembleReference(const TetMesh& mesh,
  const OpticalProperties& material,
  const std::vector<double>& q)
{
  const int n = mesh.GetNumberOfPoints();
  using Triplets = std::vector<Eigen::Triplet<double>>;
  std::array<Triplets, 3> stiffness, mass, boundary, lumpedMass, lumpedBoundary;
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    const int* tv = mesh.GetTet(t);
    const P1Tet tet = P1TetOf(mesh, t);
    const double volume = tet.Volume;
    const Eigen::Vector3d* grad = tet.Grad;
    for (int c = 0; c < 3; ++c)
    {
      const double mu = material.AbsorptionCoefficient[3 * t + c];
      const double kappa = 1.0 / (3.0 * (mu + material.ReducedScatteringCoefficient[3 * t + c]));
      for (int a = 0; a < 4; ++a)
      {
        for (int b = 0; b < 4; ++b)
        {
          stiffness[c].emplace_back(tv[a], tv[b], kappa * volume * grad[a].dot(grad[b]));
          mass[c].emplace_back(tv[a], tv[b], volume / 20.0 * (a == b ? 2.0 : 1.0) * mu);
        }
        lumpedMass[c].emplace_back(tv[a], tv[a], volume * mu / 4.0);
      }
    }
  }
  Reference ref;
  for (int c = 0; c < 3; ++c)
  {
    ref.Load[c].setZero(n);
  }
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    const int* tri = &mesh.GetBoundaryTriangles()[3 * f];
    const Eigen::Vector3d p0(mesh.GetPoint(tri[0])), p1(mesh.GetPoint(tri[1])),
      p2(mesh.GetPoint(tri[2]));
    const double area = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    const double eta = material.RefractiveIndex[mesh.GetBoundaryTriangleTets()[f]];
    const double a = AOf(eta), fdr = FdrOf(eta);
    for (int c = 0; c < 3; ++c)
    {
      for (int j = 0; j < 3; ++j)
      {
        double integral = 0.0; // int_f q beta_j with q linear on f
        for (int k = 0; k < 3; ++k)
        {
          const double m = area / 12.0 * (j == k ? 2.0 : 1.0);
          boundary[c].emplace_back(tri[j], tri[k], m / (2.0 * a));
          integral += m * q[3 * tri[k] + c];
        }
        ref.Load[c][tri[j]] += 2.0 / (a * (1.0 - fdr)) * integral;
        lumpedBoundary[c].emplace_back(tri[j], tri[j], area / 3.0 / (2.0 * a));
      }
    }
  }
  auto toMatrix = [n](const Triplets& triplets)
  {
    ColMatrix m(n, n);
    m.setFromTriplets(triplets.begin(), triplets.end());
    return m;
  };
  for (int c = 0; c < 3; ++c)
  {
    ref.Stiffness[c] = toMatrix(stiffness[c]);
    ref.Mass[c] = toMatrix(mass[c]);
    ref.BoundaryMass[c] = toMatrix(boundary[c]);
    ref.LumpedMass[c] = toMatrix(lumpedMass[c]);
    ref.LumpedBoundary[c] = toMatrix(lumpedBoundary[c]);
  }
  return ref;
}

class FiniteElementAssembly : public ::testing::TestWithParam<int> // mesh seed
{
};

TEST_P(FiniteElementAssembly, EqualsFourTimesIndependentConsistentAssembly)
{
  // Heterogeneous mu_a, sigma_s' and eta on a jittered mesh.
  const TetMesh mesh = Build(CubeMesh(5, 2.0, 0.25, GetParam()));
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 100 + GetParam());
  const std::vector<double> q = RandomIrradiance(mesh, 200 + GetParam());
  FiniteElement fem;
  DiffusionSystem system;
  fem.Assemble(mesh, material, q, system);
  EXPECT_EQ(system.NumberOfUnknowns, mesh.GetNumberOfPoints());
  EXPECT_EQ(system.ColumnIndices, mesh.GetColumnIndices());
  const Reference ref = AssembleReference(mesh, material, q);
  for (int c = 0; c < 3; ++c)
  {
    const ColMatrix m = ToEigen(system, c);
    const ColMatrix expected =
      4.0 * (ref.Stiffness[c] + ref.Mass[c] + ref.BoundaryMass[c]);
    EXPECT_LT(WorstRelativeDifference(m, expected, RowScale(expected)), 1e-12) << "channel " << c;
    EXPECT_EQ(m.nonZeros(), expected.nonZeros());

    // Exactly symmetric (both triangles get the same sums in the same order).
    const ColMatrix transposed = m.transpose();
    EXPECT_EQ((m - transposed).norm(), 0.0) << "channel " << c;
    // Positive definite: Cholesky succeeds.
    Eigen::SimplicialLLT<ColMatrix> llt(m);
    EXPECT_EQ(llt.info(), Eigen::Success) << "channel " << c;

    const Eigen::VectorXd& b = system.RightHandSide[c];
    EXPECT_LT((b - 4.0 * ref.Load[c]).lpNorm<Eigen::Infinity>(),
      1e-13 * ref.Load[c].lpNorm<Eigen::Infinity>())
      << "channel " << c;
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      if (!mesh.IsBoundaryPoint(i))
      {
        EXPECT_EQ(b[i], 0.0);
      }
    }
  }
}

TEST_P(FiniteElementAssembly, StiffnessIdentityWithDiscreteDivergence)
{
  // Both matrices are 4 x (P1 stiffness + mass + boundary mass); FEM's mass
  // parts are consistent, the divergence's lumped. Uniform eta so that the
  // divergence's per-vertex A equals FEM's per-triangle A.
  const TetMesh mesh = Build(CubeMesh(5, 2.0, 0.25, 10 + GetParam()));
  const OpticalProperties material =
    RandomMaterial(mesh.GetNumberOfTets(), 110 + GetParam(), 1.37);
  const std::vector<double> q = RandomIrradiance(mesh, 210 + GetParam());
  FiniteElement fem;
  DiscreteDivergence divergence;
  DiffusionSystem femSystem, divSystem;
  fem.Assemble(mesh, material, q, femSystem);
  divergence.Assemble(mesh, material, q, divSystem);
  const Reference ref = AssembleReference(mesh, material, q);
  for (int c = 0; c < 3; ++c)
  {
    const ColMatrix f = ToEigen(femSystem, c);
    const ColMatrix d = ToEigen(divSystem, c);
    const Eigen::VectorXd scale = RowScale(f);
    // FEM - 4 (consistent parts) == divergence - 4 (lumped parts): the same
    // stiffness, to round-off.
    const ColMatrix femStiffness = f - 4.0 * (ref.Mass[c] + ref.BoundaryMass[c]);
    const ColMatrix divStiffness = d - 4.0 * (ref.LumpedMass[c] + ref.LumpedBoundary[c]);
    EXPECT_LT(WorstRelativeDifference(femStiffness, divStiffness, scale), 1e-12)
      << "channel " << c;

    // Lumping FEM's matrix (each row summed onto its diagonal) gives the
    // divergence matrix: the row sums of FEM - divergence vanish. This uses
    // no reference part at all.
    const ColMatrix difference = f - d;
    const Eigen::VectorXd rowSums = difference * Eigen::VectorXd::Ones(difference.cols());
    EXPECT_LT((rowSums.array() / scale.array()).abs().maxCoeff(), 1e-13) << "channel " << c;
  }
}

INSTANTIATE_TEST_SUITE_P(RandomMeshes, FiniteElementAssembly, ::testing::Values(1, 2, 3));

TEST(FiniteElement, UniformIrradianceGivesTheDivergenceRightHandSideSum)
{
  // For uniform q the consistent load per boundary vertex sums, over the
  // mesh, to the lumped load of TransCut eq. 12: sum_i 8 S_i q/(3A(1-Fdr)).
  const TetMesh mesh = Build(CubeMesh(4, 3.0, 0.25, 21));
  const double eta = 1.44;
  OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 22, eta);
  std::vector<double> q(3 * mesh.GetNumberOfPoints(), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    q[3 * i + 0] = 1.0;
    q[3 * i + 1] = 0.5;
    q[3 * i + 2] = 2.0;
  }
  FiniteElement fem;
  DiffusionSystem system;
  fem.Assemble(mesh, material, q, system);
  double totalArea = 0.0;
  for (double s : mesh.GetBoundaryTriangleAreas())
  {
    totalArea += s;
  }
  const double qc[3] = { 1.0, 0.5, 2.0 };
  for (int c = 0; c < 3; ++c)
  {
    // sum_i S_i = 3 x total area.
    const double expected = 8.0 * 3.0 * totalArea * qc[c] / (3.0 * AOf(eta) * (1.0 - FdrOf(eta)));
    EXPECT_NEAR(system.RightHandSide[c].sum(), expected, 1e-12 * expected) << "channel " << c;
  }
}

TEST(FiniteElement, MassAndBoundaryPartsByLinearity)
{
  // The mass part is what changes when mu_a moves into sigma_s' at fixed
  // mu_a + sigma_s' (kappa unchanged to the bit); the boundary part is what
  // changes with eta. Extract both from assembled matrices and check their
  // totals and their row sums (lumped versions) against the divergence's.
  const TetMesh mesh = Build(CubeMesh(6, 2.5, 0.25, 31));
  const double eta1 = 1.3, eta2 = 1.5;
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 32, eta1);
  OpticalProperties noAbsorption = material;
  for (size_t k = 0; k < material.AbsorptionCoefficient.size(); ++k)
  {
    noAbsorption.AbsorptionCoefficient[k] = 0.0;
    noAbsorption.ReducedScatteringCoefficient[k] =
      material.AbsorptionCoefficient[k] + material.ReducedScatteringCoefficient[k];
  }
  OpticalProperties otherEta = material;
  std::fill(otherEta.RefractiveIndex.begin(), otherEta.RefractiveIndex.end(), eta2);
  const std::vector<double> q(3 * mesh.GetNumberOfPoints(), 0.0);

  FiniteElement fem;
  DiscreteDivergence divergence;
  auto assemble = [&](Discretization& d, const OpticalProperties& m, int c)
  {
    DiffusionSystem system;
    d.Assemble(mesh, m, q, system);
    return ToEigen(system, c);
  };
  double totalArea = 0.0;
  for (double s : mesh.GetBoundaryTriangleAreas())
  {
    totalArea += s;
  }
  for (int c = 0; c < 3; ++c)
  {
    const ColMatrix full = assemble(fem, material, c);
    const Eigen::VectorXd scale = RowScale(full);
    const Eigen::VectorXd ones = Eigen::VectorXd::Ones(full.cols());

    // Mass: sum of all entries = 4 sum_t V_t mu_t; lumped = divergence's.
    const ColMatrix femMass = full - assemble(fem, noAbsorption, c);
    const ColMatrix divMass = assemble(divergence, material, c) - assemble(divergence, noAbsorption, c);
    double expectedMass = 0.0;
    for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
    {
      expectedMass += 4.0 * mesh.GetTetVolume(t) * material.AbsorptionCoefficient[3 * t + c];
    }
    EXPECT_NEAR(femMass.sum(), expectedMass, 1e-11 * expectedMass) << "channel " << c;
    const Eigen::VectorXd femMassRows = femMass * ones;
    const Eigen::VectorXd divMassRows = divMass * ones;
    EXPECT_LT(((femMassRows - divMassRows).array() / scale.array()).abs().maxCoeff(), 1e-13);
    // The divergence's mass part is diagonal (lumped), FEM's is not.
    const ColMatrix divMassOff = divMass - ColMatrix(divMass.diagonal().asDiagonal());
    EXPECT_LT(divMassOff.cwiseAbs().sum(), 1e-12 * expectedMass);
    const ColMatrix femMassOff = femMass - ColMatrix(femMass.diagonal().asDiagonal());
    EXPECT_GT(femMassOff.sum(), 0.5 * expectedMass); // 3/5 of the total in exact arithmetic

    // Boundary: 4 x (1/(2A)) int phi v changes by 2 (1/A1 - 1/A2) x total
    // area in sum; its lumped version equals the divergence's.
    const ColMatrix femBoundary = full - assemble(fem, otherEta, c);
    const ColMatrix divBoundary = assemble(divergence, material, c) - assemble(divergence, otherEta, c);
    const double expectedBoundary = 2.0 * (1.0 / AOf(eta1) - 1.0 / AOf(eta2)) * totalArea;
    EXPECT_NEAR(femBoundary.sum(), expectedBoundary, 1e-11 * std::abs(expectedBoundary));
    const Eigen::VectorXd femBoundaryRows = femBoundary * ones;
    const Eigen::VectorXd divBoundaryRows = divBoundary * ones;
    EXPECT_LT(
      ((femBoundaryRows - divBoundaryRows).array() / scale.array()).abs().maxCoeff(), 1e-13);
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      if (!mesh.IsBoundaryPoint(i))
      {
        EXPECT_LT(std::abs(femBoundaryRows[i]), 1e-13 * scale[i]);
      }
    }
  }
}

TEST(FiniteElement, ConstantSolutionWithoutAbsorption)
{
  // mu_a = 0 (kappa may vary: the stiffness rows sum to 0), uniform eta and
  // q: phi = 4 q / (1 - Fdr) solves the consistent system exactly.
  const TetMesh mesh = Build(CubeMesh(8, 4.0, 0.25, 5));
  const double eta = 1.3;
  OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 51, eta);
  std::fill(material.AbsorptionCoefficient.begin(), material.AbsorptionCoefficient.end(), 0.0);
  const double qc[3] = { 0.7, 1.3, 0.2 };
  std::vector<double> q(3 * mesh.GetNumberOfPoints(), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    for (int c = 0; c < 3; ++c)
    {
      q[3 * i + c] = qc[c];
    }
  }
  FiniteElement fem;
  DiffusionSystem system;
  fem.Assemble(mesh, material, q, system);
  const auto x = Solve(system, 1e-13);
  const double fdr = FdrOf(eta);
  for (int c = 0; c < 3; ++c)
  {
    const double expected = 4.0 * qc[c] / (1.0 - fdr);
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      ASSERT_NEAR(x[c][i], expected, 1e-8 * expected) << "channel " << c << " point " << i;
    }
  }
  std::vector<double> fluence;
  fem.ToPointFluence(mesh, system, x, fluence);
  ASSERT_EQ(fluence.size(), 3u * mesh.GetNumberOfPoints());
  EXPECT_EQ(fluence[3 * 7 + 2], x[2][7]);
}

TEST(FiniteElement, ParallelEqualsSerial)
{
  const TetMesh mesh = Build(CubeMesh(16, 3.0, 0.25, 4));
  ASSERT_GT(mesh.GetScatterSchedule().ColourOffsets[1], 4); // several chunks per colour
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 41);
  const std::vector<double> q = RandomIrradiance(mesh, 42);
  FiniteElement fem;
  DiffusionSystem serial, parallel;
  fem.SetNumberOfThreads(1);
  fem.Assemble(mesh, material, q, serial);
  fem.SetNumberOfThreads(2);
  EXPECT_EQ(fem.GetNumberOfThreads(), 2);
  fem.Assemble(mesh, material, q, parallel);
  ASSERT_EQ(serial.ColumnIndices, parallel.ColumnIndices);
  for (int c = 0; c < 3; ++c)
  {
    ASSERT_EQ(serial.Values[c].size(), parallel.Values[c].size());
    for (size_t k = 0; k < serial.Values[c].size(); ++k)
    {
      ASSERT_EQ(serial.Values[c][k], parallel.Values[c][k]) << "channel " << c << " entry " << k;
    }
    for (int i = 0; i < serial.NumberOfUnknowns; ++i)
    {
      ASSERT_EQ(serial.RightHandSide[c][i], parallel.RightHandSide[c][i]);
    }
  }
  // Re-assembling into a used system gives the same values again.
  fem.Assemble(mesh, material, q, parallel);
  EXPECT_EQ(serial.Values[1], parallel.Values[1]);
  EXPECT_EQ(serial.RightHandSide[2], parallel.RightHandSide[2]);
}

// ---- manufactured solution ----

/// How the manufactured Robin data q, smooth on each box face but
/// discontinuous across the box edges (the faces' normals differ), becomes
/// the per-vertex irradiance the solvers take.
enum class BoundaryData
{
  /// q_i = mean of the faces' values at x_i weighted by the triangle areas
  /// around i (TestDiscreteDivergence.cxx): with the lumped load S_i q_i / 3
  /// this is exactly the lumped quadrature of the per-face q.
  VertexMean,
  /// q = the L2 projection of the per-face q onto continuous P1 functions on
  /// the boundary (solve with the consistent boundary mass matrix): with the
  /// consistent load this gives exactly the Galerkin load int q_face beta_i.
  L2Projection
};

/// Per-vertex irradiance (3 per point) from Robin data given per box face:
/// faceQ(c, x, n) is q of channel c at x on the face with outward normal n
/// (the boundary of the mesh must be an axis-aligned box).
std::vector<double> IrradianceFromFaceData(const TetMesh& mesh,
  BoundaryData data,
  const std::function<double(int, const Eigen::Vector3d&, const Eigen::Vector3d&)>& faceQ)
{
  const int n = mesh.GetNumberOfPoints();
  std::array<Eigen::VectorXd, 3> sums;
  for (auto& v : sums)
  {
    v.setZero(n);
  }
  std::vector<double> weight(n, 0.0);
  std::vector<Eigen::Triplet<double>> boundaryMass;
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    const int* tri = &mesh.GetBoundaryTriangles()[3 * f];
    const Eigen::Vector3d p0(mesh.GetPoint(tri[0])), p1(mesh.GetPoint(tri[1])),
      p2(mesh.GetPoint(tri[2]));
    Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
    const double area = 0.5 * normal.norm();
    // The exact face normal: the axis the triangle is normal to, signed.
    Eigen::Index axis;
    normal.cwiseAbs().maxCoeff(&axis);
    const Eigen::Vector3d faceNormal = Eigen::Vector3d::Unit(axis) * (normal[axis] > 0 ? 1 : -1);
    std::array<std::array<double, 3>, 3> qFace; // [vertex m][channel c]
    for (int m = 0; m < 3; ++m)
    {
      const Eigen::Vector3d x(mesh.GetPoint(tri[m]));
      for (int c = 0; c < 3; ++c)
      {
        qFace[m][c] = faceQ(c, x, faceNormal);
      }
      weight[tri[m]] += area;
    }
    for (int j = 0; j < 3; ++j)
    {
      for (int c = 0; c < 3; ++c)
      {
        // VertexMean: area-weighted sums. L2Projection: int_f q_face beta_j
        // with the face's own q interpolated linearly on the triangle.
        sums[c][tri[j]] += data == BoundaryData::VertexMean
          ? area * qFace[j][c]
          : area / 12.0 * (qFace[0][c] + qFace[1][c] + qFace[2][c] + qFace[j][c]);
      }
      for (int k = 0; k < 3; ++k)
      {
        boundaryMass.emplace_back(tri[j], tri[k], area / 12.0 * (j == k ? 2.0 : 1.0));
      }
    }
  }
  for (int i = 0; i < n; ++i)
  {
    if (!mesh.IsBoundaryPoint(i))
    {
      boundaryMass.emplace_back(i, i, 1.0); // interior rows: q = 0
    }
  }
  std::vector<double> q(3 * n, 0.0);
  ColMatrix mass(n, n);
  mass.setFromTriplets(boundaryMass.begin(), boundaryMass.end());
  Eigen::SimplicialLLT<ColMatrix> llt;
  if (data == BoundaryData::L2Projection)
  {
    llt.compute(mass);
    EXPECT_EQ(llt.info(), Eigen::Success);
  }
  for (int c = 0; c < 3; ++c)
  {
    const Eigen::VectorXd projected =
      data == BoundaryData::L2Projection ? Eigen::VectorXd(llt.solve(sums[c])) : sums[c];
    for (int i : mesh.GetBoundaryPoints())
    {
      q[3 * i + c] = data == BoundaryData::VertexMean ? sums[c][i] / weight[i] : projected[i];
      EXPECT_GE(q[3 * i + c], 0.0); // physical data: the setup must keep q >= 0
    }
  }
  return q;
}

TEST(FiniteElement, ReproducesLinearSolutionsExactly)
{
  // Patch test. With mu_a = 0 and uniform kappa, phi = c0 + g.x solves the
  // diffusion equation and its Robin data q = (1 - Fdr)/4 (phi + 2 A kappa
  // g.n) is linear on each box face. phi lies in the P1 space, and the
  // L2-projected q gives the exact Galerkin load, so the consistent Galerkin
  // solution is phi itself at every vertex of any mesh (here jittered, with
  // different kappa per channel). (The divergence scheme with the
  // vertex-mean q is exact here too: phi cancels from its lumped boundary
  // rows, leaving the exact per-face fluxes.)
  const TetMesh mesh = Build(CubeMesh(6, 3.0, 0.3, 81));
  const double eta = 1.4, fdr = FdrOf(eta), bigA = AOf(eta);
  const double muA[3] = { 0.0, 0.0, 0.0 };
  const double sigma[3] = { 0.5, 1.5, 4.0 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigma, eta);
  const Eigen::Vector3d g(0.3, -0.2, 0.5);
  const double c0 = 5.0;
  auto faceQ = [&](int c, const Eigen::Vector3d& x, const Eigen::Vector3d& normal)
  {
    const double kappa = 1.0 / (3.0 * sigma[c]);
    return (1.0 - fdr) / 4.0 * (c0 + g.dot(x) + 2.0 * bigA * kappa * g.dot(normal));
  };
  FiniteElement fem;
  DiffusionSystem system;
  fem.Assemble(mesh, material, IrradianceFromFaceData(mesh, BoundaryData::L2Projection, faceQ),
    system);
  const auto x = Solve(system, 1e-14);
  for (int c = 0; c < 3; ++c)
  {
    double worst = 0.0;
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      const double exact = c0 + g.dot(Eigen::Vector3d(mesh.GetPoint(i)));
      worst = std::max(worst, std::abs(x[c][i] - exact) / exact);
    }
    EXPECT_LT(worst, 1e-10) << "channel " << c;
  }
}

/// Max and RMS relative vertex error of the discrete solution against
/// phi = exp(a.x) on the cube [0, L]^3 with n cells per side, |a|^2 =
/// mu_a / kappa (so div(kappa grad phi) - mu_a phi = 0), as in
/// TestDiscreteDivergence.cxx; q = (1 - Fdr)/4 (phi + 2 A kappa dphi/dn) with
/// the exact face normals.
ConvergenceErrors ManufacturedErrors(Discretization& discretization,
  BoundaryData data,
  int cells,
  double length,
  const double muA[3],
  const double sigma[3],
  const Eigen::Vector3d& direction,
  double eta)
{
  const TetMesh mesh = Build(CubeMesh(cells, length));
  const int n = mesh.GetNumberOfPoints();
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigma, eta);
  const double fdr = FdrOf(eta), bigA = AOf(eta);
  const ExponentialSolution exact(muA, sigma, direction);
  auto faceQ = [&](int c, const Eigen::Vector3d& x, const Eigen::Vector3d& normal)
  { return exact.RobinData(c, x, normal, fdr, bigA); };
  DiffusionSystem system;
  discretization.Assemble(mesh, material, IrradianceFromFaceData(mesh, data, faceQ), system);
  const auto x = Solve(system, 1e-12);
  ConvergenceErrors errors;
  for (int c = 0; c < 3; ++c)
  {
    RelativeErrors(
      n, [&](int i) { return x[c][i]; },
      [&](int i) { return exact(c, Eigen::Vector3d(mesh.GetPoint(i))); }, errors.Max[c],
      errors.Rms[c]);
  }
  return errors;
}

TEST(FiniteElement, ConvergenceToManufacturedSolution)
{
  // The channels of TestDiscreteDivergence: skin1 red, marble red, apple blue
  // (absorption lengths 3.7, 8.5 and 1.9 mm) on a 10 mm cube. The order is
  // asserted with the L2-projected q (the data the consistent load needs).
  // With the vertex-mean q the per-face Robin data, discontinuous across the
  // box edges, is interpolated across them: an O(h) error next to the edges
  // (max order about 1, 0.5-0.8 for the weakly absorbing channel) while the
  // RMS order stays a little under 2; printed for the record (n = 8, 16),
  // with the divergence error at the finest level.
  const ChannelMaterials channels = ConvergenceChannels();
  const double* muA = channels.MuA;
  const double* sigma = channels.Sigma;
  const Eigen::Vector3d direction(1.0, 2.0, 3.0);
  const int levels[] = { 4, 8, 16, 32 };
  const size_t f = 3;
  FiniteElement fem;
  DiscreteDivergence divergence;
  std::vector<ConvergenceErrors> projected, mean;
  for (int n : levels)
  {
    projected.push_back(
      ManufacturedErrors(fem, BoundaryData::L2Projection, n, 10.0, muA, sigma, direction, 1.3));
  }
  // For the record (cheap levels): the vertex-mean q of TestDiscreteDivergence.
  for (size_t l = f - 2; l < f; ++l)
  {
    mean.push_back(ManufacturedErrors(
      fem, BoundaryData::VertexMean, levels[l], 10.0, muA, sigma, direction, 1.3));
  }
  const ConvergenceErrors divergenceFinest = ManufacturedErrors(
    divergence, BoundaryData::VertexMean, levels[f], 10.0, muA, sigma, direction, 1.3);

  std::ostringstream report;
  report << std::setprecision(3);
  auto table = [&](const char* title, const std::vector<ConvergenceErrors>& errors, int c)
  {
    report << "  " << title << ":";
    const size_t first = errors.size() == projected.size() ? 0 : f - 2; // level of errors[0]
    WriteRefinementRow(report, levels + first, errors, c);
    report << "\n";
  };
  for (int c = 0; c < 3; ++c)
  {
    report << "channel " << c << ":\n";
    table("fem, L2-projected q", projected, c);
    table("fem, vertex-mean q ", mean, c);
    report << "  n=" << levels[f] << " divergence (vertex-mean q): max " << divergenceFinest.Max[c]
           << " rms " << divergenceFinest.Rms[c] << "\n";
    const double rmsOrder = ConvergenceOrder(projected[f - 1].Rms[c], projected[f].Rms[c]);
    const double maxOrder = ConvergenceOrder(projected[f - 1].Max[c], projected[f].Max[c]);
    ::testing::Test::RecordProperty(
      "fem_rms_order_channel_" + std::to_string(c), std::to_string(rmsOrder));
    ::testing::Test::RecordProperty(
      "fem_max_order_channel_" + std::to_string(c), std::to_string(maxOrder));
    EXPECT_GE(rmsOrder, 1.8) << "channel " << c;
    EXPECT_LT(projected[f].Rms[c], projected[0].Rms[c]);
    EXPECT_LT(mean[1].Rms[c], mean[0].Rms[c]);
  }
  std::cout << "[ convergence ] FEM relative vertex errors, phi = exp(a.x):\n" << report.str();
}

// ---- through the common interface ----

TEST(FiniteElement, FactoryAndVertexSolver)
{
  const std::vector<std::string> names = GetDiffusionSolverNames();
  ASSERT_GE(names.size(), 2u);
  EXPECT_EQ(names[0], "divergence");
  EXPECT_EQ(names[1], "fem");
  std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver("FEM");
  ASSERT_TRUE(solver);
  EXPECT_EQ(solver->GetName(), "fem");

  const TetMesh mesh = Build(CubeMesh(6, 2.0, 0.2, 71));
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 72);
  const std::vector<double> q = RandomIrradiance(mesh, 73);
  DiffusionProblem problem = MakeProblem(mesh, material, q);
  solver->SetRelTol(1e-12);
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(solver->Solve(problem, fluence, report));
  EXPECT_EQ(report.Solver, "fem");
  EXPECT_EQ(report.NumberOfUnknowns, mesh.GetNumberOfPoints());
  ASSERT_EQ(fluence.size(), 3u * mesh.GetNumberOfPoints());
  // The same system assembled directly, solved by Cholesky.
  FiniteElement fem;
  DiffusionSystem system;
  fem.Assemble(mesh, material, q, system);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(report.Converged[c]);
    Eigen::SimplicialLLT<ColMatrix> llt(ToEigen(system, c));
    const Eigen::VectorXd x = llt.solve(system.RightHandSide[c]);
    double worst = 0.0;
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      worst = std::max(worst, std::abs(fluence[3 * i + c] - x[i]));
    }
    EXPECT_LT(worst, 1e-8 * x.lpNorm<Eigen::Infinity>()) << "channel " << c;
  }
}

// ---- input checks ----

TEST(FiniteElementErrors, InvalidInputThrows)
{
  const TetMesh mesh = Build(CubeMesh(3, 1.0));
  const OpticalProperties good = RandomMaterial(mesh.GetNumberOfTets(), 7);
  const std::vector<double> q = RandomIrradiance(mesh, 8);
  FiniteElement fem;
  DiffusionSystem system;
  auto assemble = [&](const OpticalProperties& m, const std::vector<double>& irradiance)
  { return ErrorMessage([&] { fem.Assemble(mesh, m, irradiance, system); }); };
  EXPECT_EQ(assemble(good, q), "");

  OpticalProperties bad = good;
  bad.AbsorptionCoefficient[3 * 12 + 1] = -0.5;
  std::string message = assemble(bad, q);
  EXPECT_TRUE(Contains(message, "AbsorptionCoefficient of tet 12, channel G is -0.5")) << message;

  bad = good;
  bad.ReducedScatteringCoefficient[3 * 40 + 2] = std::numeric_limits<double>::quiet_NaN();
  message = assemble(bad, q);
  EXPECT_TRUE(Contains(message, "ReducedScatteringCoefficient of tet 40, channel B")) << message;

  bad = good;
  bad.RefractiveIndex[9] = -1.0;
  message = assemble(bad, q);
  EXPECT_TRUE(Contains(message, "RefractiveIndex of tet 9")) << message;

  bad = good;
  bad.RefractiveIndex.pop_back();
  message = assemble(bad, q);
  EXPECT_TRUE(Contains(message, "RefractiveIndex has")) << message;

  std::vector<double> badQ = q;
  badQ[3 * 5 + 2] = std::numeric_limits<double>::infinity();
  message = assemble(good, badQ);
  EXPECT_TRUE(Contains(message, "Irradiance of point 5, channel B")) << message;
  badQ = q;
  badQ.resize(7);
  message = assemble(good, badQ);
  EXPECT_TRUE(Contains(message, "Irradiance has 7 values")) << message;

  const TetMesh empty;
  message = ErrorMessage([&] { fem.Assemble(empty, OpticalProperties(), {}, system); });
  EXPECT_TRUE(Contains(message, "no tetrahedra")) << message;

  // Solution of the wrong size.
  fem.Assemble(mesh, good, q, system);
  std::array<Eigen::VectorXd, 3> x;
  for (auto& v : x)
  {
    v = Eigen::VectorXd::Zero(mesh.GetNumberOfPoints());
  }
  x[1].resize(3);
  std::vector<double> fluence;
  message = ErrorMessage([&] { fem.ToPointFluence(mesh, system, x, fluence); });
  EXPECT_TRUE(Contains(message, "channel G has 3 values")) << message;

  // Through the common interface: a missing irradiance.
  std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver("fem");
  DiffusionProblem problem = MakeProblem(mesh, good);
  SolverReport report;
  message = ErrorMessage([&] { solver->Solve(problem, fluence, report); });
  EXPECT_TRUE(Contains(message, "irradiance")) << message;
}

TEST(FiniteElement, PointsUsedByNoTetGetIdentityRows)
{
  MeshData data = CubeMesh(2, 1.0);
  data.Points.insert(data.Points.end(), { 3.0, 3.0, 3.0 });
  const TetMesh mesh = Build(data);
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 9);
  std::vector<double> q = RandomIrradiance(mesh, 10);
  const int orphan = mesh.GetNumberOfPoints() - 1;
  q[3 * orphan] = 5.0;
  FiniteElement fem;
  DiffusionSystem system;
  fem.Assemble(mesh, material, q, system);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(system.Values[c][mesh.GetDiagonalPositions()[orphan]], 1.0);
    EXPECT_EQ(system.RightHandSide[c][orphan], 0.0);
    Eigen::SimplicialLLT<ColMatrix> llt(ToEigen(system, c));
    EXPECT_EQ(llt.info(), Eigen::Success);
  }
}

// ---- divergence vs FEM on the bunny (TransCut Sec. 6.2) ----

/// Minimum dihedral angle of tet t (degrees).
double MinDihedralAngle(const TetMesh& mesh, int t)
{
  const int* tv = mesh.GetTet(t);
  Eigen::Vector3d p[4], n[4];
  for (int a = 0; a < 4; ++a)
  {
    p[a] = Eigen::Vector3d(mesh.GetPoint(tv[a]));
  }
  for (int a = 0; a < 4; ++a)
  {
    const Eigen::Vector3d& o = p[(a + 1) % 4];
    n[a] = (p[(a + 2) % 4] - o).cross(p[(a + 3) % 4] - o).normalized();
    if (n[a].dot(p[a] - o) > 0.0)
    {
      n[a] = -n[a]; // outward
    }
  }
  double smallest = 180.0;
  for (int a = 0; a < 4; ++a)
  {
    for (int b = a + 1; b < 4; ++b)
    {
      const double cosine = std::max(-1.0, std::min(1.0, n[a].dot(n[b])));
      smallest = std::min(smallest, 180.0 - std::acos(cosine) * 180.0 / 3.14159265358979323846);
    }
  }
  return smallest;
}

/// Max and RMS over the boundary points of |phi_div - phi_fem| / phi_fem.
struct BunnyDifference
{
  std::array<double, 3> Max{}, Rms{};
  std::array<int, 3> WorstPoint{};
};

BunnyDifference CompareOnBunny(const TetMesh& mesh,
  const OpticalProperties& material,
  const std::vector<LightSource>& lights,
  double uniformIrradiance,
  std::vector<double>& q)
{
  EXPECT_TRUE(ComputeBoundaryIrradiance(mesh,
    PointRefractiveIndex(mesh, material.RefractiveIndex),
    lights,
    uniformIrradiance,
    0,
    false,
    q));
  DiffusionProblem problem = MakeProblem(mesh, material, q);
  std::vector<double> phiDiv, phiFem;
  SolverReport divReport, femReport;
  std::unique_ptr<DiffusionSolver> div = CreateDiffusionSolver("divergence");
  std::unique_ptr<DiffusionSolver> fem = CreateDiffusionSolver("fem");
  for (DiffusionSolver* s : { div.get(), fem.get() })
  {
    s->SetRelTol(1e-10);
    s->SetMaxIter(20000);
  }
  EXPECT_TRUE(div->Solve(problem, phiDiv, divReport));
  EXPECT_TRUE(fem->Solve(problem, phiFem, femReport));
  BunnyDifference d;
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(divReport.Converged[c]);
    EXPECT_TRUE(femReport.Converged[c]);
    double sum2 = 0.0;
    for (int i : mesh.GetBoundaryPoints())
    {
      const double rel = std::abs(phiDiv[3 * i + c] - phiFem[3 * i + c]) / phiFem[3 * i + c];
      sum2 += rel * rel;
      if (rel > d.Max[c])
      {
        d.Max[c] = rel;
        d.WorstPoint[c] = i;
      }
    }
    d.Rms[c] = std::sqrt(sum2 / mesh.GetBoundaryPoints().size());
  }
  return d;
}

TetMesh BunnyMesh(const std::string& switches)
{
  std::vector<double> surfacePoints;
  std::vector<int> triangles;
  ReadPly(std::string(TRANSLUCENCY_DATA_DIR) + "/bunny.ply", surfacePoints, triangles);
  const MeshData raw = Tetrahedralize(surfacePoints, triangles, switches);
  std::vector<int> pointOrder, tetOrder;
  TetMesh::ComputeSpatialOrder(raw.Points, raw.Tets, pointOrder, tetOrder);
  return Build(translucency::testing::Permute(raw, pointOrder, tetOrder));
}

TEST(FiniteElement, DivergenceMatchesFemOnTheBunny)
{
  // TransCut Sec. 6.2 / Fig. 4: the discrete-divergence solution is within
  // about 2 % (max) of Arbree et al.'s FEM on a TetGen mesh of a real model.
  //
  // What we find (marble, no shadows): under uniform light (smooth q) the max
  // boundary difference is a few tenths of a percent, and that is asserted
  // against the paper's 2 %. Under a directional light the max is ~20 % at
  // ~70k tets, at boundary points on or next to the terminator, where q =
  // max(0, n.l) has a kink that the surface mesh does not resolve (the
  // consistent and the lumped load spread it differently), and in dim regions
  // far from the light; the worst points' tets are well shaped (min dihedral
  // angles 15-30 degrees) and points next to slivers are not the worst. Both
  // solvers are consistent second-order discretisations of the same problem,
  // so what is asserted for the directional light is that the RMS difference
  // shrinks under mesh refinement at least like the surface mesh size h
  // (h^2 ~ boundary area / number of boundary points).
  const auto start = std::chrono::steady_clock::now();
  const MaterialPreset& marble = FindMaterialPreset("marble");
  LightSource light;
  light.Type = LightSource::Kind::Directional;
  light.Direction = { -0.3, -1.0, -0.5 }; // from above (the bunny's +y), front
  light.Power = { 1.0, 1.0, 1.0 };

  std::ostringstream report;
  report << std::setprecision(3);
  std::array<BunnyDifference, 2> directional;
  std::array<double, 2> boundaryPoints{};
  const char* const switches[2] = { "pq1.414a1zQ", "pq1.414a0.1zQ" };
  for (int level = 0; level < 2; ++level)
  {
    const TetMesh mesh = BunnyMesh(switches[level]);
    const OpticalProperties material = OpticalProperties::Uniform(mesh.GetNumberOfTets(),
      marble.Absorption, marble.ReducedScattering, marble.RefractiveIndex);
    boundaryPoints[level] = static_cast<double>(mesh.GetBoundaryPoints().size());
    report << "[ bunny ] TetGen -" << switches[level] << ": " << mesh.GetNumberOfTets()
           << " tets, " << mesh.GetBoundaryPoints().size()
           << " boundary points; |phi_div - phi_fem| / phi_fem at the boundary, R G B:\n";
    std::vector<double> q;
    if (level == 0)
    {
      const BunnyDifference uniform = CompareOnBunny(mesh, material, {}, 1.0, q);
      report << "  uniform light:     max";
      for (int c = 0; c < 3; ++c)
      {
        report << " " << 100.0 * uniform.Max[c] << " %";
        EXPECT_LE(uniform.Max[c], 0.02) << "channel " << c; // TransCut Sec. 6.2
        EXPECT_GT(uniform.Max[c], 0.0);                      // two different matrices
      }
      report << "; rms";
      for (int c = 0; c < 3; ++c)
      {
        report << " " << 100.0 * uniform.Rms[c] << " %";
      }
      report << "\n";
    }
    directional[level] = CompareOnBunny(mesh, material, { light }, 0.0, q);
    const BunnyDifference& d = directional[level];
    report << "  directional light: max";
    for (int c = 0; c < 3; ++c)
    {
      report << " " << 100.0 * d.Max[c] << " %";
    }
    report << "; rms";
    for (int c = 0; c < 3; ++c)
    {
      report << " " << 100.0 * d.Rms[c] << " %";
    }
    // Where the largest difference is: its irradiance, its lit neighbours,
    // the shape of its tets.
    const int worst = d.WorstPoint[0];
    const double* x = mesh.GetPoint(worst);
    int lit = 0, neighbours = 0;
    for (int k = mesh.GetRowOffsets()[worst]; k < mesh.GetRowOffsets()[worst + 1]; ++k)
    {
      const int j = mesh.GetColumnIndices()[k];
      if (j != worst && mesh.IsBoundaryPoint(j))
      {
        ++neighbours;
        lit += q[3 * j] > 0.0;
      }
    }
    double dihedral = 180.0;
    for (int k = mesh.GetPointTetOffsets()[worst]; k < mesh.GetPointTetOffsets()[worst + 1]; ++k)
    {
      dihedral = std::min(dihedral, MinDihedralAngle(mesh, mesh.GetPointTets()[k]));
    }
    report << "\n    R max at (" << x[0] << ", " << x[1] << ", " << x[2] << "): q " << q[3 * worst]
           << ", " << lit << " of " << neighbours
           << " boundary neighbours lit, smallest dihedral angle of its tets " << dihedral
           << " deg\n";
  }
  // RMS difference at least first order in the surface mesh size.
  const double hRatio = std::sqrt(boundaryPoints[1] / boundaryPoints[0]);
  ASSERT_GT(hRatio, 1.3); // a real refinement
  for (int c = 0; c < 3; ++c)
  {
    const double ratio = directional[0].Rms[c] / directional[1].Rms[c];
    report << "  channel " << c << ": rms ratio " << ratio << " for h ratio " << hRatio
           << " (order " << std::log(ratio) / std::log(hRatio) << ")\n";
    // (The max is a pointwise value on the terminator: it need not fall
    // monotonically, e.g. -a0.2 gives a larger R max than -a1.)
    EXPECT_GE(ratio, hRatio) << "channel " << c;
  }
  report << "  total "
         << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
         << " s\n";
  std::cout << report.str();
}

} // namespace
