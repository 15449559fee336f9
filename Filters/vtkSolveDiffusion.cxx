#include "vtkSolveDiffusion.h"

#include "AimedPencilBeam.h"
#include "Detectors.h"
#include "ModelRange.h"
#include "MonteCarlo.h"
#include "Sp3Solver.h"
#include "DiffusionFrontEnd.h"
#include "DiffusionSolverFactory.h"
#include "DiscreteDivergence.h"
#include "InteractiveAccuracy.h"
#include "Error.h"
#include "Strings.h"
#include "TetMesh.h"
#include "Timer.h"
#include "VertexDiffusionSolver.h"
#include "vtkTranslucencyDistributedIrradiance.h"
#include "vtkTranslucencyDistributedSolve.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"
#include "vtkTranslucencyDispatch.h"
#include "vtkTranslucencyMPI.h"

#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkCellData.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkStringArray.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>

vtkStandardNewMacro(vtkSolveDiffusion);

namespace
{
/// The registry entry of a SOLVER_* constant (the constants are indices
/// into the registry; TestSolveDiffusionRegistry checks the order).
const translucency::DiffusionSolverRegistry::Entry& SolverEntry(int solver)
{
  return translucency::GetDiffusionSolverRegistry().GetEntries().at(static_cast<size_t>(solver));
}
}

namespace
{
/// Whether the input asks for the extended collimated-source model
/// (vtkSurfaceIrradiance's CollimatedModel, in the field data): the
/// distributed path does not implement it, so such inputs are gathered.
bool ExtendedCollimatedModel(vtkInformationVector* inputs, const vtkTranslucencyCommunicator& comm)
{
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputs);
  vtkDataArray* model =
    input ? input->GetFieldData()->GetArray("TranslucencyCollimatedModel") : nullptr;
  const bool extended =
    model && model->GetNumberOfTuples() > 0 && model->GetComponent(0, 0) != 0.0;
  // A collective decision: an empty piece may carry no field data, and every
  // rank must take the same path (or the others hang in its collectives).
  return comm.Any(extended);
}
}

struct vtkSolveDiffusion::Internals
{
  /// The solver, the changed-tet detection and the warm-start bookkeeping.
  translucency::DiffusionFrontEnd FrontEnd;
  translucency::SolverReport Report;
  /// The Robin rule of the last solve (Moments after a divergence/fem solve
  /// with the "extended-moments" collimated model), for the power balance
  /// and, through the field array TranslucencyBoundaryRule, the radiance.
  translucency::Fresnel::BoundaryRule SolvedRule = translucency::Fresnel::BoundaryRule::Fit;
  /// GetAvailableLinearSolvers()'s array.
  vtkNew<vtkStringArray> LinearSolverNames;
  translucency::Sources Sources;
  /// The sources of the last execution: Sources plus the interactive ones.
  translucency::Sources SolvedSources;
  std::vector<translucency::Detector> Detectors;
  /// The detectors of the last execution: Detectors plus the interactive one.
  std::vector<translucency::Detector> SolvedDetectors;
  /// Readings of the last solve (amplitudes) and their phases (radians).
  std::vector<translucency::DetectorReading> Readings;
  /// Monte Carlo: standard errors of Readings (continuous wave) and of the
  /// gate readings ([gate][detector]); empty otherwise.
  std::vector<translucency::DetectorReading> ReadingErrors;
  /// The photons' power bookkeeping after a montecarlo solve (else unset).
  /// The sp3 solver's own read-outs of the last solve (Sp3Solver): its
  /// exitance (3 per point) and its interior sources' injected power.
  bool HasSp3Balance = false;
  std::vector<double> Sp3Exitance;
  std::array<double, 3> Sp3SourcePower{};
  bool HasMonteCarloBalance = false;
  std::array<translucency::MonteCarloSolver::PowerBalance, 3> MonteCarloBalance{};
  std::vector<std::vector<translucency::DetectorReading>> GateErrors;
  std::vector<std::array<double, 3>> FluencePhase, ExitancePhase;
  /// The model-range check's inputs last time: the mesh (its TetSizes) and
  /// the modification times of the coefficient arrays. A relight changes
  /// neither, so it does not repeat the check.
  std::weak_ptr<const translucency::TetMesh> RangeMesh;
  std::vector<double> Sizes;
  vtkMTimeType RangeAbsorptionTime = 0, RangeScatteringTime = 0;
  /// The distributed path's solver (kept: hierarchy and warm start).
  vtkTranslucencyDistributedSolve Distributed;
  /// Time gates: the snapshots asked for and the last time-resolved result.
  std::vector<int> TimeSnapshots;
  translucency::TimeResolvedResult TimeResolved;
};

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
  const auto& registry = translucency::GetDiffusionSolverRegistry();
  try
  {
    const auto& entry = registry.Get(name ? name : "");
    this->SetSolver(static_cast<int>(&entry - registry.GetEntries().data()));
    return true;
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return false;
  }
}

vtkStringArray* vtkSolveDiffusion::GetAvailableLinearSolvers()
{
  vtkStringArray* names = this->Internal->LinearSolverNames;
  names->Initialize();
  names->InsertNextValue("default");
  for (const auto& list :
    { translucency::GetLinearSolverNames(), translucency::GetNonSymmetricLinearSolverNames() })
  {
    for (const std::string& name : list)
    {
      names->InsertNextValue(name);
    }
  }
  return names;
}

const char* vtkSolveDiffusion::GetSolverName() const
{
  return SolverEntry(this->Solver).Name.c_str();
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

double vtkSolveDiffusion::GetInteractiveRelTol()
{
  return translucency::InteractiveRelTol;
}

const char* vtkSolveDiffusion::GetLastLinearSetup() const
{
  return this->Internal->Report.LinearSetup.c_str();
}

vtkIdType vtkSolveDiffusion::GetNumberOfChangedTets() const
{
  return static_cast<vtkIdType>(this->Internal->FrontEnd.GetNumberOfChangedTets());
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
void vtkSolveDiffusion::AddPointSource(
  double x, double y, double z, double powerR, double powerG, double powerB)
{
  translucency::PointSource source;
  source.Position = { x, y, z };
  source.Power = { powerR, powerG, powerB };
  this->Internal->Sources.AddPointSource(source);
  this->Modified();
}

void vtkSolveDiffusion::AddPencilBeam(double x, double y, double z, double dx, double dy,
  double dz, double powerR, double powerG, double powerB)
{
  translucency::PencilBeam beam;
  beam.Position = { x, y, z };
  beam.Direction = { dx, dy, dz };
  beam.Power = { powerR, powerG, powerB };
  this->Internal->Sources.AddPencilBeam(beam);
  this->Modified();
}

void vtkSolveDiffusion::RemoveAllSources()
{
  if (!this->Internal->Sources.Empty())
  {
    this->Internal->Sources.Clear();
    this->Modified();
  }
}

void vtkSolveDiffusion::RemoveAllPointSources()
{
  if (!this->Internal->Sources.GetPointSources().empty())
  {
    this->Internal->Sources.ClearPointSources();
    this->Modified();
  }
}

void vtkSolveDiffusion::RemoveAllPencilBeams()
{
  if (!this->Internal->Sources.GetPencilBeams().empty())
  {
    this->Internal->Sources.ClearPencilBeams();
    this->Modified();
  }
}

int vtkSolveDiffusion::GetNumberOfSources() const
{
  return static_cast<int>(this->Internal->Sources.GetPointSources().size() +
    this->Internal->Sources.GetPencilBeams().size());
}

void vtkSolveDiffusion::AddDetector(double x, double y, double z, double radius)
{
  translucency::Detector detector;
  detector.Position = { x, y, z };
  detector.Radius = radius;
  this->Internal->Detectors.push_back(detector);
  this->Modified();
}

void vtkSolveDiffusion::RemoveAllDetectors()
{
  if (!this->Internal->Detectors.empty())
  {
    this->Internal->Detectors.clear();
    this->Modified();
  }
}

int vtkSolveDiffusion::GetNumberOfDetectors() const
{
  return static_cast<int>(this->Internal->Detectors.size());
}

namespace
{
bool InRange(int k, int c, std::size_t n)
{
  return k >= 0 && static_cast<std::size_t>(k) < n && c >= 0 && c < 3;
}
}

double vtkSolveDiffusion::GetDetectorFluence(int detector, int channel) const
{
  const auto& r = this->Internal->Readings;
  return InRange(detector, channel, r.size()) ? r[detector].Fluence[channel] : 0.0;
}

double vtkSolveDiffusion::GetDetectorExitance(int detector, int channel) const
{
  const auto& r = this->Internal->Readings;
  return InRange(detector, channel, r.size()) ? r[detector].Exitance[channel] : 0.0;
}

double vtkSolveDiffusion::GetDetectorFluencePhase(int detector, int channel) const
{
  const auto& p = this->Internal->FluencePhase;
  return InRange(detector, channel, p.size()) ? p[detector][channel] : 0.0;
}

double vtkSolveDiffusion::GetDetectorExitancePhase(int detector, int channel) const
{
  const auto& p = this->Internal->ExitancePhase;
  return InRange(detector, channel, p.size()) ? p[detector][channel] : 0.0;
}

void vtkSolveDiffusion::GetDetectorSurfacePosition(int detector, double position[3]) const
{
  const auto& r = this->Internal->Readings;
  for (int d = 0; d < 3; ++d)
  {
    position[d] = InRange(detector, 0, r.size()) ? r[detector].SurfacePosition[d] : 0.0;
  }
}

//------------------------------------------------------------------------------
void vtkSolveDiffusion::SetTimeGates(double t0, double t1, int n)
{
  this->TimeGatesCountText = n;
  if (t0 != this->TimeGatesStart || t1 != this->TimeGatesEnd || n != this->TimeGatesCount)
  {
    this->TimeGatesStart = t0;
    this->TimeGatesEnd = t1;
    this->TimeGatesCount = n;
    this->Modified();
  }
}

void vtkSolveDiffusion::SetTimeGatesFromPanel(double t0, double t1, double n)
{
  // ParaView's DoubleVectorProperty passes the count as a double: a whole
  // number is the count; anything else is kept to be reported by RequestData.
  const bool whole = std::isfinite(n) && n == std::floor(n) && std::abs(n) <= 1e9;
  this->SetTimeGates(t0, t1, whole ? static_cast<int>(n) : 0);
  if (!whole)
  {
    this->TimeGatesCountText = n; // reported by RequestData
    this->Modified();
  }
}

void vtkSolveDiffusion::AddTimeSnapshot(int gate)
{
  this->Internal->TimeSnapshots.push_back(gate);
  this->Modified();
}

void vtkSolveDiffusion::RemoveAllTimeSnapshots()
{
  if (!this->Internal->TimeSnapshots.empty())
  {
    this->Internal->TimeSnapshots.clear();
    this->Modified();
  }
}

int vtkSolveDiffusion::GetNumberOfTimeGates() const
{
  const auto& r = this->Internal->TimeResolved;
  return r.IntegratedFluence.empty() ? 0 : r.Gates.Count;
}

double vtkSolveDiffusion::GetTimeGateCentre(int gate) const
{
  const auto& r = this->Internal->TimeResolved;
  return gate >= 0 && gate < this->GetNumberOfTimeGates() ? r.Gates.GetGateCentre(gate) : 0.0;
}

int vtkSolveDiffusion::GetTimeStepsPerGateUsed() const
{
  return this->GetNumberOfTimeGates() > 0 ? this->Internal->TimeResolved.Gates.StepsPerGate : 0;
}

double vtkSolveDiffusion::GetDetectorFluenceTPSF(int detector, int gate, int channel) const
{
  const auto& r = this->Internal->TimeResolved.Readings;
  return gate >= 0 && static_cast<std::size_t>(gate) < r.size() &&
      InRange(detector, channel, r[gate].size())
    ? r[gate][detector].Fluence[channel]
    : 0.0;
}

double vtkSolveDiffusion::GetDetectorExitanceTPSF(int detector, int gate, int channel) const
{
  const auto& r = this->Internal->TimeResolved.Readings;
  return gate >= 0 && static_cast<std::size_t>(gate) < r.size() &&
      InRange(detector, channel, r[gate].size())
    ? r[gate][detector].Exitance[channel]
    : 0.0;
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
    // 12 components (kind 0 directional / 1 point / 2 spot, direction or
    // position, power R, G, B, spot axis, cut-off, exponent); 7 in files
    // written before spot lights (no spot part).
    const int components = lights->GetNumberOfComponents();
    if (components == 7 || components == 12)
    {
      for (vtkIdType k = 0; k < lights->GetNumberOfTuples(); ++k)
      {
        double v[12] = {};
        lights->GetTuple(k, v);
        translucency::LightSource light;
        using Kind = translucency::LightSource::Kind;
        light.Type = v[0] == 0 ? Kind::Directional : (v[0] == 2 ? Kind::Spot : Kind::Point);
        if (light.Type == Kind::Directional)
        {
          light.Direction = { v[1], v[2], v[3] };
        }
        else
        {
          light.Position = { v[1], v[2], v[3] };
        }
        if (light.Type == Kind::Spot)
        {
          light.Direction = { v[7], v[8], v[9] };
          light.SpotCutoff = v[10];
          light.SpotExponent = v[11];
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
  // vtkSurfaceIrradiance's CollimatedModel: 1 = extended, 2 = extended with
  // the Fresnel-moment boundary (its Irradiance then leaves the directional
  // lights out).
  if (vtkDataArray* model = fd->GetArray("TranslucencyCollimatedModel"))
  {
    const double value = model->GetComponent(0, 0);
    problem.Collimated = value == 1.0 ? translucency::CollimatedModel::Extended
      : value == 2.0                  ? translucency::CollimatedModel::ExtendedMoments
                                      : translucency::CollimatedModel::Surface;
  }
}
}

//------------------------------------------------------------------------------
namespace
{
/// The detector field arrays of a solve (the serial, gathered and distributed
/// paths): positions, radii, readings, Monte Carlo standard errors, phases.
void AttachDetectorArrays(vtkUnstructuredGrid* output,
  const std::vector<translucency::Detector>& detectors,
  const std::vector<translucency::DetectorReading>& readings,
  const std::vector<translucency::DetectorReading>& readingErrors,
  const std::vector<std::array<double, 3>>& fluencePhases,
  const std::vector<std::array<double, 3>>& exitancePhases, bool frequencyDomain)
{
  if (!readings.empty())
  {
    std::vector<double> position, detectorFluence, exitance, fluencePhase, exitancePhase;
    for (std::size_t k = 0; k < readings.size(); ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        position.push_back(readings[k].SurfacePosition[c]);
        detectorFluence.push_back(readings[k].Fluence[c]);
        exitance.push_back(readings[k].Exitance[c]);
        fluencePhase.push_back(fluencePhases[k][c]);
        exitancePhase.push_back(exitancePhases[k][c]);
      }
    }
    auto field = [output](const char* name, const std::vector<double>& values) {
      vtkDataArray* array = vtkTranslucency::NewTripleArray(name, values);
      output->GetFieldData()->AddArray(array);
      array->Delete();
    };
    field("DetectorPosition", position);
    // What was asked for (vtkDetectorReadings' table shows both positions).
    std::vector<double> requested;
    vtkNew<vtkDoubleArray> radius;
    radius->SetName("DetectorRadius");
    for (const translucency::Detector& detector : detectors)
    {
      requested.insert(requested.end(), detector.Position.begin(), detector.Position.end());
      radius->InsertNextValue(detector.Radius);
    }
    field("DetectorRequestedPosition", requested);
    output->GetFieldData()->AddArray(radius);
    field("DetectorFluence", detectorFluence);
    field("DetectorExitance", exitance);
    if (!readingErrors.empty()) // Monte Carlo, continuous wave
    {
      std::vector<double> fluenceError, exitanceError;
      for (const auto& error : readingErrors)
      {
        for (int c = 0; c < 3; ++c)
        {
          fluenceError.push_back(error.Fluence[c]);
          exitanceError.push_back(error.Exitance[c]);
        }
      }
      field("DetectorFluenceStandardError", fluenceError);
      field("DetectorExitanceStandardError", exitanceError);
    }
    if (frequencyDomain)
    {
      field("DetectorFluencePhase", fluencePhase);
      field("DetectorExitancePhase", exitancePhase);
    }
  }
}
}

//------------------------------------------------------------------------------
int vtkSolveDiffusion::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  this->Internal->HasMonteCarloBalance = false; // set again by a montecarlo solve
  this->Internal->HasSp3Balance = false;        // set again by an sp3 solve
  return vtkTranslucencyDispatch::Run(this, request, inputVector, outputVector,
    [this](vtkInformationVector** i, const vtkTranslucencyCommunicator& c)
    { return this->PlanParallel(i, c); },
    { [this](vtkInformation* r, vtkInformationVector** i, vtkInformationVector* o)
      { return this->RequestSerial(r, i, o); },
      nullptr,
      [this](vtkInformationVector** i, vtkInformationVector* o, const vtkTranslucencyCommunicator&)
      { return this->RequestDistributed(i, o); } },
    { this->ParallelPath, this->ParallelPlan });
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkSolveDiffusion::PlanParallel(
  vtkInformationVector** inputVector, const vtkTranslucencyCommunicator& comm)
{
  using Plan = vtkTranslucencyParallelPlan;
  const Plan::GatherMode mode = Plan::GatherMode::SameMesh;
  // Collective first: every rank takes part whatever the settings.
  const bool extended = ExtendedCollimatedModel(inputVector[0], comm);
  const bool vertexSolver = this->Solver == SOLVER_DIVERGENCE || this->Solver == SOLVER_FEM;
  if (!vertexSolver)
  {
    return Plan::Gathered(mode, "the solver is serial (only divergence and fem run distributed)");
  }
  if (!this->DistributedSolve)
  {
    return Plan::Gathered(mode, "DistributedSolve is off");
  }
  if (this->ModulationFrequency != 0.0)
  {
    return Plan::Gathered(mode, "a modulation frequency (the distributed solve is real)");
  }
  if (this->TimeGatesCount != 0)
  {
    return Plan::Gathered(mode, "time gates (the distributed solve is continuous wave)");
  }
  if (this->InteractiveDetector)
  {
    return Plan::Gathered(mode, "the interactive detector");
  }
  if (extended)
  {
    return Plan::Gathered(mode, "the extended collimated model");
  }
  if (!vtkTranslucency::CanDistribute(comm))
  {
    return Plan::Gathered(mode, "this build has no distributed solve (hypre and VTK's ParallelMPI)");
  }
  Plan plan = Plan::Distributed(
    mode, "one hypre system over the ranks' pieces (divergence or fem, continuous wave)");
  plan.DeprecatedVariable = "TRANSLUCENCY_GATHERED_SOLVE";
  return plan;
}

//------------------------------------------------------------------------------
int vtkSolveDiffusion::RequestSerial(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  Internals& in = *this->Internal;
  std::string error;
  this->TopologyTime = this->AssemblyTime = this->SolveTime = 0.0;
  in.Report = translucency::SolverReport();
  in.SolvedRule = translucency::Fresnel::BoundaryRule::Fit;
  in.Readings.clear();
  in.FluencePhase.clear();
  in.ExitancePhase.clear();
  in.TimeResolved = translucency::TimeResolvedResult();
  if (!std::isfinite(this->ModulationFrequency) || this->ModulationFrequency < 0.0)
  {
    vtkErrorMacro(<< "ModulationFrequency " << this->ModulationFrequency
                  << " Hz: expected a finite value >= 0 (0 = continuous wave)");
    return 0;
  }
  if (!(std::isfinite(this->TimeGatesCountText) &&
        this->TimeGatesCountText == std::floor(this->TimeGatesCountText)))
  {
    vtkErrorMacro(<< "TimeGates: the number of gates must be a whole number, got "
                  << this->TimeGatesCountText);
    return 0;
  }
  const bool timeResolved = this->TimeGatesCount != 0;
  translucency::TimeGates gates;
  gates.Start = this->TimeGatesStart;
  gates.End = this->TimeGatesEnd;
  gates.Count = this->TimeGatesCount;
  gates.StepsPerGate = this->TimeStepsPerGate;
  if (timeResolved)
  {
    const std::string fault = gates.Check();
    if (!fault.empty())
    {
      vtkErrorMacro(<< "TimeGates (" << gates.Start << ", " << gates.End << ", " << gates.Count
                    << "): " << fault);
      return 0;
    }
    if (this->ModulationFrequency > 0.0)
    {
      vtkErrorMacro(<< "ModulationFrequency " << this->ModulationFrequency
                    << " Hz and TimeGates together: choose the frequency domain or the time "
                       "domain");
      return 0;
    }
  }
  else if (!in.TimeSnapshots.empty())
  {
    vtkErrorMacro(<< "time snapshots without TimeGates: call SetTimeGates(T0, T1, N) first");
    return 0;
  }

  // Convert: the shared mesh, the material, the irradiance and the lights.
  auto start = translucency::Clock::now();
  bool built = false;
  std::string warning;
  auto mesh = vtkTranslucency::AcquireTetMesh(input, error, &built, &warning);
  if (!warning.empty())
  {
    vtkWarningMacro(<< warning);
  }
  if (!mesh)
  {
    in.FrontEnd.Reset();
    vtkErrorMacro(<< error);
    return 0;
  }
  if (built)
  {
    this->TopologyTime = translucency::MillisecondsSince(start);
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
  translucency::DiffusionProblem light;
  ReadLights(input, light);
  // The listed sources and, while on, the interactive ones (the plugin's widgets).
  in.SolvedSources = in.Sources;
  std::fill(this->InteractivePencilBeamEntry, this->InteractivePencilBeamEntry + 3, 0.0);
  try
  {
    if (this->InteractivePointSource)
    {
      translucency::PointSource source;
      std::copy_n(this->InteractivePointSourcePosition, 3, source.Position.begin());
      std::copy_n(this->InteractivePointSourcePower, 3, source.Power.begin());
      source.Label = "interactive point source";
      in.SolvedSources.AddPointSource(source);
    }
    if (this->InteractivePencilBeam)
    {
      std::array<double, 3> point1, point2, power;
      std::copy_n(this->InteractivePencilBeamPoint1, 3, point1.begin());
      std::copy_n(this->InteractivePencilBeamPoint2, 3, point2.begin());
      std::copy_n(this->InteractivePencilBeamPower, 3, power.begin());
      const translucency::PencilBeam beam =
        translucency::AimPencilBeam(*mesh, point1, point2, power, "interactive pencil beam");
      in.SolvedSources.AddPencilBeam(beam);
      std::copy_n(beam.Position.begin(), 3, this->InteractivePencilBeamEntry);
    }
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  light.InteriorSources = &in.SolvedSources;
  // The listed detectors and, while on, the interactive one (projected).
  in.SolvedDetectors = in.Detectors;
  std::fill(
    this->InteractiveDetectorSurfacePosition, this->InteractiveDetectorSurfacePosition + 3, 0.0);
  if (this->InteractiveDetector)
  {
    const double* x = this->InteractiveDetectorPosition;
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]) ||
      !std::isfinite(this->InteractiveDetectorRadius) || this->InteractiveDetectorRadius < 0.0)
    {
      vtkErrorMacro(<< "interactive detector at (" << x[0] << ", " << x[1] << ", " << x[2]
                    << "), radius " << this->InteractiveDetectorRadius
                    << " mm: expected a finite position and a finite radius >= 0");
      return 0;
    }
    try
    {
      const translucency::SurfacePoint surface = translucency::FindSurfacePoint(*mesh, x);
      translucency::Detector detector;
      detector.Position = surface.Position;
      detector.Radius = this->InteractiveDetectorRadius;
      detector.Label = "interactive detector";
      in.SolvedDetectors.push_back(detector);
      std::copy_n(surface.Position.begin(), 3, this->InteractiveDetectorSurfacePosition);
    }
    catch (const translucency::Error& e)
    {
      vtkErrorMacro(<< "interactive detector: " << e.what());
      return 0;
    }
  }

  try
  {
    // Validate: a vertex solver's linear solver must be one of this build's.
    const auto& entry = SolverEntry(this->Solver);
    const std::string linearSolver =
      translucency::ToLower(this->LinearSolver) == "default" ? "" : this->LinearSolver;
    if (entry.Properties.UnknownsAtVertices && !linearSolver.empty())
    {
      const std::vector<std::string> names = translucency::GetLinearSolverNames();
      if (std::find(names.begin(), names.end(), translucency::ToLower(linearSolver)) ==
        names.end())
      {
        vtkErrorMacro(<< "unknown LinearSolver '" << this->LinearSolver << "' for the "
                      << entry.Name << " solver (this build has: "
                      << translucency::JoinNames(names) << "; empty or \"default\" = "
                      << translucency::VertexDiffusionSolver::GetDefaultLinearSolverName(
                           mesh->GetNumberOfPoints())
                      << " for this mesh)");
        return 0;
      }
    }

    // The core: the front end keeps the solver, detects the changed tets
    // and warm-starts; the settings go through the options hook.
    translucency::DiffusionFrontEnd& frontEnd = in.FrontEnd;
    frontEnd.SetSolver(entry.Name);
    frontEnd.SetIncrementalAssembly(this->IncrementalAssembly);
    frontEnd.SetMaximumChangedFraction(this->MaximumChangedFraction);
    translucency::DiffusionSolver& solver = frontEnd.GetSolver();
    if (auto* vertex = dynamic_cast<translucency::VertexDiffusionSolver*>(&solver))
    {
      if (auto* divergence =
            dynamic_cast<translucency::DiscreteDivergence*>(&vertex->GetDiscretization()))
      {
        divergence->SetNumberOfThreads(this->NumberOfThreads);
      }
    }
    solver.SetRelTol(this->RelTol);
    solver.SetMaxIter(this->MaxIter);
    solver.SetWarmStart(this->WarmStart);
    solver.SetLinearSolver(linearSolver);
    // Every solver-specific property; the selected solver reads its own and
    // leaves the others unused (they do not apply to it).
    solver.SetOptions(translucency::SolverOptions{
      { translucency::DiffusionOption::GridSpacing, this->GridSpacing },
      { translucency::DiffusionOption::MultiLevel, this->MultiLevel ? 1.0 : 0.0 },
      { translucency::DiffusionOption::TwoPointFlux, this->QuadGraphTwoPointFlux ? 1.0 : 0.0 },
      { translucency::DiffusionOption::Photons, static_cast<double>(this->NumberOfPhotons) },
      { translucency::DiffusionOption::Seed, static_cast<double>(this->Seed) } });
    solver.SetProgressCallback([this](double fraction) {
      this->UpdateProgress(0.05 + 0.9 * fraction);
      return !this->CheckAbort();
    });

    // The diffusion model's range (Monte Carlo solves the transport itself):
    // a warning when the verdict changes (not at every paint stroke); the
    // mesh resolution is a note (GetMeshResolutionNote), printed by the CLI.
    vtkDataArray* absorption =
      input->GetCellData()->GetArray(vtkTranslucency::AbsorptionName);
    vtkDataArray* scattering =
      input->GetCellData()->GetArray(vtkTranslucency::ScatteringName);
    const vtkMTimeType absorptionTime = absorption ? absorption->GetMTime() : 0;
    const vtkMTimeType scatteringTime = scattering ? scattering->GetMTime() : 0;
    if (entry.Name == "montecarlo")
    {
      this->ModelRangeWarning.clear();
      this->MeshResolutionNote.clear();
      in.RangeMesh.reset(); // checked again when a diffusion solver returns
    }
    else if (in.RangeMesh.lock() != mesh || absorptionTime != in.RangeAbsorptionTime ||
      scatteringTime != in.RangeScatteringTime)
    {
      if (in.RangeMesh.lock() != mesh)
      {
        in.Sizes = translucency::TetSizes(*mesh);
      }
      in.RangeMesh = mesh;
      in.RangeAbsorptionTime = absorptionTime;
      in.RangeScatteringTime = scatteringTime;
      const translucency::ModelRangeReport range =
        translucency::CheckModelRange(*mesh, material, &in.Sizes);
      const std::string warning = range.AlbedoMessage();
      if (!warning.empty() && warning != this->ModelRangeWarning)
      {
        vtkWarningMacro(<< warning);
      }
      this->ModelRangeWarning = warning;
      this->MeshResolutionNote = range.ResolutionMessage();
    }

    const bool frequencyDomain = this->ModulationFrequency > 0.0;
    auto* monteCarlo = dynamic_cast<translucency::MonteCarloSolver*>(&solver);
    if (monteCarlo)
    {
      // Henyey-Greenstein g, interior sources, detectors and time-of-flight
      // gates; no frequency domain, no fluence snapshots per gate.
      monteCarlo->SetAnisotropy(this->Anisotropy);
      monteCarlo->SetDetectors(in.SolvedDetectors);
      monteCarlo->SetTimeGates(timeResolved ? gates : translucency::TimeGates());
      if (frequencyDomain)
      {
        vtkErrorMacro(<< "the montecarlo solver has no frequency domain (ModulationFrequency "
                      << this->ModulationFrequency
                      << " Hz): use the divergence or fem solver, or time gates");
        return 0;
      }
      if (!in.TimeSnapshots.empty())
      {
        vtkErrorMacro(<< "the montecarlo solver tallies the time gates at the detectors only: "
                         "no fluence snapshots per gate (use the divergence or fem solver)");
        return 0;
      }
    }
    else if (entry.Name == "sp3")
    {
      // SP3 resolves the phase function's moments: g per tet and channel
      // (mu_s = mu_s' / (1 - g)); checked by OpticalProperties::Validate.
      if (this->Anisotropy != 0.0)
      {
        material.Anisotropy.assign(material.AbsorptionCoefficient.size(), this->Anisotropy);
      }
    }
    else if (this->Anisotropy != 0.0)
    {
      vtkWarningMacro(<< "Anisotropy g = " << this->Anisotropy << " is ignored by the "
                      << entry.Name
                      << " solver: it applies to montecarlo only (the diffusion solvers use the "
                         "reduced scattering coefficient, in which g is already folded)");
    }
    // Detectors read the vertex Fluence every solver writes and every solver
    // takes interior sources (the continuous-wave branch below), so both
    // work for quadgraph and grid too; the frequency and time domains need
    // the vertex systems (or the photons).
    if ((frequencyDomain || timeResolved) && !entry.Properties.UnknownsAtVertices && !monteCarlo)
    {
      vtkErrorMacro(<< "the " << entry.Name
                    << " solver has no frequency domain or time gates: they are implemented "
                       "for the divergence, fem and (but the frequency domain) montecarlo "
                       "solvers");
      return 0;
    }
    // The detectors read the material and the irradiance after the solve.
    translucency::OpticalProperties detectorMaterial;
    std::vector<double> detectorIrradiance;
    if (!in.SolvedDetectors.empty())
    {
      detectorMaterial = material;
      detectorIrradiance = irradiance;
    }
    std::vector<double> fluence;
    std::vector<double> amplitude, phase;
    // The detector readings of a time-resolved run: the time integrals of
    // the gate averages (the continuous-wave readings when the gates cover
    // the whole response).
    auto integrateGates = [&in]() {
      const double width = in.TimeResolved.Gates.GetWidth();
      in.Readings = in.TimeResolved.Readings.front();
      for (std::size_t k = 0; k < in.Readings.size(); ++k)
      {
        in.Readings[k].Fluence.fill(0.0);
        in.Readings[k].Exitance.fill(0.0);
        for (const auto& gate : in.TimeResolved.Readings)
        {
          for (int c = 0; c < 3; ++c)
          {
            in.Readings[k].Fluence[c] += width * gate[k].Fluence[c];
            in.Readings[k].Exitance[c] += width * gate[k].Exitance[c];
          }
        }
      }
    };
    in.ReadingErrors.clear();
    in.GateErrors.clear();
    in.HasMonteCarloBalance = false;
    if (monteCarlo)
    {
      if (!frontEnd.Solve(mesh, std::move(material), std::move(irradiance), light, fluence,
            in.Report))
      {
        return 0; // aborted by the user
      }
      in.HasMonteCarloBalance = true;
      for (int c = 0; c < 3; ++c)
      {
        in.MonteCarloBalance[c] = monteCarlo->GetPowerBalance(c);
      }
      in.Readings = monteCarlo->GetDetectorReadings();
      in.ReadingErrors = monteCarlo->GetDetectorStandardErrors();
      in.TimeResolved = translucency::TimeResolvedResult();
      if (timeResolved)
      {
        in.TimeResolved.Gates = gates;
        in.TimeResolved.Readings = monteCarlo->GetGateReadings();
        in.TimeResolved.IntegratedFluence = fluence; // all time (the photons' CW fluence)
        in.GateErrors = monteCarlo->GetGateStandardErrors();
        if (!in.SolvedDetectors.empty())
        {
          integrateGates();
          in.ReadingErrors.clear(); // those are of the all-time readings
        }
      }
      in.FluencePhase.assign(in.Readings.size(), { 0.0, 0.0, 0.0 });
      in.ExitancePhase.assign(in.Readings.size(), { 0.0, 0.0, 0.0 });
    }
    else if (timeResolved)
    {
      auto* vertex = dynamic_cast<translucency::VertexDiffusionSolver*>(&solver);
      translucency::DiffusionProblem problem = light;
      problem.Mesh = mesh.get();
      problem.Material = &material;
      problem.Irradiance = &irradiance;
      if (!vertex ||
        !vertex->SolveTimeResolved(
          problem, gates, in.SolvedDetectors, in.TimeSnapshots, in.TimeResolved, in.Report))
      {
        return 0; // aborted by the user
      }
      fluence = in.TimeResolved.IntegratedFluence;
      if (light.Collimated == translucency::CollimatedModel::ExtendedMoments)
      {
        in.SolvedRule = translucency::Fresnel::BoundaryRule::Moments;
      }
      if (!in.SolvedDetectors.empty())
      {
        integrateGates();
        in.FluencePhase.assign(in.Readings.size(), { 0.0, 0.0, 0.0 });
        in.ExitancePhase.assign(in.Readings.size(), { 0.0, 0.0, 0.0 });
      }
    }
    else if (frequencyDomain)
    {
      auto* vertex = dynamic_cast<translucency::VertexDiffusionSolver*>(&solver);
      translucency::DiffusionProblem problem = light;
      problem.Mesh = mesh.get();
      problem.Material = &material;
      problem.Irradiance = &irradiance;
      std::vector<std::complex<double>> complexFluence;
      if (!vertex ||
        !vertex->SolveFrequencyDomain(problem, this->ModulationFrequency, complexFluence,
          in.Report))
      {
        return 0; // aborted by the user
      }
      // The extended collimated model: the total Phi = Phi_d + the
      // modulated beam; real and imag hold the diffuse Phi_d (what the
      // detectors read, as in continuous wave), and Fluence is |Phi_d| +
      // |E_c| so that Fluence - CollimatedFluence is the diffuse amplitude
      // downstream (vtkOutgoingRadiance); FluenceAmplitude and FluencePhase
      // are those of the total.
      const translucency::SolverReport& report = in.Report;
      const bool beam = report.CollimatedFluence.size() == complexFluence.size() &&
        report.CollimatedFluencePhase.size() == complexFluence.size();
      if (light.Collimated == translucency::CollimatedModel::ExtendedMoments)
      {
        in.SolvedRule = translucency::Fresnel::BoundaryRule::Moments;
      }
      std::vector<double> real(complexFluence.size()), imag(complexFluence.size());
      amplitude.resize(complexFluence.size());
      phase.resize(complexFluence.size());
      fluence.resize(complexFluence.size());
      for (std::size_t i = 0; i < complexFluence.size(); ++i)
      {
        const std::complex<double> diffuse = beam
          ? complexFluence[i] -
            std::polar(report.CollimatedFluence[i], report.CollimatedFluencePhase[i])
          : complexFluence[i];
        real[i] = diffuse.real();
        imag[i] = diffuse.imag();
        amplitude[i] = std::abs(complexFluence[i]);
        phase[i] = std::arg(complexFluence[i]);
        fluence[i] = beam ? std::abs(diffuse) + report.CollimatedFluence[i] : amplitude[i];
      }
      if (!in.SolvedDetectors.empty())
      {
        // The readings are linear in (phi, q): read the real part with q
        // (modulated in phase with the sources) and the imaginary part
        // without, then take amplitude and phase.
        const auto re = translucency::ReadDetectors(
          *mesh, detectorMaterial, in.SolvedDetectors, real, &detectorIrradiance, in.SolvedRule);
        const auto im = translucency::ReadDetectors(
          *mesh, detectorMaterial, in.SolvedDetectors, imag, nullptr, in.SolvedRule);
        in.Readings = re;
        in.FluencePhase.resize(re.size());
        in.ExitancePhase.resize(re.size());
        for (std::size_t k = 0; k < re.size(); ++k)
        {
          for (int c = 0; c < 3; ++c)
          {
            const std::complex<double> f(re[k].Fluence[c], im[k].Fluence[c]);
            const std::complex<double> j(re[k].Exitance[c], im[k].Exitance[c]);
            in.Readings[k].Fluence[c] = std::abs(f);
            in.Readings[k].Exitance[c] = std::abs(j);
            in.FluencePhase[k][c] = std::arg(f);
            in.ExitancePhase[k][c] = std::arg(j);
          }
        }
      }
    }
    else
    {
      if (!frontEnd.Solve(mesh, std::move(material), std::move(irradiance), light, fluence,
            in.Report))
      {
        return 0; // aborted by the user
      }
      // divergence and fem solve the extended-moments model with the Robin
      // rule of the Fresnel moments (VertexDiffusionSolver; quadgraph and
      // grid refuse the extended models).
      if (light.Collimated == translucency::CollimatedModel::ExtendedMoments)
      {
        in.SolvedRule = translucency::Fresnel::BoundaryRule::Moments;
      }
      if (!in.SolvedDetectors.empty())
      {
        // The detectors read the diffuse fluence (the unscattered beam of
        // the extended model does not leave as diffuse exitance).
        std::vector<double> diffuse = fluence;
        for (std::size_t k = 0; k < in.Report.CollimatedFluence.size(); ++k)
        {
          diffuse[k] -= in.Report.CollimatedFluence[k];
        }
        in.Readings = translucency::ReadDetectors(*mesh, detectorMaterial, in.SolvedDetectors,
          diffuse, &detectorIrradiance,
          light.Collimated == translucency::CollimatedModel::ExtendedMoments
            ? translucency::Fresnel::BoundaryRule::Moments
            : translucency::Fresnel::BoundaryRule::Fit);
        in.FluencePhase.assign(in.Readings.size(), { 0.0, 0.0, 0.0 });
        in.ExitancePhase.assign(in.Readings.size(), { 0.0, 0.0, 0.0 });
      }
      if (auto* sp3 = dynamic_cast<translucency::Sp3Solver*>(&solver))
      {
        // SP3's exitance is its own (the outgoing half of the P3 radiance),
        // read through the detectors' footprints; the power balance uses it.
        in.HasSp3Balance = true;
        in.Sp3Exitance = sp3->GetExitance();
        in.Sp3SourcePower = sp3->GetSourcePower();
        if (!in.SolvedDetectors.empty())
        {
          const auto footprints = translucency::LocateDetectors(*mesh, in.SolvedDetectors);
          for (std::size_t k = 0; k < footprints.size() && k < in.Readings.size(); ++k)
          {
            in.Readings[k].Exitance = { 0.0, 0.0, 0.0 };
            for (const auto& [point, weight] : footprints[k].GetPointWeights(*mesh))
            {
              for (int c = 0; c < 3; ++c)
              {
                in.Readings[k].Exitance[c] +=
                  weight * in.Sp3Exitance[3 * static_cast<std::size_t>(point) + c];
              }
            }
          }
        }
      }
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

    // Attach.
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
    attach("CollimatedFluence", in.Report.CollimatedFluence);
    attach("CollimatedFluencePhase", in.Report.CollimatedFluencePhase);
    if (in.SolvedRule == translucency::Fresnel::BoundaryRule::Moments)
    {
      // Read by vtkOutgoingRadiance: the radiance of this solve's boundary
      // condition (Fresnel-moment A and Fdr), not eq. 3's fit.
      vtkNew<vtkIntArray> rule;
      rule->SetName("TranslucencyBoundaryRule");
      rule->InsertNextValue(1);
      output->GetFieldData()->AddArray(rule);
    }
    else
    {
      output->GetFieldData()->RemoveArray("TranslucencyBoundaryRule"); // not this solve's
    }
    attach("MonteCarloRadiance", in.Report.Radiance);
    attach("MonteCarloRadianceStandardError", in.Report.RadianceStandardError);
    attach("FluenceAmplitude", amplitude);
    attach("FluencePhase", phase);
    const translucency::TimeResolvedResult& timeResult = in.TimeResolved;
    for (std::size_t k = 0; k < timeResult.Snapshots.size(); ++k)
    {
      attach(("FluenceGate" + std::to_string(timeResult.SnapshotGates[k])).c_str(),
        timeResult.Snapshots[k]);
    }
    if (timeResolved)
    {
      vtkNew<vtkDoubleArray> centres;
      centres->SetName("TimeGateCentres");
      for (int g = 0; g < timeResult.Gates.Count; ++g)
      {
        centres->InsertNextValue(timeResult.Gates.GetGateCentre(g));
      }
      output->GetFieldData()->AddArray(centres);
      for (std::size_t k = 0; k < in.SolvedDetectors.size(); ++k)
      {
        std::vector<double> tpsfFluence, tpsfExitance, tpsfFluenceError, tpsfExitanceError;
        for (const auto& gate : timeResult.Readings)
        {
          for (int c = 0; c < 3; ++c)
          {
            tpsfFluence.push_back(gate[k].Fluence[c]);
            tpsfExitance.push_back(gate[k].Exitance[c]);
          }
        }
        for (const auto& gate : in.GateErrors) // Monte Carlo only
        {
          for (int c = 0; c < 3; ++c)
          {
            tpsfFluenceError.push_back(gate[k].Fluence[c]);
            tpsfExitanceError.push_back(gate[k].Exitance[c]);
          }
        }
        for (const auto& [name, values] :
          { std::make_pair("DetectorFluenceTPSF", &tpsfFluence),
            std::make_pair("DetectorExitanceTPSF", &tpsfExitance),
            std::make_pair("DetectorFluenceTPSFStandardError", &tpsfFluenceError),
            std::make_pair("DetectorExitanceTPSFStandardError", &tpsfExitanceError) })
        {
          if (values->empty())
          {
            continue;
          }
          vtkDataArray* array = vtkTranslucency::NewTripleArray(
            (std::string(name) + std::to_string(k)).c_str(), *values);
          output->GetFieldData()->AddArray(array);
          array->Delete();
        }
      }
    }
    AttachDetectorArrays(output, in.SolvedDetectors, in.Readings, in.ReadingErrors,
      in.FluencePhase, in.ExitancePhase, frequencyDomain);
    if (this->InteractiveDetector && !in.Readings.empty())
    {
      // What was asked for: the handle's position (DetectorPosition has the surface point).
      if (vtkDataArray* requested =
            output->GetFieldData()->GetArray("DetectorRequestedPosition"))
      {
        requested->SetTuple(
          requested->GetNumberOfTuples() - 1, this->InteractiveDetectorPosition);
      }
    }
  }
  catch (const translucency::Error& e)
  {
    in.FrontEnd.Reset(); // no warm start nor incremental update from a failed solve
    vtkErrorMacro(<< e.what());
    return 0;
  }
  this->UpdateProgress(1.0);
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
bool vtkSolveDiffusion::ComputePowerBalance(
  double injected[3], double absorbed[3], double escaped[3])
{
  vtkUnstructuredGrid* output = this->GetOutput();
  std::string error;
  if (this->ParallelPath == "distributed")
  {
    // Summed over the ranks inside the collective solve: the whole object's
    // balance on every rank (DistributedVertexSolver::GetPowerBalance).
    if (!this->Internal->Distributed.GetPowerBalance(injected, absorbed, escaped))
    {
      vtkErrorMacro(<< "no power balance: no distributed solution (update the filter first; a "
                       "failed solve leaves an empty output)");
      return false;
    }
    return true;
  }
  if (this->ModulationFrequency > 0.0)
  {
    vtkErrorMacro(<< "no power balance in the frequency domain (ModulationFrequency "
                  << this->ModulationFrequency << " Hz): the fluence is complex");
    return false;
  }
  if (!output || output->GetNumberOfCells() == 0 ||
    !output->GetPointData()->GetArray(vtkTranslucency::FluenceName))
  {
    vtkErrorMacro(<< "no power balance: no solution (update the filter first; a failed solve "
                     "leaves an empty output)");
    return false;
  }
  if (this->Internal->HasMonteCarloBalance)
  {
    for (int c = 0; c < 3; ++c)
    {
      const auto& balance = this->Internal->MonteCarloBalance[c];
      injected[c] = balance.Injected;
      absorbed[c] = balance.Absorbed;
      escaped[c] = balance.Escaped;
    }
    return true;
  }
  auto mesh = vtkTranslucency::AcquireTetMesh(output, error);
  translucency::OpticalProperties material;
  std::vector<double> fluence, irradiance;
  if (!mesh || !vtkTranslucency::ToOpticalProperties(output, material, error) ||
    !vtkTranslucency::ReadPointArray(output, vtkTranslucency::FluenceName, 3, fluence, error) ||
    !vtkTranslucency::ReadPointArray(
      output, vtkTranslucency::IrradianceName, 3, irradiance, error))
  {
    vtkErrorMacro(<< "no power balance: " << error);
    return false;
  }
  try
  {
    // The extended collimated model: Fluence = phi_d + E_c. The diffuse
    // field's balance is read from phi_d with the solve's Robin rule; the
    // beam adds what entered (injected), what it deposited directly
    // (absorbed) and what leaves unscattered, entering - scattered -
    // absorbed (escaped; DiffuseOptics.md, "Power balance").
    const translucency::SolverReport& report = this->Internal->Report;
    const bool beam = report.CollimatedFluence.size() == fluence.size();
    if (beam)
    {
      for (std::size_t k = 0; k < fluence.size(); ++k)
      {
        fluence[k] -= report.CollimatedFluence[k];
      }
    }
    translucency::PowerBalance balance = translucency::ComputePowerBalance(
      *mesh, material, fluence, &irradiance, this->Internal->SolvedRule);
    auto sources = this->Internal->SolvedSources.InjectedPower(*mesh, material);
    const std::vector<double>& sp3Exitance = this->Internal->Sp3Exitance;
    if (this->Internal->HasSp3Balance && sp3Exitance.size() == fluence.size())
    {
      // sp3: its exitance (P1 integral over the surface) and the power its
      // sources injected (a pencil beam's first-collision source).
      balance.Escaped = { 0.0, 0.0, 0.0 };
      const std::vector<int>& triangles = mesh->GetBoundaryTriangles();
      for (int f = 0; f < mesh->GetNumberOfBoundaryTriangles(); ++f)
      {
        const double third = mesh->GetBoundaryTriangleAreas()[f] / 3.0;
        for (int a = 0; a < 3; ++a)
        {
          const std::size_t p = static_cast<std::size_t>(triangles[3 * static_cast<std::size_t>(f) + a]);
          for (int c = 0; c < 3; ++c)
          {
            balance.Escaped[c] += third * sp3Exitance[3 * p + c];
          }
        }
      }
      for (int c = 0; c < 3; ++c)
      {
        sources[c] = this->Internal->Sp3SourcePower[c];
      }
    }
    for (int c = 0; c < 3; ++c)
    {
      injected[c] = balance.BoundaryInjected[c] + sources[c];
      absorbed[c] = balance.Absorbed[c];
      escaped[c] = balance.Escaped[c];
      if (beam)
      {
        injected[c] += report.CollimatedEntering[c];
        absorbed[c] += report.CollimatedAbsorbed[c];
        escaped[c] +=
          report.CollimatedEntering[c] - report.CollimatedScattered[c] - report.CollimatedAbsorbed[c];
      }
    }
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< "no power balance: " << e.what());
    return false;
  }
  return true;
}

//------------------------------------------------------------------------------
int vtkSolveDiffusion::RequestDistributed(
  vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  Internals& in = *this->Internal;
  in.Report = translucency::SolverReport();
  in.Readings.clear();
  in.FluencePhase.clear();
  in.ExitancePhase.clear();
  in.FrontEnd.Reset();
  this->TopologyTime = this->AssemblyTime = this->SolveTime = 0.0;
  in.ReadingErrors.clear();
  in.GateErrors.clear();
  in.TimeResolved = translucency::TimeResolvedResult();
  // The listed sources and the interactive ones.
  in.SolvedSources = in.Sources;
  std::fill(this->InteractivePencilBeamEntry, this->InteractivePencilBeamEntry + 3, 0.0);
  if (this->InteractivePointSource)
  {
    translucency::PointSource source;
    std::copy_n(this->InteractivePointSourcePosition, 3, source.Position.begin());
    std::copy_n(this->InteractivePointSourcePower, 3, source.Power.begin());
    source.Label = "interactive point source";
    in.SolvedSources.AddPointSource(source);
  }
  if (this->InteractivePencilBeam)
  {
    // Aimed by a ray cast over the whole object's surface: the physical
    // boundary all-gathered (every rank casts the same ray on the same
    // triangles, so every rank finds the same entry, or the same error).
    std::string error;
    translucency::BoundarySurface surface;
    if (!vtkTranslucencyDistributedIrradiance::GatherSurface(input, surface, error))
    {
      vtkErrorMacro(<< error);
      return 0;
    }
    try
    {
      std::array<double, 3> point1, point2, power;
      std::copy_n(this->InteractivePencilBeamPoint1, 3, point1.begin());
      std::copy_n(this->InteractivePencilBeamPoint2, 3, point2.begin());
      std::copy_n(this->InteractivePencilBeamPower, 3, power.begin());
      const translucency::PencilBeam beam = translucency::AimPencilBeam(surface.Points,
        surface.Triangles, translucency::SurfaceTolerance(surface.Points, surface.Triangles),
        point1, point2, power, "interactive pencil beam");
      in.SolvedSources.AddPencilBeam(beam);
      std::copy_n(beam.Position.begin(), 3, this->InteractivePencilBeamEntry);
    }
    catch (const translucency::Error& e)
    {
      vtkErrorMacro(<< e.what());
      return 0;
    }
  }
  std::vector<double> fluence;
  std::string error;
  if (!in.Distributed.Solve(input, SolverEntry(this->Solver).Name, this->RelTol, this->MaxIter,
        this->WarmStart, this->NumberOfThreads, &in.SolvedSources, in.Detectors, fluence,
        in.Readings, in.Report, error))
  {
    in.Report = translucency::SolverReport();
    in.Readings.clear();
    vtkErrorMacro(<< error);
    return 0;
  }
  in.FluencePhase.assign(in.Readings.size(), { 0.0, 0.0, 0.0 });
  in.ExitancePhase.assign(in.Readings.size(), { 0.0, 0.0, 0.0 });
  this->AssemblyTime = in.Report.SetupMilliseconds;
  this->SolveTime = in.Report.SolveMilliseconds;
  static const char* channelNames[3] = { "R", "G", "B" };
  for (int c = 0; c < 3; ++c)
  {
    if (!in.Report.Converged[c] && in.Report.Iterations[c] > 0)
    {
      vtkWarningMacro(<< "channel " << channelNames[c] << " did not converge: relative residual "
                      << in.Report.Residual[c] << " after " << in.Report.Iterations[c]
                      << " iterations (RelTol " << this->RelTol << ", MaxIter " << this->MaxIter
                      << ")");
    }
  }
  if (input)
  {
    output->ShallowCopy(input);
    vtkDataArray* array = vtkTranslucency::NewTripleArray(vtkTranslucency::FluenceName, fluence);
    output->GetPointData()->AddArray(array);
    array->Delete();
  }
  // On every rank (an empty piece too): the field arrays vtkDetectorReadings reads.
  AttachDetectorArrays(output, in.Detectors, in.Readings, in.ReadingErrors, in.FluencePhase,
    in.ExitancePhase, false);
  this->UpdateProgress(1.0);
  return outputs.Succeed();
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
  os << indent << "Anisotropy: " << this->Anisotropy << "\n";
  os << indent << "LinearSolver: " << this->LinearSolver << "\n";
  os << indent << "MultiLevel: " << this->MultiLevel << "\n";
  os << indent << "QuadGraphTwoPointFlux: " << this->QuadGraphTwoPointFlux << "\n";
  os << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
  os << indent << "IncrementalAssembly: " << this->IncrementalAssembly << "\n";
  os << indent << "MaximumChangedFraction: " << this->MaximumChangedFraction << "\n";
  os << indent << "Sources: " << this->GetNumberOfSources() << "\n";
  os << indent << "InteractivePointSource: " << this->InteractivePointSource << "\n";
  os << indent << "InteractivePencilBeam: " << this->InteractivePencilBeam << "\n";
  os << indent << "InteractiveDetector: " << this->InteractiveDetector << "\n";
  os << indent << "Detectors: " << this->GetNumberOfDetectors() << "\n";
  os << indent << "ModulationFrequency: " << this->ModulationFrequency << " Hz\n";
  os << indent << "DistributedSolve: " << this->DistributedSolve << "\n";
  os << indent << "TimeGates: " << this->TimeGatesStart << ", " << this->TimeGatesEnd << " ns, "
     << this->TimeGatesCount << " gates\n";
  os << indent << "TimeStepsPerGate: " << this->TimeStepsPerGate << "\n";
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}
