#include "SubsurfaceOperator.h"

#include "Error.h"
#include "Fresnel.h"
#include "RadiosityScene.h"
#include "Radiance.h"
#include "TetMesh.h"

#include <Eigen/Core>

#include <cmath>
#include <sstream>

namespace translucency
{

void DiffusionSubsurface::SetLinearSolver(const std::string& name)
{
  auto solver = CreateLinearSolver(name); // throws for an unknown name
  LinearSolverName_ = solver->GetName();
  Solver_.reset();
}

void DiffusionSubsurface::SetRelTol(double tol)
{
  RelTol_ = tol;
  if (Solver_)
  {
    Solver_->SetRelTol(tol);
  }
}

void DiffusionSubsurface::Setup(const RadiosityScene& scene, int object)
{
  const RadiosityObject& obj = scene.GetObject(object);
  if (!obj.Translucent || !obj.Mesh)
  {
    throw Error("diffusion S: object " + std::to_string(object) + " is not translucent");
  }
  const TetMesh& mesh = *obj.Mesh;
  const bool sameMesh = Mesh_ == &mesh;
  Mesh_ = &mesh;
  const int numPoints = mesh.GetNumberOfPoints();
  // beta: the right-hand side per unit q (TransCut eq. 12 is linear in q).
  std::vector<double> ones(3 * static_cast<std::size_t>(numPoints), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    ones[3 * i] = ones[3 * i + 1] = ones[3 * i + 2] = 1.0;
  }
  Discretization_.Assemble(mesh, obj.Material, ones, System_);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    Beta_[c] = System_.RightHandSide[c];
  }
  const std::vector<double> eta = BoundaryPointRefractiveIndex(mesh, obj.Material.RefractiveIndex);
  HalfOverA_.assign(numPoints, 0.0);
  QFactor_.assign(numPoints, 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    const double fdr = Fresnel::DiffuseReflectance(eta[i]);
    HalfOverA_[i] = 1.0 / (2.0 * Fresnel::MismatchA(eta[i]));
    QFactor_[i] = (1.0 - fdr) / (1.0 + fdr);
  }
  if (!sameMesh)
  {
    for (auto& x : Solution_)
    {
      x.resize(0);
    }
  }
  const bool newSolver = !Solver_;
  if (newSolver)
  {
    Solver_ = CreateLinearSolver(LinearSolverName_);
  }
  Solver_->SetRelTol(RelTol_);
  Solver_->Setup(System_, &mesh, newSolver || !sameMesh);
}

void DiffusionSubsurface::Apply(const std::vector<double>& q, std::vector<double>& radiosity)
{
  if (!Mesh_)
  {
    throw Error("diffusion S: Apply() before Setup()");
  }
  const TetMesh& mesh = *Mesh_;
  const int numPatches = mesh.GetNumberOfBoundaryTriangles();
  if (q.size() != 3 * static_cast<std::size_t>(numPatches))
  {
    std::ostringstream os;
    os << "diffusion S: " << q.size() << " values for " << numPatches << " patches";
    throw Error(os.str());
  }
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const std::vector<double>& areas = mesh.GetBoundaryTriangleAreas();
  const std::vector<double>& pointArea = mesh.GetBoundaryAreas();
  const int numPoints = mesh.GetNumberOfPoints();
  // 1. Patch q -> vertex q (area-weighted mean: the same power).
  std::vector<double> qv(3 * static_cast<std::size_t>(numPoints), 0.0);
  for (int t = 0; t < numPatches; ++t)
  {
    for (int m = 0; m < 3; ++m)
    {
      const int v = triangles[3 * t + m];
      for (int c = 0; c < 3; ++c)
      {
        qv[3 * v + c] += areas[t] * q[3 * t + c];
      }
    }
  }
  for (int v : mesh.GetBoundaryPoints())
  {
    for (int c = 0; c < 3; ++c)
    {
      qv[3 * v + c] /= pointArea[v];
    }
  }
  // 2. b = beta .* q (TransCut eq. 12).
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    Eigen::VectorXd& b = System_.RightHandSide[c];
    for (int i = 0; i < numPoints; ++i)
    {
      b[i] = Beta_[c][i] * qv[3 * i + c];
    }
  }
  // 3. Diffusion solve with warm start. Below 50k unknowns an SpMV is too
  // short to share between threads (each parallel region costs more than it
  // saves, badly so on a busy machine): solve serially.
  const int threads = Eigen::nbThreads();
  if (numPoints < 50000)
  {
    Eigen::setNbThreads(1);
  }
  Solver_->Solve(System_, Solution_, WarmStart_, Stats_);
  Eigen::setNbThreads(threads);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    TotalIterations_ += Stats_[c].Iterations;
  }
  // 4. Vertex exitance from the discrete energy balance; 5. patch mean.
  radiosity.assign(3 * static_cast<std::size_t>(numPatches), 0.0);
  for (int t = 0; t < numPatches; ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      double sum = 0.0;
      for (int m = 0; m < 3; ++m)
      {
        const int v = triangles[3 * t + m];
        sum += Solution_[c][v] * HalfOverA_[v] - qv[3 * v + c] * QFactor_[v];
      }
      radiosity[3 * t + c] = sum / 3.0;
    }
  }
}

std::size_t DiffusionSubsurface::GetMemoryBytes() const
{
  std::size_t bytes = (Solver_ ? Solver_->GetMemoryBytes() : 0) +
    System_.RowOffsets.size() * sizeof(int) +
    System_.ColumnIndices.size() * sizeof(int) + (HalfOverA_.size() + QFactor_.size()) * sizeof(double);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    bytes += System_.Values[c].size() * sizeof(double) +
      (System_.RightHandSide[c].size() + Solution_[c].size() + Beta_[c].size()) * sizeof(double);
  }
  return bytes;
}

double DipoleTotalReflectance(double muA, double sigmaS, double eta)
{
  const double alpha = sigmaS / (sigmaS + muA);
  const double a = Fresnel::MismatchA(eta);
  const double root = std::sqrt(3.0 * (1.0 - alpha));
  // Jensen et al. 2001, total diffuse reflectance of the dipole.
  return 0.5 * alpha * (1.0 + std::exp(-4.0 / 3.0 * a * root)) * std::exp(-root);
}

} // namespace translucency
