#include "vtkSolveDiffusion.h"

#include "ConjugateGradient.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "TetMesh.h"
#include "vtkTranslucencyMeshConversion.h"

#include <vtkDataArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>

#include <chrono>

vtkStandardNewMacro(vtkSolveDiffusion);

struct vtkSolveDiffusion::Internals
{
  std::shared_ptr<const translucency::TetMesh> Mesh;
  translucency::DiscreteDivergence Discretization;
  translucency::DiffusionSystem System;
  translucency::ConjugateGradient Solver;
  std::array<Eigen::VectorXd, translucency::NumberOfChannels> Solution;
  bool HaveSolution = false;
};

namespace
{
double MillisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
    .count();
}
}

//------------------------------------------------------------------------------
vtkSolveDiffusion::vtkSolveDiffusion()
  : Internal(new Internals)
{
}

//------------------------------------------------------------------------------
vtkSolveDiffusion::~vtkSolveDiffusion() = default;

//------------------------------------------------------------------------------
int vtkSolveDiffusion::GetNumberOfIterations(int channel) const
{
  return (channel >= 0 && channel < 3) ? this->Internal->Solver.GetNumIterations(channel) : 0;
}

double vtkSolveDiffusion::GetFinalResidual(int channel) const
{
  return (channel >= 0 && channel < 3) ? this->Internal->Solver.GetFinalNorm(channel) : 0.0;
}

bool vtkSolveDiffusion::GetConverged(int channel) const
{
  return (channel >= 0 && channel < 3) && this->Internal->Solver.GetConverged(channel);
}

const char* vtkSolveDiffusion::GetSolverName() const
{
  return "divergence";
}

//------------------------------------------------------------------------------
int vtkSolveDiffusion::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  Internals& in = *this->Internal;
  std::string error;
  this->TopologyTime = this->AssemblyTime = this->SolveTime = 0.0;

  auto start = std::chrono::steady_clock::now();
  bool built = false;
  auto mesh = vtkTranslucency::AcquireTetMesh(input, error, &built);
  if (!mesh)
  {
    in.Mesh.reset();
    in.HaveSolution = false;
    vtkErrorMacro(<< error);
    return 0;
  }
  if (mesh != in.Mesh)
  {
    in.Mesh = mesh; // a new geometry: the previous solution is no start point
    in.HaveSolution = false;
  }
  if (built)
  {
    this->TopologyTime = MillisecondsSince(start);
  }
  this->UpdateProgress(0.1);

  translucency::OpticalProperties material;
  std::vector<double> irradiance;
  if (!vtkTranslucency::ToOpticalProperties(input, material, error) ||
    !vtkTranslucency::ReadPointArray(input, vtkTranslucency::IrradianceName, 3, irradiance, error))
  {
    if (error.find("no point array") != std::string::npos)
    {
      error += ": compute it with vtkSurfaceIrradiance or supply your own";
    }
    vtkErrorMacro(<< error);
    return 0;
  }

  start = std::chrono::steady_clock::now();
  try
  {
    in.Discretization.SetNumberOfThreads(this->NumberOfThreads);
    in.Discretization.Assemble(*in.Mesh, material, irradiance, in.System);
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  this->AssemblyTime = MillisecondsSince(start);
  this->UpdateProgress(0.2);

  start = std::chrono::steady_clock::now();
  in.Solver.SetRelTol(this->RelTol);
  in.Solver.SetMaxIter(this->MaxIter);
  in.Solver.SetProgressCallback([this](double fraction) {
    this->UpdateProgress(0.2 + 0.75 * fraction);
    return !this->CheckAbort();
  });
  const bool warm = this->WarmStart && in.HaveSolution;
  if (!in.Solver.Solve(in.System, in.Solution, warm))
  {
    in.HaveSolution = false;
    return 0; // aborted by the user
  }
  in.HaveSolution = true;
  this->SolveTime = MillisecondsSince(start);
  static const char* channelNames[3] = { "R", "G", "B" };
  for (int c = 0; c < 3; ++c)
  {
    if (!in.Solver.GetConverged(c))
    {
      vtkWarningMacro(<< "channel " << channelNames[c] << " did not converge: relative residual "
                      << in.Solver.GetFinalNorm(c) << " after " << in.Solver.GetNumIterations(c)
                      << " iterations (RelTol " << this->RelTol << ", MaxIter " << this->MaxIter
                      << ")");
    }
  }

  std::vector<double> fluence;
  in.Discretization.ToPointFluence(*in.Mesh, in.System, in.Solution, fluence);
  output->ShallowCopy(input);
  vtkDataArray* array = vtkTranslucency::NewTripleArray(vtkTranslucency::FluenceName, fluence);
  output->GetPointData()->AddArray(array);
  array->Delete();
  this->UpdateProgress(1.0);
  return 1;
}

//------------------------------------------------------------------------------
void vtkSolveDiffusion::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "RelTol: " << this->RelTol << "\n";
  os << indent << "MaxIter: " << this->MaxIter << "\n";
  os << indent << "WarmStart: " << this->WarmStart << "\n";
  os << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
}
