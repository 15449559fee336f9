#include "vtkSolveDiffusion.h"

#include "DiffusionSolverFactory.h"
#include "DiscreteDivergence.h"
#include "Error.h"
#include "Strings.h"
#include "TetMesh.h"
#include "VertexDiffusionSolver.h"
#include "vtkTranslucencyMeshConversion.h"

#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstring>

vtkStandardNewMacro(vtkSolveDiffusion);

namespace
{
const char* const SolverNames[] = { "divergence", "fem", "quadgraph", "grid", "montecarlo" };

double MillisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
    .count();
}
}

struct vtkSolveDiffusion::Internals
{
  std::shared_ptr<const translucency::TetMesh> Mesh;
  std::unique_ptr<translucency::DiffusionSolver> Solver;
  int SolverKind = -1;
  translucency::SolverReport Report;
  /// Material and irradiance of the last successful vertex solve (for the
  /// incremental update after a paint); HaveLast is false when not valid.
  bool HaveLast = false;
  translucency::OpticalProperties LastMaterial;
  std::vector<double> LastIrradiance;
  vtkIdType ChangedTets = -1;

  void ForgetLast()
  {
    HaveLast = false;
    LastMaterial = translucency::OpticalProperties();
    LastIrradiance.clear();
  }
};

namespace
{
/// Ids of the tets whose mu_a, sigma_s' or eta differ between a and b (same
/// sizes), stopping once more than `limit` are found.
std::vector<int> ChangedTets(
  const translucency::OpticalProperties& a, const translucency::OpticalProperties& b, size_t limit)
{
  std::vector<int> changed;
  const size_t n = a.RefractiveIndex.size();
  const double* a0 = a.AbsorptionCoefficient.data();
  const double* a1 = b.AbsorptionCoefficient.data();
  const double* s0 = a.ReducedScatteringCoefficient.data();
  const double* s1 = b.ReducedScatteringCoefficient.data();
  for (size_t t = 0; t < n && changed.size() <= limit; ++t)
  {
    // Compared as bits (memcmp): a NaN that stays a NaN is no change, and a
    // value that changes in any way is one.
    if (std::memcmp(a0 + 3 * t, a1 + 3 * t, 3 * sizeof(double)) != 0 ||
      std::memcmp(s0 + 3 * t, s1 + 3 * t, 3 * sizeof(double)) != 0 ||
      std::memcmp(&a.RefractiveIndex[t], &b.RefractiveIndex[t], sizeof(double)) != 0)
    {
      changed.push_back(static_cast<int>(t));
    }
  }
  return changed;
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
bool vtkSolveDiffusion::SetSolverByName(const char* name)
{
  std::string key = name ? name : "";
  key = translucency::ToLower(key);
  for (int k = SOLVER_DIVERGENCE; k <= SOLVER_MONTECARLO; ++k)
  {
    if (key == SolverNames[k])
    {
      this->SetSolver(k);
      return true;
    }
  }
  vtkErrorMacro(<< "unknown solver '" << (name ? name : "")
                << "' (known solvers: divergence, fem, quadgraph, grid, montecarlo)");
  return false;
}

const char* vtkSolveDiffusion::GetSolverName() const
{
  return SolverNames[this->Solver];
}

//------------------------------------------------------------------------------
int vtkSolveDiffusion::GetNumberOfIterations(int channel) const
{
  return (channel >= 0 && channel < 3) ? this->Internal->Report.Iterations[channel] : 0;
}

double vtkSolveDiffusion::GetFinalResidual(int channel) const
{
  return (channel >= 0 && channel < 3) ? this->Internal->Report.Residual[channel] : 0.0;
}

bool vtkSolveDiffusion::GetConverged(int channel) const
{
  return (channel >= 0 && channel < 3) && this->Internal->Report.Converged[channel];
}

const char* vtkSolveDiffusion::GetLinearSolverUsed() const
{
  return this->Internal->Report.LinearSolver.c_str();
}

const char* vtkSolveDiffusion::GetLastAssembly() const
{
  return this->Internal->Report.Assembly.c_str();
}

vtkIdType vtkSolveDiffusion::GetNumberOfChangedTets() const
{
  return this->Internal->ChangedTets;
}

vtkTypeInt64 vtkSolveDiffusion::GetNumberOfUnknowns() const
{
  return this->Internal->Report.NumberOfUnknowns;
}

vtkTypeInt64 vtkSolveDiffusion::GetNumberOfNonZeros() const
{
  return this->Internal->Report.NumberOfNonZeros;
}

vtkTypeInt64 vtkSolveDiffusion::GetMemoryBytes() const
{
  return static_cast<vtkTypeInt64>(this->Internal->Report.MemoryBytes);
}

//------------------------------------------------------------------------------
namespace
{
/// The lights vtkSurfaceIrradiance recorded in the field data (for Monte Carlo).
void ReadLights(vtkUnstructuredGrid* input, translucency::DiffusionProblem& problem)
{
  vtkFieldData* fd = input->GetFieldData();
  if (vtkDataArray* lights = fd->GetArray("TranslucencyLights"))
  {
    if (lights->GetNumberOfComponents() == 7)
    {
      for (vtkIdType k = 0; k < lights->GetNumberOfTuples(); ++k)
      {
        double v[7];
        lights->GetTuple(k, v);
        translucency::LightSource light;
        light.Type = v[0] == 0 ? translucency::LightSource::Kind::Directional
                               : translucency::LightSource::Kind::Point;
        if (light.Type == translucency::LightSource::Kind::Directional)
        {
          light.Direction = { v[1], v[2], v[3] };
        }
        else
        {
          light.Position = { v[1], v[2], v[3] };
        }
        light.Power = { v[4], v[5], v[6] };
        problem.Lights.push_back(light);
      }
    }
  }
  if (vtkDataArray* uniform = fd->GetArray("TranslucencyUniformLight"))
  {
    problem.UniformIrradiance = uniform->GetComponent(0, 0);
  }
  if (vtkDataArray* shadows = fd->GetArray("TranslucencyShadows"))
  {
    problem.Shadows = shadows->GetComponent(0, 0) != 0;
  }
}
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
  in.Report = translucency::SolverReport();

  auto start = std::chrono::steady_clock::now();
  bool built = false;
  auto mesh = vtkTranslucency::AcquireTetMesh(input, error, &built);
  if (!mesh)
  {
    in.Mesh.reset();
    vtkErrorMacro(<< error);
    return 0;
  }
  if (built)
  {
    this->TopologyTime = MillisecondsSince(start);
  }
  this->UpdateProgress(0.05);

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

  try
  {
    if (this->Solver <= 1 && !this->LinearSolver.empty())
    {
      // Vertex discretisations: the name must be one of the linear solvers.
      std::string key = this->LinearSolver, known;
      key = translucency::ToLower(key);
      bool found = false;
      for (const auto& name : translucency::GetLinearSolverNames())
      {
        found = found || name == key;
        known += (known.empty() ? "" : ", ") + name;
      }
      if (!found)
      {
        vtkErrorMacro(<< "unknown LinearSolver '" << this->LinearSolver << "' for the "
                      << SolverNames[this->Solver] << " solver (this build has: " << known
                      << "; empty = " << translucency::VertexDiffusionSolver::GetDefaultLinearSolverName()
                      << ")");
        return 0;
      }
    }
    if (!in.Solver || in.SolverKind != this->Solver)
    {
      in.Solver = translucency::CreateDiffusionSolver(SolverNames[this->Solver]);
      in.SolverKind = this->Solver;
      in.ForgetLast();
    }
    if (mesh != in.Mesh)
    {
      in.Solver->Reset(); // a new geometry: the previous solution is no start point
      in.Mesh = mesh;
      in.ForgetLast();
    }
    translucency::DiffusionSolver& solver = *in.Solver;
    auto* vertex = dynamic_cast<translucency::VertexDiffusionSolver*>(&solver);
    in.ChangedTets = -1;
    if (vertex)
    {
      // Incremental assembly after a paint (TransCut Sec. 5.2): same mesh
      // (topology and points: the shared TetMesh is keyed by both), same
      // irradiance, only some tets' coefficients changed since the last
      // successful solve. The changed tets are found by comparing with the
      // coefficients cached from that solve (whatever changed them).
      const size_t numTets = material.RefractiveIndex.size();
      const size_t limit = static_cast<size_t>(this->MaximumChangedFraction * numTets);
      if (this->IncrementalAssembly && in.HaveLast &&
        in.LastMaterial.RefractiveIndex.size() == numTets &&
        in.LastMaterial.AbsorptionCoefficient.size() == material.AbsorptionCoefficient.size() &&
        in.LastMaterial.ReducedScatteringCoefficient.size() ==
          material.ReducedScatteringCoefficient.size() &&
        in.LastIrradiance.size() == irradiance.size() &&
        std::memcmp(in.LastIrradiance.data(), irradiance.data(),
          irradiance.size() * sizeof(double)) == 0)
      {
        std::vector<int> changed = ChangedTets(in.LastMaterial, material, limit);
        if (changed.size() <= limit)
        {
          in.ChangedTets = static_cast<vtkIdType>(changed.size());
          vertex->SetChangedTets(std::move(changed));
        }
      }
      in.ForgetLast(); // until this solve succeeds
      if (auto* divergence =
            dynamic_cast<translucency::DiscreteDivergence*>(&vertex->GetDiscretization()))
      {
        divergence->SetNumberOfThreads(this->NumberOfThreads);
      }
    }
    solver.SetRelTol(this->RelTol);
    solver.SetMaxIter(this->MaxIter);
    solver.SetWarmStart(this->WarmStart);
    solver.SetGridSpacing(this->GridSpacing);
    solver.SetNumberOfPhotons(this->NumberOfPhotons);
    solver.SetSeed(this->Seed);
    solver.SetLinearSolver(this->LinearSolver);
    solver.SetMultiLevel(this->MultiLevel);
    solver.SetProgressCallback([this](double fraction) {
      this->UpdateProgress(0.05 + 0.9 * fraction);
      return !this->CheckAbort();
    });

    translucency::DiffusionProblem problem;
    problem.Mesh = mesh.get();
    problem.Material = &material;
    problem.Irradiance = &irradiance;
    ReadLights(input, problem);

    std::vector<double> fluence;
    if (!solver.Solve(problem, fluence, in.Report))
    {
      return 0; // aborted by the user
    }
    if (vertex && this->IncrementalAssembly)
    {
      in.LastMaterial = std::move(material);
      in.LastIrradiance = std::move(irradiance);
      in.HaveLast = true;
    }
    this->AssemblyTime = in.Report.SetupMilliseconds;
    this->SolveTime = in.Report.SolveMilliseconds;

    static const char* channelNames[3] = { "R", "G", "B" };
    for (int c = 0; c < 3; ++c)
    {
      if (!in.Report.Converged[c] && in.Report.Iterations[c] > 0)
      {
        vtkWarningMacro(<< "channel " << channelNames[c] << " did not converge: relative residual "
                        << in.Report.Residual[c] << " after " << in.Report.Iterations[c]
                        << " iterations (RelTol " << this->RelTol << ", MaxIter "
                        << this->MaxIter << ")");
      }
    }

    output->ShallowCopy(input);
    auto attach = [output](const char* name, const std::vector<double>& values) {
      if (values.size() == 3 * static_cast<size_t>(output->GetNumberOfPoints()))
      {
        vtkDataArray* array = vtkTranslucency::NewTripleArray(name, values);
        output->GetPointData()->AddArray(array);
        array->Delete();
      }
    };
    attach(vtkTranslucency::FluenceName, fluence);
    attach("FluenceStandardError", in.Report.FluenceStandardError);
    attach("MonteCarloRadiance", in.Report.Radiance);
    attach("MonteCarloRadianceStandardError", in.Report.RadianceStandardError);
  }
  catch (const translucency::Error& e)
  {
    in.ForgetLast();
    if (in.Solver)
    {
      in.Solver->Reset();
    }
    vtkErrorMacro(<< e.what());
    return 0;
  }
  this->UpdateProgress(1.0);
  return 1;
}

//------------------------------------------------------------------------------
void vtkSolveDiffusion::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Solver: " << this->GetSolverName() << "\n";
  os << indent << "RelTol: " << this->RelTol << "\n";
  os << indent << "MaxIter: " << this->MaxIter << "\n";
  os << indent << "WarmStart: " << this->WarmStart << "\n";
  os << indent << "GridSpacing: " << this->GridSpacing << "\n";
  os << indent << "NumberOfPhotons: " << this->NumberOfPhotons << "\n";
  os << indent << "Seed: " << this->Seed << "\n";
  os << indent << "LinearSolver: " << this->LinearSolver << "\n";
  os << indent << "MultiLevel: " << this->MultiLevel << "\n";
  os << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
  os << indent << "IncrementalAssembly: " << this->IncrementalAssembly << "\n";
  os << indent << "MaximumChangedFraction: " << this->MaximumChangedFraction << "\n";
}
