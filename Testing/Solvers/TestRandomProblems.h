/**
 * @file TestRandomProblems.h
 * @brief Random heterogeneous problems shared by the multiresolution and
 * multigrid solver tests (no VTK): per-tet materials spanning two decades,
 * random boundary irradiance, a mesh in two disconnected pieces, and an
 * assembled problem made of them.
 */
#pragma once

#include "DiffusionSystem.h"
#include "DiscreteDivergence.h"
#include "FiniteElement.h"
#include "OpticalProperties.h"
#include "TestMeshes.h"
#include "TetMesh.h"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace translucency
{
namespace testing
{

/// Random heterogeneous material: per-tet mu_a in [0.002, 0.2] and sigma_s'
/// in [0.2, 20] 1/mm (log-uniform), eta 1.3.
inline OpticalProperties RandomMaterial(int numTets, std::uint64_t seed)
{
  std::mt19937_64 rng(seed);
  OpticalProperties m;
  m.AbsorptionCoefficient.resize(3 * static_cast<std::size_t>(numTets));
  m.ReducedScatteringCoefficient.resize(3 * static_cast<std::size_t>(numTets));
  m.RefractiveIndex.assign(numTets, 1.3);
  for (int t = 0; t < numTets; ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      m.AbsorptionCoefficient[3 * t + c] = 0.002 * std::pow(100.0, Uniform01(rng));
      m.ReducedScatteringCoefficient[3 * t + c] = 0.2 * std::pow(100.0, Uniform01(rng));
    }
  }
  return m;
}

/// Uniform random irradiance in [0, scale) W/mm^2 on the boundary points
/// (0 inside), 3 channels.
inline std::vector<double> RandomIrradiance(
  const TetMesh& mesh, std::uint64_t seed, double scale = 1.0)
{
  std::mt19937_64 rng(seed);
  std::vector<double> q(3 * static_cast<std::size_t>(mesh.GetNumberOfPoints()), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    for (int c = 0; c < 3; ++c)
    {
      q[3 * i + c] = scale * Uniform01(rng);
    }
  }
  return q;
}

/// Two meshes: a jittered cube and its copy shifted away (two pieces).
inline MeshData TwoPieces(int n)
{
  MeshData a = CubeMesh(n, 3.0, 0.2, 5);
  MeshData b = CubeMesh(n, 3.0, 0.2, 6);
  const int offset = a.NumberOfPoints();
  for (std::size_t k = 0; k < b.Points.size(); k += 3)
  {
    a.Points.push_back(b.Points[k] + 10.0);
    a.Points.push_back(b.Points[k + 1]);
    a.Points.push_back(b.Points[k + 2]);
  }
  for (int v : b.Tets)
  {
    a.Tets.push_back(v + offset);
  }
  return a;
}

/// A mesh with a random heterogeneous material and random boundary
/// irradiance, assembled by the discrete divergence (or the FEM).
struct RandomProblem
{
  TetMesh Mesh;
  OpticalProperties Material;
  DiffusionSystem System;
  RandomProblem(const MeshData& data, std::uint64_t seed, bool fem = false)
  {
    Mesh.SetGeometry(data.Points, data.Tets);
    Material = RandomMaterial(Mesh.GetNumberOfTets(), seed);
    const auto q = RandomIrradiance(Mesh, seed + 1);
    if (fem)
    {
      FiniteElement().Assemble(Mesh, Material, q, System);
    }
    else
    {
      DiscreteDivergence().Assemble(Mesh, Material, q, System);
    }
  }
};

/// The three channels' solutions by a sparse LDL^T factorisation (the
/// direct reference of the iterative solvers' tests).
inline std::array<Eigen::VectorXd, 3> Cholesky(const DiffusionSystem& system)
{
  std::array<Eigen::VectorXd, 3> x;
  for (int c = 0; c < 3; ++c)
  {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(
      Eigen::SparseMatrix<double>(system.Matrix(c)));
    EXPECT_EQ(ldlt.info(), Eigen::Success);
    x[c] = ldlt.solve(system.RightHandSide[c]);
  }
  return x;
}

} // namespace testing
} // namespace translucency
