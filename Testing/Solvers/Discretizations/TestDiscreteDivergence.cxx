// The discrete-divergence assembly (TransCut Sec. 3) against an independent
// P1 finite-element assembly, exact discrete solutions, a conservation
// identity and a manufactured solution with a measured convergence order.

#include "ConjugateGradient.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "Fresnel.h"
#include "Radiance.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TestReferenceAssembly.h"
#include "TetMesh.h"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <cmath>
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

/// Random heterogeneous material: every tet, channel and index different.
OpticalProperties RandomMaterial(int numTets, std::uint64_t seed, bool absorbing = true)
{
  std::mt19937_64 rng(seed);
  OpticalProperties m;
  for (int t = 0; t < numTets; ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      m.AbsorptionCoefficient.push_back(absorbing ? 0.01 + 0.5 * Uniform01(rng) : 0.0);
      m.ReducedScatteringCoefficient.push_back(0.2 + 3.0 * Uniform01(rng));
    }
    m.RefractiveIndex.push_back(1.2 + 0.3 * Uniform01(rng));
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

/// Refractive index seen by each boundary point, recomputed here from the
/// boundary triangles (area-weighted mean over the owning tets).
std::vector<double> BoundaryEta(const TetMesh& mesh, const std::vector<double>& tetEta)
{
  std::vector<double> weighted(mesh.GetNumberOfPoints(), 0.0), area(mesh.GetNumberOfPoints(), 0.0);
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    const int* tri = &mesh.GetBoundaryTriangles()[3 * f];
    const Eigen::Vector3d p0(mesh.GetPoint(tri[0])), p1(mesh.GetPoint(tri[1])),
      p2(mesh.GetPoint(tri[2]));
    const double a = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    for (int m = 0; m < 3; ++m)
    {
      weighted[tri[m]] += a * tetEta[mesh.GetBoundaryTriangleTets()[f]];
      area[tri[m]] += a;
    }
  }
  for (size_t i = 0; i < weighted.size(); ++i)
  {
    weighted[i] = area[i] > 0.0 ? weighted[i] / area[i] : 0.0;
  }
  return weighted;
}

/// Independent P1 Galerkin assembly with lumped mass and lumped boundary
/// terms: K_ab = kappa_t V_t grad(beta_a).grad(beta_b) with gradients from
/// the inverse of the 3x3 edge matrix, + V_t mu_t / 4 on each vertex, +
/// S_i/(6A) on boundary diagonals; load (S_i/3) (2/(A(1 - Fdr))) q_i.
struct FemReference
{
  std::array<ColMatrix, 3> Matrix;
  std::array<Eigen::VectorXd, 3> Load;
};

FemReference AssembleFem(const TetMesh& mesh,
  const OpticalProperties& material,
  const std::vector<double>& q)
{
  const int n = mesh.GetNumberOfPoints();
  std::array<std::vector<Eigen::Triplet<double>>, 3> triplets;
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
          triplets[c].emplace_back(tv[a], tv[b], kappa * volume * grad[a].dot(grad[b]));
        }
        triplets[c].emplace_back(tv[a], tv[a], volume * mu / 4.0);
      }
    }
  }
  const std::vector<double> eta = BoundaryEta(mesh, material.RefractiveIndex);
  FemReference fem;
  for (int c = 0; c < 3; ++c)
  {
    fem.Load[c].setZero(n);
  }
  for (int i : mesh.GetBoundaryPoints())
  {
    const double fdr = -1.440 / (eta[i] * eta[i]) + 0.710 / eta[i] + 0.668 + 0.0636 * eta[i];
    const double a = (1.0 + fdr) / (1.0 - fdr);
    const double s = mesh.GetBoundaryAreas()[i];
    for (int c = 0; c < 3; ++c)
    {
      triplets[c].emplace_back(i, i, s / (6.0 * a));
      fem.Load[c][i] = s / 3.0 * 2.0 / (a * (1.0 - fdr)) * q[3 * i + c];
    }
  }
  for (int c = 0; c < 3; ++c)
  {
    fem.Matrix[c].resize(n, n);
    fem.Matrix[c].setFromTriplets(triplets[c].begin(), triplets[c].end());
  }
  return fem;
}

class AssemblyTest : public ::testing::TestWithParam<int> // mesh seed
{
};

TEST_P(AssemblyTest, MatrixIsFourTimesLumpedP1Fem)
{
  const MeshData data = CubeMesh(5, 2.0, 0.25, GetParam());
  const TetMesh mesh = Build(data);
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 100 + GetParam());
  const std::vector<double> q = RandomIrradiance(mesh, 200 + GetParam());
  DiscreteDivergence divergence;
  DiffusionSystem system;
  divergence.Assemble(mesh, material, q, system);
  const FemReference fem = AssembleFem(mesh, material, q);

  for (int c = 0; c < 3; ++c)
  {
    const ColMatrix m = ToEigen(system, c);
    const ColMatrix reference = 4.0 * fem.Matrix[c];
    // Entry by entry, relative to the largest entry of the row (the
    // diagonal entries are sums with cancellation).
    const ColMatrix difference = m - reference;
    Eigen::VectorXd rowScale = Eigen::VectorXd::Zero(m.rows());
    for (int k = 0; k < reference.outerSize(); ++k)
    {
      for (ColMatrix::InnerIterator it(reference, k); it; ++it)
      {
        rowScale[it.row()] = std::max(rowScale[it.row()], std::abs(it.value()));
      }
    }
    double worst = 0.0;
    for (int k = 0; k < difference.outerSize(); ++k)
    {
      for (ColMatrix::InnerIterator it(difference, k); it; ++it)
      {
        worst = std::max(worst, std::abs(it.value()) / rowScale[it.row()]);
      }
    }
    EXPECT_LT(worst, 1e-12) << "channel " << c;
    EXPECT_EQ(m.nonZeros(), reference.nonZeros());

    // Exactly symmetric (both triangles get the same sums in the same order).
    const ColMatrix transposed = m.transpose();
    EXPECT_EQ((m - transposed).norm(), 0.0) << "channel " << c;

    // Positive definite: Cholesky succeeds.
    Eigen::SimplicialLLT<ColMatrix> llt(m);
    EXPECT_EQ(llt.info(), Eigen::Success) << "channel " << c;

    // Right-hand side: 4 x the lumped load, TransCut eq. 12.
    const Eigen::VectorXd& b = system.RightHandSide[c];
    EXPECT_LT((b - 4.0 * fem.Load[c]).lpNorm<Eigen::Infinity>(),
      1e-13 * fem.Load[c].lpNorm<Eigen::Infinity>())
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

INSTANTIATE_TEST_SUITE_P(RandomMeshes, AssemblyTest, ::testing::Values(1, 2, 3));

TEST(DiscreteDivergence, ParallelEqualsSerial)
{
  const MeshData data = CubeMesh(16, 3.0, 0.25, 4);
  const TetMesh mesh = Build(data);
  ASSERT_GT(mesh.GetScatterSchedule().ColourOffsets[1], 4); // several chunks per colour
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 41);
  const std::vector<double> q = RandomIrradiance(mesh, 42);
  DiscreteDivergence divergence;
  DiffusionSystem serial, parallel;
  divergence.SetNumberOfThreads(1);
  divergence.Assemble(mesh, material, q, serial);
  divergence.SetNumberOfThreads(2);
  divergence.Assemble(mesh, material, q, parallel);
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
  divergence.Assemble(mesh, material, q, parallel);
  EXPECT_EQ(serial.Values[1], parallel.Values[1]);
}

TEST(DiscreteDivergence, ConstantSolutionWithoutAbsorption)
{
  // mu_a = 0, uniform kappa and q: phi = 4 q / (1 - Fdr) solves the discrete
  // system exactly (stiffness rows sum to 0; boundary rows balance).
  const MeshData data = CubeMesh(8, 4.0, 0.25, 5);
  const TetMesh mesh = Build(data);
  const double muA[3] = { 0.0, 0.0, 0.0 };
  const double sigma[3] = { 1.0, 2.0, 0.5 };
  const double eta = 1.3;
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigma, eta);
  const double qc[3] = { 0.7, 1.3, 0.2 };
  std::vector<double> q(3 * mesh.GetNumberOfPoints(), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    for (int c = 0; c < 3; ++c)
    {
      q[3 * i + c] = qc[c];
    }
  }
  DiscreteDivergence divergence;
  DiffusionSystem system;
  divergence.Assemble(mesh, material, q, system);
  const auto x = Solve(system, 1e-13);
  const double fdr = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
  for (int c = 0; c < 3; ++c)
  {
    const double expected = 4.0 * qc[c] / (1.0 - fdr);
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      ASSERT_NEAR(x[c][i], expected, 1e-8 * expected) << "channel " << c << " point " << i;
    }
  }
  std::vector<double> fluence;
  divergence.ToPointFluence(mesh, system, x, fluence);
  ASSERT_EQ(fluence.size(), 3u * mesh.GetNumberOfPoints());
  EXPECT_EQ(fluence[3 * 7 + 2], x[2][7]);
}

TEST(DiscreteDivergence, EnergyBalanceWithoutAbsorption)
{
  // With mu_a = 0 the stiffness part has zero column sums (it is symmetric
  // with zero row sums), so summing all rows of M phi = b leaves
  //   sum_i 2 S_i phi_i / (3 A_i) = sum_i b_i = sum_i 8 S_i q_i / (3 A_i (1 - Fdr_i)),
  // i.e. for uniform eta: sum_i S_i phi_i = sum_i S_i 4 q_i / (1 - Fdr):
  // light in = light out. Heterogeneous kappa does not matter. For an
  // approximate phi the two sides differ by sum_i r_i (r = b - M phi), and
  // |sum_i r_i| <= sqrt(N) ||r||: that, with ||r|| <= tol ||b||, is the
  // tolerance.
  const MeshData data = CubeMesh(10, 5.0, 0.25, 6);
  const TetMesh mesh = Build(data);
  OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 61, false);
  std::fill(material.RefractiveIndex.begin(), material.RefractiveIndex.end(), 1.4);
  const std::vector<double> q = RandomIrradiance(mesh, 62);
  DiscreteDivergence divergence;
  DiffusionSystem system;
  divergence.Assemble(mesh, material, q, system);
  const double tol = 1e-10;
  const auto x = Solve(system, tol);
  const double fdr = Fresnel::DiffuseReflectance(1.4);
  const double a = Fresnel::MismatchA(1.4);
  const std::vector<double>& s = mesh.GetBoundaryAreas();
  const double n = mesh.GetNumberOfPoints();
  for (int c = 0; c < 3; ++c)
  {
    double out = 0.0, in = 0.0;
    for (int i : mesh.GetBoundaryPoints())
    {
      out += s[i] * x[c][i];
      in += s[i] * 4.0 * q[3 * i + c] / (1.0 - fdr);
    }
    const Eigen::VectorXd r = system.RightHandSide[c] - system.Matrix(c) * x[c];
    EXPECT_LE(r.norm(), 2.0 * tol * system.RightHandSide[c].norm());
    // out - in = (3A/2) * (-sum_i r_i) up to round-off.
    const double bound = 1.5 * a * std::sqrt(n) * r.norm() + 1e-12 * in;
    EXPECT_NEAR(out, in, bound) << "channel " << c;
    EXPECT_NEAR(out, in, 1e-7 * in) << "channel " << c;
  }
}

// ---- manufactured solution ----

/// Max and RMS relative vertex error of the discrete solution against
/// phi = exp(a.x) on the cube [0, L]^3 with n cells per side, for the
/// channel materials (mu_a, sigma_s'); |a|^2 = mu_a / kappa makes
/// div(kappa grad phi) - mu_a phi = 0.
ConvergenceErrors ManufacturedErrors(int cells,
  double length,
  const double muA[3],
  const double sigma[3],
  const Eigen::Vector3d& direction,
  double eta)
{
  const MeshData data = CubeMesh(cells, length);
  const TetMesh mesh = Build(data);
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigma, eta);
  const double fdr = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
  const double bigA = (1.0 + fdr) / (1.0 - fdr);
  const ExponentialSolution exact(muA, sigma, direction);

  // Robin data q = (1 - Fdr)/4 (phi + 2 A kappa dphi/dn) with the exact
  // outward normal of each box face. A vertex on an edge or corner belongs to
  // several faces whose q differ (different normals); the lumped boundary
  // term stands for the integral of q over the vertex's boundary Voronoi
  // cell, which spans those faces, so q_i is the mean of the faces' values
  // weighted by the area each face contributes around the vertex.
  std::vector<double> q(3 * mesh.GetNumberOfPoints(), 0.0);
  std::vector<double> weight(mesh.GetNumberOfPoints(), 0.0);
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    const int* tri = &mesh.GetBoundaryTriangles()[3 * f];
    const Eigen::Vector3d p0(mesh.GetPoint(tri[0])), p1(mesh.GetPoint(tri[1])),
      p2(mesh.GetPoint(tri[2]));
    Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
    const double area = 0.5 * normal.norm();
    // Exact face normal: the axis the triangle is normal to, signed.
    Eigen::Index axis;
    normal.cwiseAbs().maxCoeff(&axis);
    const Eigen::Vector3d faceNormal = Eigen::Vector3d::Unit(axis) * (normal[axis] > 0 ? 1 : -1);
    for (int m = 0; m < 3; ++m)
    {
      const Eigen::Vector3d x(mesh.GetPoint(tri[m]));
      for (int c = 0; c < 3; ++c)
      {
        q[3 * tri[m] + c] += area * exact.RobinData(c, x, faceNormal, fdr, bigA);
      }
      weight[tri[m]] += area;
    }
  }
  for (int i : mesh.GetBoundaryPoints())
  {
    for (int c = 0; c < 3; ++c)
    {
      q[3 * i + c] /= weight[i];
      EXPECT_GE(q[3 * i + c], 0.0); // physical data: the test setup must keep q >= 0
    }
  }

  DiscreteDivergence divergence;
  DiffusionSystem system;
  divergence.Assemble(mesh, material, q, system);
  const auto x = Solve(system, 1e-12);
  ConvergenceErrors errors;
  for (int c = 0; c < 3; ++c)
  {
    RelativeErrors(
      mesh.GetNumberOfPoints(), [&](int i) { return x[c][i]; },
      [&](int i) { return exact(c, Eigen::Vector3d(mesh.GetPoint(i))); }, errors.Max[c],
      errors.Rms[c]);
  }
  return errors;
}

TEST(DiscreteDivergence, ConvergenceToManufacturedSolution)
{
  // Three channels, three absorption lengths (1/|a|): skin1 red (3.7 mm),
  // marble red (8.5 mm) and apple blue (1.9 mm), on a 10 mm cube.
  const ChannelMaterials channels = ConvergenceChannels();
  const Eigen::Vector3d direction(1.0, 2.0, 3.0);
  const int levels[] = { 4, 8, 16, 32 };
  std::vector<ConvergenceErrors> errors;
  for (int n : levels)
  {
    errors.push_back(
      ManufacturedErrors(n, 10.0, channels.MuA, channels.Sigma, direction, 1.3));
  }
  std::ostringstream report;
  report << std::setprecision(3);
  for (int c = 0; c < 3; ++c)
  {
    report << "channel " << c << ":";
    WriteRefinementRow(report, levels, errors, c);
    report << "\n";
    const size_t f = errors.size() - 1;
    const double rmsOrder = ConvergenceOrder(errors[f - 1].Rms[c], errors[f].Rms[c]);
    const double maxOrder = ConvergenceOrder(errors[f - 1].Max[c], errors[f].Max[c]);
    ::testing::Test::RecordProperty(
      "rms_order_channel_" + std::to_string(c), std::to_string(rmsOrder));
    ::testing::Test::RecordProperty(
      "max_order_channel_" + std::to_string(c), std::to_string(maxOrder));
    EXPECT_GE(rmsOrder, 1.7) << "channel " << c;
    EXPECT_LT(errors[f].Rms[c], errors[0].Rms[c]);
  }
  std::cout << "[ convergence ] relative vertex errors, phi = exp(a.x):\n" << report.str();
}

TEST(DiscreteDivergence, PointRefractiveIndex)
{
  MeshData data = CubeMesh(4, 2.0, 0.25, 12);
  data.Points.insert(data.Points.end(), { 9.0, 9.0, 9.0 }); // used by no tet
  const TetMesh mesh = Build(data);
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 13);
  const std::vector<double> eta = PointRefractiveIndex(mesh, material.RefractiveIndex);
  const std::vector<double> boundary = BoundaryEta(mesh, material.RefractiveIndex);
  const std::vector<double> boundaryOnly =
    BoundaryPointRefractiveIndex(mesh, material.RefractiveIndex);
  ASSERT_EQ(eta.size(), static_cast<size_t>(mesh.GetNumberOfPoints()));
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    if (mesh.IsBoundaryPoint(i))
    {
      EXPECT_NEAR(eta[i], boundary[i], 1e-14) << "point " << i;
      EXPECT_EQ(boundaryOnly[i], eta[i]);
      continue;
    }
    EXPECT_EQ(boundaryOnly[i], 0.0);
    // Interior: mean over the tets containing the point.
    double sum = 0.0;
    int count = 0;
    for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
    {
      const int* tv = mesh.GetTet(t);
      if (tv[0] == i || tv[1] == i || tv[2] == i || tv[3] == i)
      {
        sum += material.RefractiveIndex[t];
        ++count;
      }
    }
    EXPECT_NEAR(eta[i], count ? sum / count : 1.0, 1e-14) << "point " << i;
  }
  EXPECT_EQ(eta.back(), 1.0);
  EXPECT_THROW(PointRefractiveIndex(mesh, std::vector<double>(3, 1.3)), Error);
}

// ---- input checks ----

TEST(DiscreteDivergenceErrors, MaterialAndIrradianceValidation)
{
  const TetMesh mesh = Build(CubeMesh(3, 1.0));
  const OpticalProperties good = RandomMaterial(mesh.GetNumberOfTets(), 7);
  const std::vector<double> q = RandomIrradiance(mesh, 8);
  DiscreteDivergence divergence;
  DiffusionSystem system;
  auto assemble = [&](const OpticalProperties& m, const std::vector<double>& irradiance)
  { return ErrorMessage([&] { divergence.Assemble(mesh, m, irradiance, system); }); };
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
  bad.RefractiveIndex[9] = 0.0;
  message = assemble(bad, q);
  EXPECT_TRUE(Contains(message, "RefractiveIndex of tet 9")) << message;

  // Infinities and NaN (the parallel pre-check compares against DBL_MAX).
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const struct
  {
    std::vector<double> OpticalProperties::*Array;
    size_t Index;
    double Value;
    const char* Named;
  } cases[] = {
    { &OpticalProperties::AbsorptionCoefficient, 3 * 21 + 0, inf, "AbsorptionCoefficient of tet 21, channel R" },
    { &OpticalProperties::ReducedScatteringCoefficient, 3 * 22 + 1, inf, "ReducedScatteringCoefficient of tet 22, channel G" },
    { &OpticalProperties::RefractiveIndex, 23, inf, "RefractiveIndex of tet 23" },
    { &OpticalProperties::RefractiveIndex, 24, nan, "RefractiveIndex of tet 24" },
  };
  for (const auto& bc : cases)
  {
    bad = good;
    (bad.*bc.Array)[bc.Index] = bc.Value;
    message = assemble(bad, q);
    EXPECT_TRUE(Contains(message, bc.Named)) << message;
  }
  // The largest finite values are valid.
  bad = good;
  bad.AbsorptionCoefficient[3 * 25 + 2] = std::numeric_limits<double>::max();
  EXPECT_EQ(assemble(bad, q), "");

  bad = good;
  bad.AbsorptionCoefficient[3 * 3] = 0.0;
  bad.ReducedScatteringCoefficient[3 * 3] = 0.0;
  message = assemble(bad, q);
  EXPECT_TRUE(Contains(message, "tet 3, channel R")) << message;

  bad = good;
  bad.AbsorptionCoefficient.pop_back();
  message = assemble(bad, q);
  EXPECT_TRUE(Contains(message, "AbsorptionCoefficient has")) << message;
  EXPECT_TRUE(Contains(message, std::to_string(mesh.GetNumberOfTets()) + " tets")) << message;

  std::vector<double> badQ = q;
  badQ[3 * 5 + 0] = -1.0;
  message = assemble(good, badQ);
  EXPECT_TRUE(Contains(message, "Irradiance of point 5, channel R")) << message;
  badQ = q;
  badQ[3 * 6 + 1] = std::numeric_limits<double>::quiet_NaN();
  message = assemble(good, badQ);
  EXPECT_TRUE(Contains(message, "Irradiance of point 6, channel G")) << message;
  badQ = q;
  badQ[3 * 7 + 2] = std::numeric_limits<double>::infinity();
  message = assemble(good, badQ);
  EXPECT_TRUE(Contains(message, "Irradiance of point 7, channel B")) << message;
  badQ = q;
  badQ.resize(7);
  message = assemble(good, badQ);
  EXPECT_TRUE(Contains(message, "Irradiance has 7 values")) << message;
}

TEST(DiscreteDivergence, PointsUsedByNoTetGetIdentityRows)
{
  MeshData data = CubeMesh(2, 1.0);
  data.Points.insert(data.Points.end(), { 3.0, 3.0, 3.0 });
  const TetMesh mesh = Build(data);
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 9);
  std::vector<double> q = RandomIrradiance(mesh, 10);
  const int orphan = mesh.GetNumberOfPoints() - 1;
  q[3 * orphan] = 5.0;
  DiscreteDivergence divergence;
  DiffusionSystem system;
  divergence.Assemble(mesh, material, q, system);
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(system.Values[c][mesh.GetDiagonalPositions()[orphan]], 1.0);
    EXPECT_EQ(system.RightHandSide[c][orphan], 0.0);
    Eigen::SimplicialLLT<ColMatrix> llt(ToEigen(system, c));
    EXPECT_EQ(llt.info(), Eigen::Success);
  }
}

TEST(MaterialPresets, TableValuesAndLookup)
{
  const MaterialPreset& marble = FindMaterialPreset("Marble");
  EXPECT_EQ(marble.Name, "marble");
  EXPECT_EQ(marble.ReducedScattering[1], 2.62);
  EXPECT_EQ(marble.Absorption[2], 0.0071);
  EXPECT_EQ(marble.RefractiveIndex, 1.3);
  EXPECT_EQ(FindMaterialPreset("KETCHUP").Absorption[1], 0.97);
  EXPECT_EQ(FindMaterialPreset("skin1").ReducedScattering[0], 0.74);
  EXPECT_EQ(FindMaterialPreset("wholemilk").ReducedScattering[2], 3.77);
  EXPECT_GE(GetMaterialPresets().size(), 12u);
  const std::string message = ErrorMessage([] { FindMaterialPreset("jade"); });
  EXPECT_TRUE(Contains(message, "jade")) << message;
  EXPECT_TRUE(Contains(message, "skin1")) << message;
  EXPECT_TRUE(Contains(message, "wholemilk")) << message;
  // Every preset is a valid material.
  for (const MaterialPreset& p : GetMaterialPresets())
  {
    EXPECT_NO_THROW(
      OpticalProperties::Uniform(2, p.Absorption, p.ReducedScattering, p.RefractiveIndex)
        .Validate(2))
      << p.Name;
  }
}

} // namespace
