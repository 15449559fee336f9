// The regular-grid solver (Polygrid, eq. 8-9, Sec. 5.3): the tet
// locator against brute force, an exact constant solution, a manufactured
// solution with measured convergence orders, the geometry of a grid-aligned
// block, BiCGSTAB against relaxation, multi-level initialisation, warm start,
// 1 vs 2 threads and input checks.

#include "DiffusionSolverFactory.h"
#include "Error.h"
#include "Fresnel.h"
#include "GridSolver.h"
#include "TestMeshes.h"
#include "TestProblems.h"
#include "TetLocator.h"
#include "TetMesh.h"

#include <Eigen/Dense>
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

TetMesh Build(const MeshData& data)
{
  TetMesh mesh;
  mesh.SetGeometry(data.Points, data.Tets);
  return mesh;
}

/// Rotate the points of a mesh about the axis (1, 2, 3) by 0.5 rad and shift them.
MeshData Rotated(MeshData data)
{
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  for (size_t i = 0; i < data.Points.size(); i += 3)
  {
    const Eigen::Vector3d p =
      r * Eigen::Vector3d(data.Points[i], data.Points[i + 1], data.Points[i + 2]);
    for (int d = 0; d < 3; ++d)
    {
      data.Points[i + d] = p[d] + 0.3 * (d + 1);
    }
  }
  return data;
}

/// Random heterogeneous material; absorbing or not; one eta for all tets.
OpticalProperties RandomMaterial(int numTets, std::uint64_t seed, bool absorbing, double eta = 1.3)
{
  std::mt19937_64 rng(seed);
  OpticalProperties m;
  for (int t = 0; t < numTets; ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      m.AbsorptionCoefficient.push_back(absorbing ? 0.01 + 0.3 * Uniform01(rng) : 0.0);
      m.ReducedScatteringCoefficient.push_back(0.3 + 2.5 * Uniform01(rng));
    }
    m.RefractiveIndex.push_back(eta);
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

/// Light from +z on the upper part of a box surface (a realistic, smooth-ish source).
std::vector<double> TopIrradiance(const TetMesh& mesh, double zAbove)
{
  std::vector<double> q(3 * mesh.GetNumberOfPoints(), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    if (mesh.GetPoint(i)[2] > zAbove)
    {
      q[3 * i] = 1.0;
      q[3 * i + 1] = 0.5;
      q[3 * i + 2] = 0.25;
    }
  }
  return q;
}

// ---- tet locator ----

TEST(TetLocator, MatchesBruteForce)
{
  const TetMesh mesh = Build(Rotated(CubeMesh(5, 2.0, 0.25, 3)));
  TetLocator locator;
  locator.Build(mesh);
  std::mt19937_64 rng(5);
  const double* b = locator.GetBounds();
  int inside = 0, outside = 0;
  for (int k = 0; k < 2000; ++k)
  {
    double x[3];
    for (int d = 0; d < 3; ++d)
    {
      // The box and a margin around it.
      x[d] = b[d] - 0.2 + (b[d + 3] - b[d] + 0.4) * Uniform01(rng);
    }
    // Brute force with Eigen: lowest tet whose barycentric coordinates are >= -1e-12.
    int expected = -1;
    for (int t = 0; t < mesh.GetNumberOfTets() && expected < 0; ++t)
    {
      const int* tv = mesh.GetTet(t);
      Eigen::Matrix3d e;
      const Eigen::Vector3d p0(mesh.GetPoint(tv[0]));
      for (int a = 0; a < 3; ++a)
      {
        e.col(a) = Eigen::Vector3d(mesh.GetPoint(tv[a + 1])) - p0;
      }
      const Eigen::Vector3d l = e.partialPivLu().solve(Eigen::Vector3d(x[0], x[1], x[2]) - p0);
      if (l.minCoeff() >= -1e-12 && 1.0 - l.sum() >= -1e-12)
      {
        expected = t;
      }
    }
    ASSERT_EQ(locator.Locate(x), expected) << "point " << k;
    (expected >= 0 ? inside : outside)++;
  }
  EXPECT_GT(inside, 250);
  EXPECT_GT(outside, 250);
  // Mesh vertices lie in several tets: the lowest id wins.
  for (int i = 0; i < mesh.GetNumberOfPoints(); i += 7)
  {
    const int* offsets = mesh.GetPointTetOffsets().data();
    int lowest = mesh.GetNumberOfTets();
    for (int k = offsets[i]; k < offsets[i + 1]; ++k)
    {
      lowest = std::min(lowest, mesh.GetPointTets()[k]);
    }
    EXPECT_LE(locator.Locate(mesh.GetPoint(i)), lowest) << "vertex " << i;
    EXPECT_GE(locator.Locate(mesh.GetPoint(i)), 0) << "vertex " << i;
  }
}

// ---- exact solutions ----

TEST(GridSolver, ConstantSolutionWithoutAbsorption)
{
  // mu_a = 0 and uniform q: phi = 4 q / (1 - Fdr) solves the discrete system
  // exactly for any kappa (interior rows sum to 0; each boundary row reads
  // (delta/(2A) + kappa) phi_b - kappa phi_i = delta/(2A) 4q/(1 - Fdr)).
  // Heterogeneous kappa, a rotated jittered box and a spacing that fits no
  // face: links of every length and angle.
  const double eta = 1.3;
  const TetMesh mesh = Build(Rotated(CubeMesh(6, 3.0, 0.25, 7)));
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 8, false, eta);
  const double qc[3] = { 0.7, 1.3, 0.2 };
  std::vector<double> q(3 * mesh.GetNumberOfPoints(), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    for (int c = 0; c < 3; ++c)
    {
      q[3 * i + c] = qc[c];
    }
  }
  for (const char* linear : { "bicgstab", "relaxation" })
  {
    GridSolver solver;
    solver.SetGridSpacing(0.23);
    solver.SetRelTol(1e-13);
    solver.SetMaxIter(20000);
    solver.SetLinearSolver(linear);
    std::vector<double> fluence;
    SolverReport report;
    ASSERT_TRUE(solver.Solve(MakeProblem(mesh, material, q), fluence, report));
    EXPECT_EQ(solver.GetNumberOfRayFallbacks(), 0);
    const double fdr = Fresnel::DiffuseReflectance(eta);
    for (int c = 0; c < 3; ++c)
    {
      EXPECT_TRUE(report.Converged[c]) << linear << " channel " << c;
      const double expected = 4.0 * qc[c] / (1.0 - fdr);
      const Eigen::VectorXd& x = solver.GetNodeFluence()[c];
      ASSERT_EQ(x.size(), solver.GetNumberOfUnknowns());
      EXPECT_LT((x.array() - expected).abs().maxCoeff(), 1e-9 * expected)
        << linear << " channel " << c;
      for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
      {
        ASSERT_NEAR(fluence[3 * i + c], expected, 1e-9 * expected)
          << linear << " channel " << c << " point " << i;
      }
    }
  }
}

// ---- manufactured solution ----

struct GridErrors
{
  std::array<double, 3> NodeMax{}, NodeRms{}, VertexMax{}, VertexRms{};
};

/// Relative errors against phi = exp(a.x), |a|^2 = mu_a / kappa, on the box
/// [0, 4] x [0, 3] x [0, 2.5] with grid spacing h (a divisor of 0.5: the grid
/// is aligned, boundary nodes at h/2 from the faces). q at each boundary node
/// from the Robin condition with the exact outward normal of the face the
/// node lies on.
GridErrors ManufacturedErrors(double h,
  const double muA[3],
  const double sigma[3],
  const Eigen::Vector3d& direction,
  double eta,
  const std::string& linear = "bicgstab")
{
  const double length[3] = { 4.0, 3.0, 2.5 };
  const TetMesh mesh = Build(BoxMesh(8, 6, 5, length[0], length[1], length[2]));
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigma, eta);
  const double fdr = Fresnel::DiffuseReflectance(eta);
  const double bigA = (1.0 + fdr) / (1.0 - fdr);
  const ExponentialSolution exact(muA, sigma, direction);

  GridSolver solver;
  solver.SetGridSpacing(h);
  solver.SetRelTol(1e-11);
  solver.SetMaxIter(100000);
  solver.SetLinearSolver(linear);
  solver.PrepareGrid(mesh);
  const int numInterior = solver.GetNumberOfInteriorNodes();
  const int numBoundary = solver.GetNumberOfBoundaryNodes();
  std::vector<double> nodeQ(3 * static_cast<size_t>(numBoundary));
  for (int b = 0; b < numBoundary; ++b)
  {
    const std::array<double, 3> p = solver.GetNodePosition(numInterior + b);
    const Eigen::Vector3d x(p[0], p[1], p[2]);
    // The face the node lies on: the coordinate at 0 or L.
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    int faces = 0;
    for (int d = 0; d < 3; ++d)
    {
      if (std::abs(x[d]) < 1e-9)
      {
        normal[d] = -1.0;
        ++faces;
      }
      else if (std::abs(x[d] - length[d]) < 1e-9)
      {
        normal[d] = 1.0;
        ++faces;
      }
    }
    EXPECT_EQ(faces, 1) << "boundary node " << b << " is not on exactly one face";
    for (int c = 0; c < 3; ++c)
    {
      nodeQ[3 * b + c] = exact.RobinData(c, x, normal, fdr, bigA);
      EXPECT_GE(nodeQ[3 * b + c], 0.0); // the setup must keep q physical
    }
  }
  DiffusionProblem problem = MakeProblem(mesh, material);
  std::vector<double> fluence;
  SolverReport report;
  EXPECT_TRUE(solver.SolveWithNodeIrradiance(problem, nodeQ, fluence, report));
  GridErrors errors;
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_TRUE(report.Converged[c]) << "h " << h << " channel " << c;
    const Eigen::VectorXd& x = solver.GetNodeFluence()[c];
    RelativeErrors(
      numInterior + numBoundary, [&](int u) { return x[u]; },
      [&](int u)
      {
        const std::array<double, 3> p = solver.GetNodePosition(u);
        return exact(c, Eigen::Vector3d(p[0], p[1], p[2]));
      },
      errors.NodeMax[c], errors.NodeRms[c]);
    RelativeErrors(
      mesh.GetNumberOfPoints(), [&](int i) { return fluence[3 * i + c]; },
      [&](int i) { return exact(c, Eigen::Vector3d(mesh.GetPoint(i))); }, errors.VertexMax[c],
      errors.VertexRms[c]);
  }
  return errors;
}

TEST(GridSolver, ConvergenceToManufacturedSolution)
{
  // The channels of TestDiscreteDivergence: skin1 red, marble red, apple blue.
  const ChannelMaterials channels = ConvergenceChannels();
  const double* muA = channels.MuA;
  const double* sigma = channels.Sigma;
  const Eigen::Vector3d direction(1.0, 2.0, 3.0);
  const double spacings[] = { 0.5, 0.25, 0.125 };
  std::vector<GridErrors> errors;
  for (double h : spacings)
  {
    errors.push_back(ManufacturedErrors(h, muA, sigma, direction, 1.3));
  }
  std::ostringstream out;
  out << std::setprecision(3);
  const size_t f = errors.size() - 1;
  const auto order = ConvergenceOrder;
  for (int c = 0; c < 3; ++c)
  {
    out << "channel " << c << ":\n";
    for (size_t l = 0; l < errors.size(); ++l)
    {
      out << "  h=" << spacings[l] << "  nodes max " << errors[l].NodeMax[c] << " rms "
          << errors[l].NodeRms[c] << "  vertices max " << errors[l].VertexMax[c] << " rms "
          << errors[l].VertexRms[c];
      if (l > 0)
      {
        out << "  (orders: nodes " << order(errors[l - 1].NodeMax[c], errors[l].NodeMax[c]) << ", "
            << order(errors[l - 1].NodeRms[c], errors[l].NodeRms[c]) << "; vertices "
            << order(errors[l - 1].VertexMax[c], errors[l].VertexMax[c]) << ", "
            << order(errors[l - 1].VertexRms[c], errors[l].VertexRms[c]) << ")";
      }
      out << "\n";
    }
    const double nodeMaxOrder = order(errors[f - 1].NodeMax[c], errors[f].NodeMax[c]);
    const double nodeRmsOrder = order(errors[f - 1].NodeRms[c], errors[f].NodeRms[c]);
    const double vertexMaxOrder = order(errors[f - 1].VertexMax[c], errors[f].VertexMax[c]);
    const double vertexRmsOrder = order(errors[f - 1].VertexRms[c], errors[f].VertexRms[c]);
    ::testing::Test::RecordProperty(
      "node_max_order_channel_" + std::to_string(c), std::to_string(nodeMaxOrder));
    ::testing::Test::RecordProperty(
      "node_rms_order_channel_" + std::to_string(c), std::to_string(nodeRmsOrder));
    // The boundary rows (polygrid eq. 9) difference phi over the half link
    // d = h/2 one-sidedly: an O(h) error in the Robin condition, so first
    // order is what the scheme can give (the interior stencil is second
    // order). The vertex map (trilinear, or inverse-distance weights near the
    // surface) is first order too.
    EXPECT_GE(nodeMaxOrder, 0.85) << "channel " << c;
    EXPECT_GE(nodeRmsOrder, 0.85) << "channel " << c;
    EXPECT_GE(vertexMaxOrder, 0.85) << "channel " << c;
    EXPECT_GE(vertexRmsOrder, 0.85) << "channel " << c;
    EXPECT_LT(errors[f].NodeMax[c], errors[0].NodeMax[c] / 4.0) << "channel " << c;
  }
  std::cout << "[ convergence ] grid, relative errors, phi = exp(a.x):\n" << out.str();
}

// ---- a block aligned with the grid ----

TEST(GridSolver, AlignedBlockPutsBoundaryNodesOnTheFaces)
{
  // Box 2 x 1 x 0.5 mm, h = 0.1: 20 x 10 x 5 nodes at h/2 from the faces,
  // all inside; one boundary node per face-adjacent link, h/2 away, on the face.
  const double length[3] = { 2.0, 1.0, 0.5 };
  const TetMesh mesh = Build(BoxMesh(4, 3, 2, length[0], length[1], length[2], 0.2, 9));
  const double h = 0.1;
  GridSolver solver;
  solver.SetGridSpacing(h);
  solver.PrepareGrid(mesh);
  const std::array<int, 3> dims = solver.GetDimensions();
  EXPECT_EQ(dims[0], 20);
  EXPECT_EQ(dims[1], 10);
  EXPECT_EQ(dims[2], 5);
  ASSERT_EQ(solver.GetNumberOfInteriorNodes(), 20 * 10 * 5);
  ASSERT_EQ(solver.GetNumberOfBoundaryNodes(), 2 * (20 * 10 + 20 * 5 + 10 * 5));
  EXPECT_EQ(solver.GetNumberOfRayFallbacks(), 0);
  for (int d = 0; d < 3; ++d)
  {
    EXPECT_NEAR(solver.GetOrigin()[d], h / 2, 1e-14);
  }
  const int numInterior = solver.GetNumberOfInteriorNodes();
  for (int b = 0; b < solver.GetNumberOfBoundaryNodes(); ++b)
  {
    const int dir = solver.GetBoundaryNodeDirection(b);
    const int axis = dir / 2;
    const std::array<double, 3> p = solver.GetNodePosition(numInterior + b);
    const double face = dir % 2 == 0 ? length[axis] : 0.0;
    ASSERT_NEAR(p[axis], face, 1e-12) << "boundary node " << b;
    ASSERT_NEAR(solver.GetBoundaryNodeDistance(b), h / 2, 1e-12);
    // The interior node of the link is in the first layer next to that face.
    const std::array<int, 3> ijk = solver.GetInteriorNodeIndex(solver.GetBoundaryNodeInterior(b));
    EXPECT_EQ(ijk[axis], dir % 2 == 0 ? dims[axis] - 1 : 0);
  }

  // The rows against the formulas: uniform kappa, mu_a.
  const double muA[3] = { 0.05, 0.1, 0.2 }, sigma[3] = { 1.0, 2.0, 0.5 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigma, 1.4);
  const std::vector<double> q = TopIrradiance(mesh, 0.49);
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(solver.Solve(MakeProblem(mesh, material, q), fluence, report));
  const SparseMatrixMap m = solver.GetSystem().Matrix(0);
  const double kappa = 1.0 / (3.0 * (muA[0] + sigma[0]));
  // A node with 6 interior neighbours: h^2 x Stam's eq. 8 in flux form.
  const int deep = 2 + 20 * (3 + 10 * 2);
  EXPECT_NEAR(m.coeff(deep, deep), 6 * kappa + h * h * muA[0], 1e-14);
  EXPECT_NEAR(m.coeff(deep, deep + 1), -kappa, 1e-14);
  EXPECT_NEAR(m.coeff(deep, deep - 20 * 10), -kappa, 1e-14);
  // Node (0, 0, 0): along each axis the boundary node at h- = h/2 and the
  // interior neighbour at h+ = h: weights 2/(h+- (h+ + h-)) h^2 kappa.
  const double wBoundary = 2.0 / (0.5 * 1.5), wInterior = 2.0 / (1.0 * 1.5);
  EXPECT_NEAR(m.coeff(0, 1), -wInterior * kappa, 1e-14);
  EXPECT_NEAR(m.coeff(0, 0), 3 * (wBoundary + wInterior) * kappa + h * h * muA[0], 1e-13);
  int rowEntries = 0;
  for (SparseMatrixMap::InnerIterator it(m, 0); it; ++it)
  {
    ++rowEntries;
    if (it.col() >= numInterior)
    {
      EXPECT_NEAR(it.value(), -wBoundary * kappa, 1e-14);
    }
  }
  EXPECT_EQ(rowEntries, 7);
  // Boundary rows: (delta/(2A) + kappa) phi_b - kappa phi_i = delta/(2A) 4 q/(1 - Fdr).
  const double a = Fresnel::MismatchA(1.4);
  const int b = 0; // linked to node (0, 0, 0)
  EXPECT_EQ(solver.GetBoundaryNodeInterior(b), 0);
  EXPECT_NEAR(m.coeff(numInterior + b, numInterior + b), kappa + 0.05 / (2 * a), 1e-14);
  EXPECT_NEAR(m.coeff(numInterior + b, 0), -kappa, 1e-14);
  EXPECT_EQ(report.NumberOfUnknowns, numInterior + solver.GetNumberOfBoundaryNodes());
  EXPECT_EQ(report.NumberOfNonZeros, 7LL * numInterior + 2LL * solver.GetNumberOfBoundaryNodes());
  EXPECT_GT(report.MemoryBytes, static_cast<size_t>(report.NumberOfNonZeros) * 3 * sizeof(double));

  // Energy balance with mu_a = 0 does not hold for this non-symmetric
  // scheme, but the maximum principle does: 0 <= phi <= max 4q/(1-Fdr).
  const double qMax = 4.0 / (1.0 - Fresnel::DiffuseReflectance(1.4));
  for (double v : fluence)
  {
    EXPECT_GE(v, 0.0);
    EXPECT_LE(v, qMax * (1 + 1e-9));
  }
}

// ---- linear solvers, multi-level, warm start, threads ----

TEST(GridSolver, RelaxationAgreesWithBiCGSTAB)
{
  const TetMesh mesh = Build(Rotated(CubeMesh(4, 2.0, 0.25, 11)));
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 12, true);
  const std::vector<double> q = RandomIrradiance(mesh, 13);
  std::array<std::vector<double>, 2> fluence;
  std::array<Eigen::VectorXd, 2> nodes;
  const char* names[2] = { "bicgstab", "relaxation" };
  for (int s = 0; s < 2; ++s)
  {
    GridSolver solver;
    solver.SetGridSpacing(0.2);
    solver.SetLinearSolver(names[s]);
    solver.SetRelTol(1e-12);
    solver.SetMaxIter(50000);
    SolverReport report;
    ASSERT_TRUE(solver.Solve(MakeProblem(mesh, material, q), fluence[s], report));
    EXPECT_EQ(report.LinearSolver, names[s]);
    for (int c = 0; c < 3; ++c)
    {
      EXPECT_TRUE(report.Converged[c]) << names[s] << " channel " << c;
      EXPECT_LE(report.Residual[c], 1e-12);
      EXPECT_GT(report.Iterations[c], 0);
    }
    nodes[s] = solver.GetNodeFluence()[1];
  }
  // Both reach ||b - Mx|| <= 1e-12 ||b||; the solutions then agree to about
  // cond(M) 1e-12 (cond ~ 1e3 on this 10^3 grid).
  const double scale = nodes[0].lpNorm<Eigen::Infinity>();
  EXPECT_LT((nodes[0] - nodes[1]).lpNorm<Eigen::Infinity>(), 1e-8 * scale);
  for (size_t k = 0; k < fluence[0].size(); ++k)
  {
    ASSERT_NEAR(fluence[0][k], fluence[1][k], 1e-8 * scale) << k;
  }
  // Case-insensitive names; an unknown one is an error naming it.
  GridSolver solver;
  solver.SetGridSpacing(0.2);
  solver.SetLinearSolver("BiCGSTAB");
  std::vector<double> out;
  SolverReport report;
  EXPECT_NO_THROW(solver.Solve(MakeProblem(mesh, material, q), out, report));
  solver.SetLinearSolver("multigrid");
  const std::string message =
    ErrorMessage([&] { solver.Solve(MakeProblem(mesh, material, q), out, report); });
  EXPECT_TRUE(Contains(message, "'multigrid'")) << message;
  EXPECT_TRUE(Contains(message, "relaxation")) << message;
}

TEST(GridSolver, MultiLevelReducesFineIterations)
{
  const TetMesh mesh = Build(CubeMesh(6, 6.0, 0.2, 14));
  const MaterialPreset& marble = FindMaterialPreset("marble");
  const OpticalProperties material = OpticalProperties::Uniform(
    mesh.GetNumberOfTets(), marble.Absorption, marble.ReducedScattering, marble.RefractiveIndex);
  const std::vector<double> q = TopIrradiance(mesh, 3.0);
  for (const char* linear : { "bicgstab", "relaxation" })
  {
    std::array<std::array<int, 3>, 2> iterations;
    std::array<std::vector<double>, 2> fluence;
    for (int multi = 0; multi < 2; ++multi)
    {
      GridSolver solver;
      solver.SetGridSpacing(0.3); // 20^3 nodes; the coarse level has 10^3
      solver.SetLinearSolver(linear);
      solver.SetMultiLevel(multi == 1);
      solver.SetRelTol(1e-7);
      solver.SetMaxIter(100000);
      SolverReport report;
      ASSERT_TRUE(solver.Solve(MakeProblem(mesh, material, q), fluence[multi], report));
      iterations[multi] = report.Iterations;
      for (int c = 0; c < 3; ++c)
      {
        EXPECT_TRUE(report.Converged[c]);
      }
      if (multi)
      {
        EXPECT_GE(solver.GetNumberOfLevels(), 2) << linear;
        EXPECT_GT(solver.GetCoarseIterations()[0], 0) << linear;
      }
      else
      {
        EXPECT_EQ(solver.GetNumberOfLevels(), 1);
      }
    }
    std::cout << "[ multi-level ] " << linear << " fine iterations without / with:";
    for (int c = 0; c < 3; ++c)
    {
      std::cout << " " << iterations[0][c] << "/" << iterations[1][c];
      EXPECT_LT(iterations[1][c], iterations[0][c]) << linear << " channel " << c;
    }
    std::cout << "\n";
    // Same system, same tolerance: the same answer (within the tolerance).
    for (size_t k = 0; k < fluence[0].size(); ++k)
    {
      ASSERT_NEAR(fluence[0][k], fluence[1][k], 1e-4 * std::abs(fluence[0][k]) + 1e-9) << k;
    }
  }
}

TEST(GridSolver, WarmStart)
{
  TetMesh mesh = Build(CubeMesh(5, 4.0, 0.2, 15));
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 16, true);
  std::vector<double> q = RandomIrradiance(mesh, 17);
  GridSolver solver;
  solver.SetGridSpacing(0.2);
  solver.SetRelTol(1e-8);
  std::vector<double> fluence;
  SolverReport cold, again, warm;
  ASSERT_TRUE(solver.Solve(MakeProblem(mesh, material, q), fluence, cold));
  // The same problem again: the previous solution already meets the tolerance.
  ASSERT_TRUE(solver.Solve(MakeProblem(mesh, material, q), fluence, again));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_GT(cold.Iterations[c], 0);
    EXPECT_EQ(again.Iterations[c], 0) << "channel " << c;
  }
  // Slightly changed light: fewer iterations than from zero.
  for (double& v : q)
  {
    v *= 1.01;
  }
  q[3 * mesh.GetBoundaryPoints()[5]] += 0.1;
  ASSERT_TRUE(solver.Solve(MakeProblem(mesh, material, q), fluence, warm));
  GridSolver fresh;
  fresh.SetGridSpacing(0.2);
  fresh.SetRelTol(1e-8);
  std::vector<double> reference;
  SolverReport coldAgain;
  ASSERT_TRUE(fresh.Solve(MakeProblem(mesh, material, q), reference, coldAgain));
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_LT(warm.Iterations[c], coldAgain.Iterations[c]) << "channel " << c;
  }
  for (size_t k = 0; k < fluence.size(); ++k)
  {
    ASSERT_NEAR(fluence[k], reference[k], 1e-5 * std::abs(reference[k]) + 1e-9);
  }
  // Warm start off: from zero again.
  solver.SetWarmStart(false);
  SolverReport off;
  ASSERT_TRUE(solver.Solve(MakeProblem(mesh, material, q), fluence, off));
  EXPECT_EQ(off.Iterations, coldAgain.Iterations);
  // A new spacing is a new grid: no warm start (same count as a fresh solver).
  solver.SetWarmStart(true);
  solver.SetGridSpacing(0.25);
  fresh.SetGridSpacing(0.25);
  SolverReport newGrid, freshGrid;
  ASSERT_TRUE(solver.Solve(MakeProblem(mesh, material, q), fluence, newGrid));
  ASSERT_TRUE(fresh.Solve(MakeProblem(mesh, material, q), reference, freshGrid));
  EXPECT_EQ(newGrid.Iterations, freshGrid.Iterations);
  EXPECT_GT(newGrid.Iterations[0], 0);
  // Moved vertices (same mesh object): a new grid as well.
  MeshData moved = CubeMesh(5, 4.0, 0.2, 15);
  for (double& x : moved.Points)
  {
    x *= 1.05;
  }
  mesh.UpdatePoints(moved.Points);
  SolverReport deformed;
  ASSERT_TRUE(solver.Solve(MakeProblem(mesh, material, q), fluence, deformed));
  EXPECT_GT(deformed.Iterations[0], 0);
  EXPECT_NEAR(solver.GetOrigin()[0], 4.2 / 2 - 0.5 * (solver.GetDimensions()[0] - 1) * 0.25, 1e-12);
}

TEST(GridSolver, ProgressCallbackCanAbort)
{
  const TetMesh mesh = Build(CubeMesh(3, 2.0));
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 27, true);
  const std::vector<double> q = RandomIrradiance(mesh, 28);
  GridSolver solver;
  solver.SetGridSpacing(0.25);
  std::vector<double> fractions;
  solver.SetProgressCallback(
    [&](double f)
    {
      fractions.push_back(f);
      return true;
    });
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(solver.Solve(MakeProblem(mesh, material, q), fluence, report));
  ASSERT_FALSE(fractions.empty());
  EXPECT_EQ(fractions.back(), 1.0);
  for (size_t k = 1; k < fractions.size(); ++k)
  {
    EXPECT_GE(fractions[k], fractions[k - 1]);
  }
  // Abort in the second channel: Solve returns false and keeps no solution
  // for a warm start.
  solver.SetProgressCallback([](double f) { return f < 0.5; });
  EXPECT_FALSE(solver.Solve(MakeProblem(mesh, material, q), fluence, report));
  const double x[3] = { 1.0, 1.0, 1.0 };
  EXPECT_THROW(solver.EvaluateGrid(x), Error);
}

TEST(GridSolver, OneAndTwoThreadsGiveTheSameResult)
{
  // Every loop of the solver writes per node, or sums in fixed blocks of
  // rows added in block order (BiCGSTAB's dot products, the residuals), so
  // results are bit-identical for any number of threads (the automatic
  // thread count may also change with the machine's load). 15^3 nodes: more
  // than one block of rows, and a coarse level.
  const TetMesh mesh = Build(Rotated(CubeMesh(4, 3.0, 0.25, 18)));
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 19, true);
  const std::vector<double> q = RandomIrradiance(mesh, 20);
  for (const char* linear : { "bicgstab", "relaxation" })
  {
    std::array<std::vector<double>, 2> fluence;
    std::array<SolverReport, 2> reports;
    std::array<Eigen::VectorXd, 2> nodes;
    for (int threads = 1; threads <= 2; ++threads)
    {
      GridSolver solver;
      solver.SetNumberOfThreads(threads);
      solver.SetGridSpacing(0.2);
      solver.SetLinearSolver(linear);
      solver.SetMultiLevel(true);
      // Few iterations: every parallel loop runs, and each synchronisation
      // of 2 threads costs milliseconds on a busy machine (OpenMP's
      // default spin-waiting), so the test stays short.
      solver.SetRelTol(1e-8);
      solver.SetMaxIter(std::string(linear) == "relaxation" ? 3 : 4);
      ASSERT_TRUE(
        solver.Solve(MakeProblem(mesh, material, q), fluence[threads - 1], reports[threads - 1]));
      nodes[threads - 1] = solver.GetNodeFluence()[2];
      ASSERT_GE(solver.GetNumberOfLevels(), 2);
      ASSERT_GT(solver.GetNumberOfUnknowns(), 4096);
    }
    EXPECT_EQ(reports[0].Iterations, reports[1].Iterations) << linear;
    EXPECT_EQ(reports[0].Residual, reports[1].Residual) << linear;
    ASSERT_EQ(fluence[0].size(), fluence[1].size());
    for (size_t k = 0; k < fluence[0].size(); ++k)
    {
      ASSERT_EQ(fluence[0][k], fluence[1][k]) << linear << " value " << k;
    }
    ASSERT_EQ(nodes[0].size(), nodes[1].size());
    EXPECT_TRUE((nodes[0].array() == nodes[1].array()).all()) << linear;
  }
}

// ---- linear fields, slanted faces ----

TEST(GridSolver, LinearFieldIsExactOnAnAxisAlignedBox)
{
  // With mu_a = 0 and uniform kappa a linear phi solves the interior rows
  // exactly (the 7-point weights of polygrid eq. 9 / Appendix B are exact
  // for quadratics), and on faces normal to an axis (phi_b - phi_i) / d is
  // exactly dphi/dn: given q at the boundary nodes from the Robin condition,
  // the discrete solution is phi itself. The spacing fits no side of the box
  // (links of several lengths). The vertex map is linear-exact (trilinear,
  // or the least-squares linear fit near the surface), so the mesh points
  // get phi too.
  const double eta = 1.3;
  const TetMesh mesh = Build(BoxMesh(4, 3, 2, 2.0, 1.5, 1.0, 0.2, 25));
  const double muA[3] = { 0.0, 0.0, 0.0 }, sigma[3] = { 1.0, 2.0, 0.5 };
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigma, eta);
  const Eigen::Vector3d gradient(0.1, -0.05, 0.08);
  auto phi = [&](const Eigen::Vector3d& x) { return 1.0 + gradient.dot(x); };
  const double length[3] = { 2.0, 1.5, 1.0 };
  const double fdr = Fresnel::DiffuseReflectance(eta), bigA = Fresnel::MismatchA(eta);
  GridSolver solver;
  solver.SetGridSpacing(0.17);
  solver.SetRelTol(1e-13);
  solver.PrepareGrid(mesh);
  const int numInterior = solver.GetNumberOfInteriorNodes();
  const int numBoundary = solver.GetNumberOfBoundaryNodes();
  std::vector<double> nodeQ(3 * static_cast<size_t>(numBoundary));
  for (int b = 0; b < numBoundary; ++b)
  {
    const std::array<double, 3> p = solver.GetNodePosition(numInterior + b);
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    for (int d = 0; d < 3; ++d)
    {
      normal[d] = std::abs(p[d]) < 1e-9 ? -1.0 : (std::abs(p[d] - length[d]) < 1e-9 ? 1.0 : 0.0);
    }
    ASSERT_EQ(normal.squaredNorm(), 1.0) << "boundary node " << b;
    for (int c = 0; c < 3; ++c)
    {
      const double kappa = 1.0 / (3.0 * sigma[c]);
      nodeQ[3 * b + c] = (1.0 - fdr) / 4.0 *
        (phi(Eigen::Vector3d(p[0], p[1], p[2])) + 2.0 * bigA * kappa * gradient.dot(normal));
    }
  }
  DiffusionProblem problem = MakeProblem(mesh, material);
  std::vector<double> fluence;
  SolverReport report;
  ASSERT_TRUE(solver.SolveWithNodeIrradiance(problem, nodeQ, fluence, report));
  for (int c = 0; c < 3; ++c)
  {
    for (int u = 0; u < numInterior + numBoundary; ++u)
    {
      const std::array<double, 3> p = solver.GetNodePosition(u);
      ASSERT_NEAR(solver.GetNodeFluence()[c][u], phi(Eigen::Vector3d(p[0], p[1], p[2])), 1e-10)
        << "channel " << c << " node " << u;
    }
    for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      ASSERT_NEAR(fluence[3 * i + c], phi(Eigen::Vector3d(mesh.GetPoint(i))), 1e-10)
        << "channel " << c << " point " << i;
    }
  }
  // EvaluateGrid anywhere in the box, e.g. at a corner and inside.
  const double corner[3] = { 2.0, 0.0, 1.0 }, inside[3] = { 0.77, 1.01, 0.5 };
  EXPECT_NEAR(solver.EvaluateGrid(corner)[1], phi(Eigen::Vector3d(corner)), 1e-10);
  EXPECT_NEAR(solver.EvaluateGrid(inside)[0], phi(Eigen::Vector3d(inside)), 1e-10);
}

TEST(GridSolver, ProbesOnSlantedFacesInterpolateOnTheNormal)
{
  // On faces not normal to the link the normal derivative is read at
  // x_b - l n: the probe weights are a convex combination of interior nodes
  // that reproduces that point (so linear functions exactly).
  const TetMesh mesh = Build(Rotated(CubeMesh(4, 3.0, 0.2, 26)));
  GridSolver solver;
  solver.SetGridSpacing(0.15);
  solver.PrepareGrid(mesh);
  const GridLevel& level = solver.GetLevel(0);
  const int numInterior = level.NumberOfInterior();
  int probes = 0, links = 0;
  for (int b = 0; b < level.NumberOfBoundary(); ++b)
  {
    const GridLevel::BoundaryNode& node = level.Boundary[b];
    ASSERT_GE(node.Triangle, 0);
    const int* tri = &mesh.GetBoundaryTriangles()[3 * node.Triangle];
    const Eigen::Vector3d a(mesh.GetPoint(tri[0])), bb(mesh.GetPoint(tri[1])),
      c(mesh.GetPoint(tri[2]));
    const Eigen::Vector3d n = (bb - a).cross(c - a).normalized();
    double xb[3];
    level.Position(numInterior + b, xb);
    // The boundary node is on the plane of its triangle (unless its link
    // was lengthened to the shortest allowed, 0.1 h).
    if (node.Distance > 0.1 * 0.15 * (1 + 1e-12))
    {
      ASSERT_NEAR(n.dot(Eigen::Vector3d(xb[0], xb[1], xb[2]) - a), 0.0, 1e-12);
    }
    if (node.ProbeCount == 1)
    {
      ++links;
      EXPECT_EQ(node.ProbeNodes[0], node.Interior);
      EXPECT_NEAR(node.Probe, node.Distance * node.Cosine, 1e-15);
      continue;
    }
    ++probes;
    ASSERT_TRUE(node.ProbeCount == 8 || node.ProbeCount == 4);
    double sum = 0.0;
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    for (int k = 0; k < node.ProbeCount; ++k)
    {
      ASSERT_GE(node.ProbeWeights[k], 0.0);
      ASSERT_LT(node.ProbeNodes[k], numInterior);
      if (k > 0)
      {
        ASSERT_LT(node.ProbeNodes[k - 1], node.ProbeNodes[k]); // sorted CSR columns
      }
      double p[3];
      level.Position(node.ProbeNodes[k], p);
      point += node.ProbeWeights[k] * Eigen::Vector3d(p[0], p[1], p[2]);
      sum += node.ProbeWeights[k];
    }
    EXPECT_NEAR(sum, 1.0, 1e-14);
    const Eigen::Vector3d expected = Eigen::Vector3d(xb[0], xb[1], xb[2]) - node.Probe * n;
    EXPECT_LT((point - expected).norm(), 1e-12) << "boundary node " << b;
    EXPECT_GE(node.Probe, 0.5 * 0.15 - 1e-15);
    EXPECT_LE(node.Probe, 3.0 * 0.15 + 1e-15);
  }
  // Most nodes probe; the others are within about h of an edge of the cube.
  std::cout << "[ probes ] " << probes << " boundary nodes probe along the normal, " << links
            << " use their link\n";
  EXPECT_GT(probes, 4 * links);
}

TEST(GridSolver, RotatedBoxRmsConvergence)
{
  // The manufactured solution on the box rotated against the grid. Where the
  // normal derivative is probed along the normal the boundary rows are
  // first-order consistent; within about h of the cube's edges (where no
  // cell along the normal has its corners inside) they fall back to the
  // link, whose O(tan) error in the Robin condition does not shrink with h.
  // Those nodes are a band of width ~h along the edges, a fraction ~h^2 of
  // all nodes, so the RMS error still falls at first order while the
  // maximum stalls (printed, not asserted).
  const double length[3] = { 4.0, 3.0, 2.5 };
  const ChannelMaterials channels = ConvergenceChannels();
  const double* muA = channels.MuA;
  const double* sigma = channels.Sigma;
  const double eta = 1.3, fdr = Fresnel::DiffuseReflectance(eta), bigA = Fresnel::MismatchA(eta);
  const Eigen::Matrix3d rotation =
    Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  MeshData data = BoxMesh(8, 6, 5, length[0], length[1], length[2]);
  for (size_t i = 0; i < data.Points.size(); i += 3)
  {
    const Eigen::Vector3d p = rotation * Eigen::Vector3d(&data.Points[i]);
    for (int d = 0; d < 3; ++d)
    {
      data.Points[i + d] = p[d];
    }
  }
  const TetMesh mesh = Build(data);
  const OpticalProperties material =
    OpticalProperties::Uniform(mesh.GetNumberOfTets(), muA, sigma, eta);
  const Eigen::Vector3d direction = Eigen::Vector3d(1, 2, 3).normalized();
  const double spacings[] = { 0.4, 0.2, 0.1 };
  std::array<std::array<double, 3>, 3> rms{}, maxError{};
  for (int l = 0; l < 3; ++l)
  {
    GridSolver solver;
    solver.SetGridSpacing(spacings[l]);
    solver.SetRelTol(1e-10);
    solver.SetMaxIter(20000);
    solver.PrepareGrid(mesh);
    const int numInterior = solver.GetNumberOfInteriorNodes();
    const int numBoundary = solver.GetNumberOfBoundaryNodes();
    std::vector<double> nodeQ(3 * static_cast<size_t>(numBoundary));
    for (int b = 0; b < numBoundary; ++b)
    {
      const std::array<double, 3> p = solver.GetNodePosition(numInterior + b);
      const Eigen::Vector3d x(p[0], p[1], p[2]);
      // The box face the node lies on, in the box's own frame.
      const Eigen::Vector3d y = rotation.transpose() * x;
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      double best = std::numeric_limits<double>::infinity();
      for (int d = 0; d < 3; ++d)
      {
        for (int side = 0; side < 2; ++side)
        {
          const double distance = std::abs(y[d] - side * length[d]);
          if (distance < best)
          {
            best = distance;
            normal = Eigen::Vector3d::Zero();
            normal[d] = side ? 1.0 : -1.0;
          }
        }
      }
      // On a face, or within 0.1 h of it where the link was lengthened.
      ASSERT_LT(best,
        1e-9 +
          (solver.GetBoundaryNodeDistance(b) <= 0.1 * spacings[l] * (1 + 1e-12) ? 0.1 * spacings[l]
                                                                                : 0.0))
        << "boundary node " << b << " is not on the box";
      normal = rotation * normal;
      for (int c = 0; c < 3; ++c)
      {
        const double kappa = 1.0 / (3.0 * (muA[c] + sigma[c]));
        const Eigen::Vector3d a = std::sqrt(muA[c] / kappa) * direction;
        const double value = std::exp(a.dot(x));
        nodeQ[3 * b + c] = (1.0 - fdr) / 4.0 * (value + 2.0 * bigA * kappa * a.dot(normal) * value);
        ASSERT_GE(nodeQ[3 * b + c], 0.0);
      }
    }
    DiffusionProblem problem = MakeProblem(mesh, material);
    std::vector<double> fluence;
    SolverReport report;
    ASSERT_TRUE(solver.SolveWithNodeIrradiance(problem, nodeQ, fluence, report));
    for (int c = 0; c < 3; ++c)
    {
      ASSERT_TRUE(report.Converged[c]);
      const double kappa = 1.0 / (3.0 * (muA[c] + sigma[c]));
      const Eigen::Vector3d a = std::sqrt(muA[c] / kappa) * direction;
      double sum2 = 0.0;
      for (int u = 0; u < numInterior + numBoundary; ++u)
      {
        const std::array<double, 3> p = solver.GetNodePosition(u);
        const double e = std::exp(a.dot(Eigen::Vector3d(p[0], p[1], p[2])));
        const double rel = std::abs(solver.GetNodeFluence()[c][u] - e) / e;
        maxError[l][c] = std::max(maxError[l][c], rel);
        sum2 += rel * rel;
      }
      rms[l][c] = std::sqrt(sum2 / (numInterior + numBoundary));
    }
  }
  std::cout << std::setprecision(3)
            << "[ rotated box ] relative node errors (skin1 R, marble R, apple B):\n";
  for (int l = 0; l < 3; ++l)
  {
    std::cout << "  h=" << spacings[l];
    for (int c = 0; c < 3; ++c)
    {
      std::cout << "  max " << maxError[l][c] << " rms " << rms[l][c];
      if (l > 0)
      {
        std::cout << " (rms order " << std::log2(rms[l - 1][c] / rms[l][c]) << ")";
      }
    }
    std::cout << "\n";
  }
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_GE(std::log2(rms[1][c] / rms[2][c]), 0.8) << "channel " << c;
    EXPECT_GE(std::log2(rms[0][c] / rms[1][c]), 0.8) << "channel " << c;
  }
}

// ---- input checks ----

TEST(GridSolverErrors, BadInput)
{
  const TetMesh mesh = Build(CubeMesh(3, 1.0));
  const OpticalProperties material = RandomMaterial(mesh.GetNumberOfTets(), 21, true);
  const std::vector<double> q = RandomIrradiance(mesh, 22);
  std::vector<double> fluence;
  SolverReport report;
  GridSolver solver;
  auto solve = [&](const DiffusionProblem& p)
  { return ErrorMessage([&] { solver.Solve(p, fluence, report); }); };

  solver.SetGridSpacing(-0.1);
  std::string message = solve(MakeProblem(mesh, material, q));
  EXPECT_TRUE(Contains(message, "grid spacing -0.1 mm")) << message;
  solver.SetGridSpacing(std::numeric_limits<double>::quiet_NaN());
  message = solve(MakeProblem(mesh, material, q));
  EXPECT_TRUE(Contains(message, "grid spacing nan mm")) << message;
  solver.SetGridSpacing(std::numeric_limits<double>::infinity());
  message = solve(MakeProblem(mesh, material, q));
  EXPECT_TRUE(Contains(message, "grid spacing inf mm")) << message;
  // Larger than the 1 mm cube (issue 34: 1e300 gave NaN with exit 0).
  solver.SetGridSpacing(1e300);
  message = solve(MakeProblem(mesh, material, q));
  EXPECT_TRUE(Contains(message, "grid spacing 1e+300 mm is larger than the object")) << message;
  EXPECT_TRUE(Contains(message, "1 x 1 x 1 mm")) << message;
  solver.SetGridSpacing(1.5);
  message = solve(MakeProblem(mesh, material, q));
  EXPECT_TRUE(Contains(message, "larger than the object")) << message;

  // 0 = automatic: (volume / tets)^(1/3).
  solver.SetGridSpacing(0.0);
  EXPECT_EQ(solve(MakeProblem(mesh, material, q)), "");
  EXPECT_NEAR(solver.GetSpacing(), std::cbrt(1.0 / mesh.GetNumberOfTets()), 1e-12);

  // Too fine for the memory limit: the message states the need in bytes.
  solver.SetGridSpacing(1e-4); // 1e12 nodes in the 1 mm cube
  message = solve(MakeProblem(mesh, material, q));
  EXPECT_TRUE(Contains(message, "grid spacing 0.0001 mm needs")) << message;
  EXPECT_TRUE(Contains(message, "bytes")) << message;
  EXPECT_TRUE(Contains(message, "1e+12 grid nodes")) << message;
  EXPECT_TRUE(Contains(message, "larger spacing")) << message;
  // A settable limit: h = 0.05 (20^3 nodes, ~ 4.7 MB) fails under 1 MiB and
  // passes under 1 GiB. The estimate itself: 4 bytes per box node plus
  // ~400 per unknown (volume / h^3 + 1.5 area / h^2).
  solver.SetGridSpacing(0.05);
  double nodes = 0.0;
  const double bytes = solver.EstimateMemory(mesh, 0.05, &nodes);
  EXPECT_EQ(nodes, 20.0 * 20.0 * 20.0);
  EXPECT_NEAR(bytes, 4 * nodes + 400 * (nodes + 1.5 * 6 / (0.05 * 0.05)), 1e-6 * bytes);
  solver.SetMemoryLimit(1 << 20);
  message = solve(MakeProblem(mesh, material, q));
  EXPECT_TRUE(Contains(message, "grid spacing 0.05 mm needs")) << message;
  EXPECT_TRUE(Contains(message, "the limit is 1 MiB")) << message;
  solver.SetMemoryLimit(std::size_t(1) << 30);
  EXPECT_EQ(solve(MakeProblem(mesh, material, q)), "");
  EXPECT_EQ(solver.GetNumberOfInteriorNodes(), 8000);

  // Empty mesh, missing pieces, wrong sizes.
  const TetMesh empty;
  message = solve(MakeProblem(empty, material, q));
  EXPECT_TRUE(Contains(message, "no tetrahedra")) << message;
  DiffusionProblem missing = MakeProblem(mesh, material, q);
  missing.Irradiance = nullptr;
  EXPECT_TRUE(Contains(solve(missing), "irradiance"));
  std::vector<double> shortQ(7, 0.0);
  message = solve(MakeProblem(mesh, material, shortQ));
  EXPECT_TRUE(Contains(message, "Irradiance has 7 values")) << message;
  std::vector<double> negativeQ = q;
  negativeQ[3 * 4 + 2] = -1.0;
  message = solve(MakeProblem(mesh, material, negativeQ));
  EXPECT_TRUE(Contains(message, "point 4, channel B")) << message;
  OpticalProperties badMaterial = material;
  badMaterial.AbsorptionCoefficient[3 * 2 + 1] = -0.5;
  message = solve(MakeProblem(mesh, badMaterial, q));
  EXPECT_TRUE(Contains(message, "tet 2, channel G")) << message;
  solver.SetGridSpacing(0.25);
  std::vector<double> nodeQ(5, 1.0);
  message = ErrorMessage([&]
    { solver.SolveWithNodeIrradiance(MakeProblem(mesh, material, q), nodeQ, fluence, report); });
  EXPECT_TRUE(Contains(message, "node irradiance has 5 values")) << message;

  // Two unit cubes 8 mm apart and h = 3.9: the nodes (x = 1.1, 5, 8.9;
  // y = z = 0.5) all fall between them.
  MeshData pair = CubeMesh(1, 1.0);
  const MeshData second = CubeMesh(1, 1.0);
  const int offset = pair.NumberOfPoints();
  for (size_t k = 0; k < second.Points.size(); ++k)
  {
    pair.Points.push_back(second.Points[k] + (k % 3 == 0 ? 9.0 : 0.0));
  }
  for (int id : second.Tets)
  {
    pair.Tets.push_back(id + offset);
  }
  const TetMesh apart = Build(pair);
  const OpticalProperties apartMaterial = RandomMaterial(apart.GetNumberOfTets(), 23, true);
  const std::vector<double> apartQ = RandomIrradiance(apart, 24);
  GridSolver coarse;
  coarse.SetGridSpacing(3.9);
  message =
    ErrorMessage([&] { coarse.Solve(MakeProblem(apart, apartMaterial, apartQ), fluence, report); });
  EXPECT_TRUE(Contains(message, "leaves no grid node inside the mesh")) << message;
  EXPECT_TRUE(Contains(message, "3 x 1 x 1")) << message;
  coarse.SetGridSpacing(0.5); // 20 x 2 x 2 nodes, 8 in the cubes
  EXPECT_EQ(
    ErrorMessage([&] { coarse.Solve(MakeProblem(apart, apartMaterial, apartQ), fluence, report); }),
    "");
  EXPECT_EQ(coarse.GetNumberOfInteriorNodes(), 16);
}

TEST(GridSolver, Factory)
{
  const std::unique_ptr<DiffusionSolver> solver = CreateDiffusionSolver("Grid");
  ASSERT_TRUE(solver);
  EXPECT_EQ(solver->GetName(), "grid");
  EXPECT_NE(dynamic_cast<GridSolver*>(solver.get()), nullptr);
  const std::vector<std::string> names = GetDiffusionSolverNames();
  EXPECT_NE(std::find(names.begin(), names.end(), "grid"), names.end());
}

} // namespace
