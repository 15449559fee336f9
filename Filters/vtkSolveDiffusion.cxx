#include "vtkSolveDiffusion.h"

#include "AimedPencilBeam.h"
#include "CollimatedModels.h"
#include "CollimatedSource.h"
#include "LightSources.h"
#include "IrradianceCache.h"
#include "Detectors.h"
#include "ModelRange.h"
#include "DiffusionFrontEnd.h"
#include "DiffusionSolverFactory.h"
#include "InteractiveAccuracy.h"
#include "Sp3Solver.h"
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
#include <sstream>

vtkStandardNewMacro(vtkSolveDiffusion);

namespace
{
/// The output's record of the collimated model a solve used (field array
/// TranslucencyCollimatedModel) and, when not null, the irradiance it used
/// (a default extended model's q without the beams: vtkOutgoingRadiance's
/// q of eq. 3). The one-process and the distributed paths attach the same.
void AttachSolvedModel(vtkUnstructuredGrid* output, translucency::CollimatedModel model,
  const std::vector<double>* irradiance)
{
  if (irradiance)
  {
    vtkDataArray* array =
      vtkTranslucency::NewTripleArray(vtkTranslucency::IrradianceName, *irradiance);
    output->GetPointData()->AddArray(array);
    array->Delete();
  }
  vtkNew<vtkIntArray> modelArray;
  modelArray->SetName("TranslucencyCollimatedModel");
  modelArray->InsertNextValue(static_cast<int>(model));
  output->GetFieldData()->AddArray(modelArray);
}
} // namespace

namespace
{
/// The registry entry of a SOLVER_* constant (the constants are indices
/// into the registry; TestSolveDiffusionRegistry checks the order).
const translucency::DiffusionSolverRegistry::Entry& SolverEntry(int solver)
{
  return translucency::GetDiffusionSolverRegistry().GetEntries().at(static_cast<size_t>(solver));
}

/// The change rule of a RelTol: at the interactive RelTol or looser, the
/// interactive rule also stops when the boundary fluence stops changing; a
/// tighter RelTol asks for a residual-only solve. The serial and the
/// distributed solves get the same.
double InteractiveChangeTolFor(double relTol)
{
  return relTol >= translucency::InteractiveRelTol ? translucency::InteractiveChangeTol : 0.0;
}
}

namespace
{
void ReadLights(vtkUnstructuredGrid* input, translucency::DiffusionProblem& problem);

/// Whether vtkSurfaceIrradiance left the collimated model to this filter
/// (its COLLIMATED_DEFAULT: `TranslucencyCollimatedModelByDefault` = 1).
bool ChosenByDefault(vtkFieldData* fd)
{
  vtkDataArray* flag = fd ? fd->GetArray("TranslucencyCollimatedModelByDefault") : nullptr;
  return flag && flag->GetNumberOfTuples() > 0 && flag->GetComponent(0, 0) != 0.0;
}

/// The model of a default choice: the core's default table for the
/// scene's lights and pencil beams for the vertex solvers (divergence, fem:
/// the table was measured with them), and Monte Carlo (which ignores it);
/// the surface model for the others (quadgraph and grid have no extended
/// model; sp3 keeps its own validated default).
translucency::CollimatedModel DefaultModelFor(
  const translucency::DiffusionProblem& problem, bool pencilBeams, const std::string& solver)
{
  const auto& traits = translucency::GetDiffusionSolverRegistry().Get(solver).Properties;
  return traits.UnknownsAtVertices || traits.IsStochastic
    ? translucency::DefaultCollimatedModel(
        problem.Lights, problem.UniformIrradiance > 0.0, pencilBeams)
    : translucency::CollimatedModel::Surface;
}

}

struct vtkSolveDiffusion::Internals
{
  /// The solver, the domain and read-outs, the changed-tet detection and
  /// the warm-start bookkeeping (the core's one solve front end).
  translucency::DiffusionFrontEnd FrontEnd;
  /// The last execution's result (its Fluence moved into the output) and
  /// domain.
  translucency::SolveResult Result;
  translucency::SolveDomain SolvedDomain = translucency::SolveDomain::ContinuousWave;
  /// GetAvailableLinearSolvers()'s array.
  vtkNew<vtkStringArray> LinearSolverNames;
  /// GetLinearSolverTable()'s array.
  vtkNew<vtkStringArray> LinearSolverTable;
  translucency::Sources Sources;
  /// The sources of the last execution: Sources plus the interactive ones.
  translucency::Sources SolvedSources;
  std::vector<translucency::Detector> Detectors;
  /// The detectors of the last execution: Detectors plus the interactive one.
  std::vector<translucency::Detector> SolvedDetectors;
  /// The model-range check's inputs last time: the mesh (its TetSizes) and
  /// the modification times of the coefficient arrays. A relight changes
  /// neither, so it does not repeat the check.
  std::weak_ptr<const translucency::TetMesh> RangeMesh;
  std::vector<double> Sizes;
  vtkMTimeType RangeAbsorptionTime = 0, RangeScatteringTime = 0;
  /// The coefficient arrays (absorption, scattering, refractive index) of
  /// the last successful serial solve: their addresses and modification
  /// times, compared, never dereferenced. The same arrays, not modified
  /// since (VTK's modification times only grow, so a new array never has an
  /// old array's time), on the mesh the front end kept its material for, are
  /// the same material: a relight neither copies, validates nor compares it.
  const void* KeptArrays[3] = { nullptr, nullptr, nullptr };
  vtkMTimeType KeptTimes[3] = { 0, 0, 0 };
  /// Executions that copied and validated the coefficient arrays.
  long long MaterialConversions = 0;
  /// True if `input` carries the kept coefficient arrays, unmodified.
  bool SameMaterialArrays(vtkUnstructuredGrid* input) const;
  /// Remember `input`'s coefficient arrays (after a successful solve) or
  /// forget them (null).
  void KeepMaterialArrays(vtkUnstructuredGrid* input);
  /// The distributed path's solver (kept: hierarchy and warm start).
  vtkTranslucencyDistributedSolve Distributed;
  /// The directional lights' irradiance that a default extended model takes
  /// out of the input's (DecideDefaultCollimatedModel), kept per light.
  translucency::IrradianceCache BeamIrradiance;
  /// Time gates: the snapshots asked for.
  std::vector<int> TimeSnapshots;
  /// Time Snapshots from the panel that are not whole numbers (an error).
  std::vector<double> BadTimeSnapshots;

  // The phases of RequestData (below it): validate, convert, configure,
  // attach. Each throws translucency::Error with a message for the user.
  translucency::SolveRequest MakeRequest(const vtkSolveDiffusion& self) const;
  void AddInteractiveSources(vtkSolveDiffusion& self, const translucency::TetMesh* mesh,
    vtkUnstructuredGrid* piece);
  void AddInteractiveDetector(vtkSolveDiffusion& self, const translucency::TetMesh& mesh);
  void Configure(vtkSolveDiffusion& self, int numberOfPoints);
  void CheckModelRange(vtkSolveDiffusion& self, vtkUnstructuredGrid* input,
    const std::shared_ptr<const translucency::TetMesh>& mesh,
    const translucency::OpticalProperties& material);
  void WarnUnconverged(vtkSolveDiffusion& self) const;
  /// sp3: its own exitance (the outgoing half of the P3 radiance) at the
  /// detectors, and the power balance from it and its sources' power.
  void Sp3Readouts(const translucency::Sp3Solver& sp3, const translucency::TetMesh& mesh,
    const translucency::OpticalProperties& material, const std::vector<double>& irradiance);
  void Attach(vtkSolveDiffusion& self, vtkUnstructuredGrid* input, vtkUnstructuredGrid* output);
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

vtkStringArray* vtkSolveDiffusion::GetLinearSolverTable()
{
  vtkStringArray* table = this->Internal->LinearSolverTable;
  table->Initialize();
  for (const auto& entry : translucency::GetDiffusionSolverRegistry().GetEntries())
  {
    for (const std::string& name : entry.Properties.LinearSolvers)
    {
      table->InsertNextValue(entry.Name);
      table->InsertNextValue(name);
    }
  }
  return table;
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
  return (channel >= 0 && channel < 3) ? this->Internal->Result.Report.Iterations[channel] : 0;
}

double vtkSolveDiffusion::GetFinalResidual(int channel) const
{
  return (channel >= 0 && channel < 3) ? this->Internal->Result.Report.Residual[channel] : 0.0;
}

bool vtkSolveDiffusion::GetConverged(int channel) const
{
  return (channel >= 0 && channel < 3) && this->Internal->Result.Report.Converged[channel];
}

const char* vtkSolveDiffusion::GetLinearSolverUsed() const
{
  return this->Internal->Result.Report.LinearSolver.c_str();
}

double vtkSolveDiffusion::GetInteractiveRelTol()
{
  return translucency::InteractiveRelTol;
}

const char* vtkSolveDiffusion::GetLastLinearSetup() const
{
  return this->Internal->Result.Report.LinearSetup.c_str();
}

const char* vtkSolveDiffusion::GetLastCollimatedUpdate() const
{
  return this->Internal->Result.Report.Collimated.c_str();
}

const char* vtkSolveDiffusion::GetLastAssembly() const
{
  return this->Internal->Result.Report.Assembly.c_str();
}

vtkIdType vtkSolveDiffusion::GetNumberOfChangedTets() const
{
  return static_cast<vtkIdType>(this->Internal->FrontEnd.GetNumberOfChangedTets());
}

vtkTypeInt64 vtkSolveDiffusion::GetNumberOfMaterialConversions() const
{
  // The serial path's and the distributed path's (this rank's piece).
  return this->Internal->MaterialConversions +
    this->Internal->Distributed.GetNumberOfMaterialConversions();
}

vtkTypeInt64 vtkSolveDiffusion::GetNumberOfBeamIrradianceReuses() const
{
  return this->Internal->Distributed.GetNumberOfBeamIrradianceReuses();
}

vtkTypeInt64 vtkSolveDiffusion::GetNumberOfMaterialComparisons() const
{
  return this->Internal->FrontEnd.GetNumberOfMaterialComparisons();
}

vtkTypeInt64 vtkSolveDiffusion::GetNumberOfUnknowns() const
{
  return this->Internal->Result.Report.NumberOfUnknowns;
}

vtkTypeInt64 vtkSolveDiffusion::GetNumberOfNonZeros() const
{
  return this->Internal->Result.Report.NumberOfNonZeros;
}

vtkTypeInt64 vtkSolveDiffusion::GetMemoryBytes() const
{
  return static_cast<vtkTypeInt64>(this->Internal->Result.Report.MemoryBytes);
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
  const auto& r = this->Internal->Result.Readings;
  return InRange(detector, channel, r.size()) ? r[detector].Fluence[channel] : 0.0;
}

double vtkSolveDiffusion::GetDetectorExitance(int detector, int channel) const
{
  const auto& r = this->Internal->Result.Readings;
  return InRange(detector, channel, r.size()) ? r[detector].Exitance[channel] : 0.0;
}

double vtkSolveDiffusion::GetDetectorFluencePhase(int detector, int channel) const
{
  const auto& p = this->Internal->Result.FluencePhase;
  return InRange(detector, channel, p.size()) ? p[detector][channel] : 0.0;
}

double vtkSolveDiffusion::GetDetectorExitancePhase(int detector, int channel) const
{
  const auto& p = this->Internal->Result.ExitancePhase;
  return InRange(detector, channel, p.size()) ? p[detector][channel] : 0.0;
}

void vtkSolveDiffusion::GetDetectorSurfacePosition(int detector, double position[3]) const
{
  const auto& r = this->Internal->Result.Readings;
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

void vtkSolveDiffusion::AddTimeSnapshotFromPanel(double gate)
{
  if (std::isfinite(gate) && gate == std::floor(gate) && std::abs(gate) < 1e9)
  {
    this->AddTimeSnapshot(static_cast<int>(gate));
  }
  else
  {
    this->Internal->BadTimeSnapshots.push_back(gate);
    this->Modified();
  }
}

void vtkSolveDiffusion::RemoveAllTimeSnapshots()
{
  if (!this->Internal->TimeSnapshots.empty() || !this->Internal->BadTimeSnapshots.empty())
  {
    this->Internal->TimeSnapshots.clear();
    this->Internal->BadTimeSnapshots.clear();
    this->Modified();
  }
}

int vtkSolveDiffusion::GetNumberOfTimeGates() const
{
  const auto& r = this->Internal->Result.Time;
  return r.IntegratedFluence.empty() ? 0 : r.Gates.Count;
}

double vtkSolveDiffusion::GetTimeGateCentre(int gate) const
{
  const auto& r = this->Internal->Result.Time;
  return gate >= 0 && gate < this->GetNumberOfTimeGates() ? r.Gates.GetGateCentre(gate) : 0.0;
}

int vtkSolveDiffusion::GetTimeStepsPerGateUsed() const
{
  return this->GetNumberOfTimeGates() > 0 ? this->Internal->Result.Time.Gates.StepsPerGate : 0;
}

double vtkSolveDiffusion::GetDetectorFluenceTPSF(int detector, int gate, int channel) const
{
  const auto& r = this->Internal->Result.Time.Readings;
  return gate >= 0 && static_cast<std::size_t>(gate) < r.size() &&
      InRange(detector, channel, r[gate].size())
    ? r[gate][detector].Fluence[channel]
    : 0.0;
}

double vtkSolveDiffusion::GetDetectorExitanceTPSF(int detector, int gate, int channel) const
{
  const auto& r = this->Internal->Result.Time.Readings;
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

/**
 * vtkSurfaceIrradiance's default model (`TranslucencyCollimatedModelByDefault`),
 * decided here where the pencil beams and the solver are known
 * (DefaultModelFor: the core's default table, measured against Monte Carlo;
 * the surface model for quadgraph, grid and sp3). The irradiance upstream holds
 * every light; for an extended model the directional lights' part (their q,
 * computed as vtkSurfaceIrradiance computes it, term for term) is taken out
 * of it, as an explicit extended model leaves it out upstream (through
 * `beamCache`, which keeps the shadow caster and the unchanged lights' terms
 * across relights and paints, equal bit for bit). Returns true when
 * `irradiance` changed. An explicit model is left as it is.
 */
bool DecideDefaultCollimatedModel(vtkUnstructuredGrid* input, const std::string& solver,
  const translucency::TetMesh& mesh, const translucency::OpticalProperties& material,
  translucency::IrradianceCache& beamCache, std::vector<double>& irradiance,
  translucency::DiffusionProblem& problem)
{
  if (!ChosenByDefault(input->GetFieldData()))
  {
    return false;
  }
  const bool pencils =
    problem.InteriorSources && !problem.InteriorSources->GetPencilBeams().empty();
  problem.Collimated = DefaultModelFor(problem, pencils, solver);
  std::vector<translucency::LightSource> beams;
  for (const translucency::LightSource& light : problem.Lights)
  {
    if (light.Type == translucency::LightSource::Kind::Directional)
    {
      beams.push_back(light);
    }
  }
  if (!translucency::IsExtendedCollimatedModel(problem.Collimated) || beams.empty())
  {
    return false;
  }
  std::vector<double> q;
  beamCache.Compute(mesh, material.RefractiveIndex, beams, 0.0, 0, problem.Shadows, q);
  if (q.size() != irradiance.size())
  {
    throw translucency::Error("the directional lights' irradiance has " +
      std::to_string(q.size()) + " values, the input's Irradiance " +
      std::to_string(irradiance.size()));
  }
  for (std::size_t i = 0; i < irradiance.size(); ++i)
  {
    // What is left is the other lights' q; a point only the beams reach
    // keeps a rounding residue of their sum, set to 0.
    const double rest = irradiance[i] - q[i];
    irradiance[i] = rest > 1e-12 * irradiance[i] ? rest : 0.0;
  }
  return true;
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
  return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector, nullptr,
    [this](vtkInformationVector** i, vtkInformationVector* o, const vtkTranslucencyCommunicator&)
    { return this->RequestDistributed(i, o); });
}

//------------------------------------------------------------------------------
int vtkSolveDiffusion::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::UpdateExtent(this, request, inputVector, outputVector);
}

namespace
{
/// What the replicated Monte Carlo adds to a rank's memory per tet of the
/// whole mesh (bytes): the gathered pieces, the merged mesh, its topology and
/// walk structure, the tallies and the outputs. Measured on the 1M-tet bunny
/// (Documentation/Parallel.md, "The Monte Carlo over the ranks"): peak
/// resident 1.32 GB per rank after one run, 1.67-1.71 GB after three, over
/// ParaView's ~0.36 GB of a 50k-tet run: 0.96-1.35 kB per tet.
constexpr double MonteCarloBytesPerTet = 1400.0;
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkSolveDiffusion::PlanParallel(
  vtkInformationVector** inputVector, const vtkTranslucencyCommunicator& comm)
{
  using Plan = vtkTranslucencyParallelPlan;
  const Plan::GatherMode mode = Plan::GatherMode::SameMesh;
  // By the registry's trait: the solvers with a distributed variant (a build
  // without the Parallel layer has none).
  const translucency::DiffusionSolverTraits& traits = SolverEntry(this->Solver).Properties;
  if (!traits.Distributed)
  {
    return Plan::Gathered(mode,
      "the solver is serial (divergence and fem run distributed, montecarlo replicated)");
  }
  if (!this->DistributedSolve)
  {
    return Plan::Gathered(mode, "DistributedSolve is off");
  }
  if (traits.Replicated)
  {
    if (this->InteractiveDetector)
    {
      return Plan::Gathered(mode, "the interactive detector");
    }
    if (!vtkTranslucency::CanDistribute(comm))
    {
      return Plan::Gathered(mode, "this build has no MPI solvers (hypre and VTK's ParallelMPI)");
    }
    // Every rank will hold the whole problem: only if each node holds a copy
    // per rank on it (else rank 0 alone traces, holding one).
    vtkDataSet* piece = vtkDataSet::GetData(inputVector[0]);
    const long long tets = comm.Sum(piece ? piece->GetNumberOfCells() : 0);
    std::string why;
    if (!vtkTranslucency::ReplicationFits(
          comm, MonteCarloBytesPerTet * static_cast<double>(tets), why))
    {
      // Not only in GetParallelPlan(): the run is as slow as one process's,
      // which a user who asked for N ranks must hear of (once, from rank 0).
      if (comm.GetRank() == 0)
      {
        vtkWarningMacro(<< "the Monte Carlo runs on rank 0 alone (no faster than one process): "
                        << why);
      }
      return Plan::Gathered(mode, "the Monte Carlo on rank 0 alone: " + why);
    }
    return Plan::Replicated("the whole mesh on every rank, the photons split over the ranks "
                            "(memory: the one-process Monte Carlo's on every rank)");
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
  if (!vtkTranslucency::CanDistribute(comm))
  {
    return Plan::Gathered(mode, "this build has no distributed solve (hypre and VTK's ParallelMPI)");
  }
  Plan plan = Plan::Distributed(mode,
    "one hypre system over the ranks' pieces (divergence or fem, continuous wave; the extended "
    "collimated models' beam cast against the all-gathered boundary)");
  plan.DeprecatedVariable = "TRANSLUCENCY_GATHERED_SOLVE";
  return plan;
}

//------------------------------------------------------------------------------
int vtkSolveDiffusion::RequestSerial(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // Validate -> convert -> the core's front end -> attach.
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  Internals& in = *this->Internal;
  this->TopologyTime = this->AssemblyTime = this->SolveTime = 0.0;
  in.Result = translucency::SolveResult();
  try
  {
    // Validate the settings.
    translucency::SolveRequest solveRequest = in.MakeRequest(*this);
    in.SolvedDomain = solveRequest.Domain;

    // Convert: the shared mesh, the material, the irradiance and the lights.
    auto start = translucency::Clock::now();
    bool built = false;
    std::string error, warning;
    auto mesh = vtkTranslucency::AcquireTetMesh(input, error, &built, &warning);
    if (!warning.empty())
    {
      vtkWarningMacro(<< warning);
    }
    if (!mesh)
    {
      throw translucency::Error(error);
    }
    this->TopologyTime = built ? translucency::MillisecondsSince(start) : 0.0;
    this->UpdateProgress(0.05);
    // The material: the front end's kept copy when the input carries the
    // same coefficient arrays, unmodified, as the last solve (a relight);
    // else copied and validated.
    bool keptMaterial = in.SameMaterialArrays(input) && in.FrontEnd.HasKeptMaterial(mesh);
    in.KeepMaterialArrays(nullptr); // until this solve succeeds
    if (!keptMaterial && in.FrontEnd.HasKeptMaterial(mesh))
    {
      // A paint stroke (new arrays on the same mesh): compared with the kept
      // material in place and its changed tets written into it, without
      // copying or validating the whole material again (issue 31).
      const vtkTranslucency::CoefficientValues values =
        vtkTranslucency::CoefficientArraysInPlace(input, mesh->GetNumberOfTets());
      keptMaterial = in.FrontEnd.UpdateKeptMaterial(
        mesh, values.Absorption, values.Scattering, values.RefractiveIndex);
    }
    translucency::OpticalProperties material;
    std::vector<double> irradiance;
    if ((!keptMaterial && !vtkTranslucency::ToOpticalProperties(input, material, error)) ||
      !vtkTranslucency::ReadPointArray(
        input, vtkTranslucency::IrradianceName, 3, irradiance, error))
    {
      if (error.find("no point array") != std::string::npos)
      {
        error += ": compute it with vtkSurfaceIrradiance or supply your own";
      }
      in.FrontEnd.Reset(); // as a failed solve: no warm start from before it
      throw translucency::Error(error);
    }
    in.MaterialConversions += keptMaterial ? 0 : 1;
    translucency::DiffusionProblem light;
    ReadLights(input, light);
    in.AddInteractiveSources(*this, mesh.get(), nullptr);
    light.InteriorSources = &in.SolvedSources;
    // On a relight with the kept material, `material` was not converted.
    const bool beamsTakenOut = DecideDefaultCollimatedModel(input, this->GetSolverName(), *mesh,
      keptMaterial ? *in.FrontEnd.GetKeptMaterial() : material, in.BeamIrradiance, irradiance,
      light);
    const std::vector<double> solvedIrradiance =
      beamsTakenOut ? irradiance : std::vector<double>();
    const translucency::CollimatedModel solvedModel = light.Collimated;
    in.AddInteractiveDetector(*this, *mesh);
    solveRequest.Detectors = in.SolvedDetectors;

    // The core: the solver by name with its settings, then the one solve.
    in.Configure(*this, mesh->GetNumberOfPoints());
    in.FrontEnd.CheckDomain(solveRequest);
    auto* sp3 = dynamic_cast<translucency::Sp3Solver*>(&in.FrontEnd.GetSolver());
    if (keptMaterial && (sp3 || !in.FrontEnd.HasKeptMaterial(mesh)))
    {
      // Configure chose another solver (which forgets the kept material), or
      // sp3 (which adds the anisotropy to its own copy): read the arrays.
      if (!vtkTranslucency::ToOpticalProperties(input, material, error))
      {
        throw translucency::Error(error);
      }
      ++in.MaterialConversions;
    }
    const bool useKept = keptMaterial && !sp3 && in.FrontEnd.HasKeptMaterial(mesh);
    in.CheckModelRange(*this, input, mesh, useKept ? *in.FrontEnd.GetKeptMaterial() : material);
    if (sp3 && this->Anisotropy != 0.0)
    {
      // SP3 resolves the phase function's moments: g per tet and channel
      // (mu_s = mu_s' / (1 - g)); checked by OpticalProperties::Validate.
      material.Anisotropy.assign(material.AbsorptionCoefficient.size(), this->Anisotropy);
    }
    const translucency::OpticalProperties sp3Material =
      sp3 ? material : translucency::OpticalProperties();
    const std::vector<double> sp3Irradiance = sp3 ? irradiance : std::vector<double>();
    const bool solved = useKept
      ? in.FrontEnd.SolveKeptMaterial(mesh, std::move(irradiance), light, solveRequest, in.Result)
      : in.FrontEnd.Solve(
          mesh, std::move(material), std::move(irradiance), light, solveRequest, in.Result);
    if (!solved)
    {
      return 0; // aborted by the user
    }
    in.KeepMaterialArrays(input);
    if (sp3)
    {
      in.Sp3Readouts(*sp3, *mesh, sp3Material, sp3Irradiance);
    }
    this->AssemblyTime = in.Result.Report.SetupMilliseconds;
    this->SolveTime = in.Result.Report.SolveMilliseconds;
    in.WarnUnconverged(*this); // only with AcceptUnconverged (else the solve threw)

    // Attach, with the model this solve used (and, for a default extended
    // model, the irradiance it used: vtkOutgoingRadiance's q of eq. 3).
    in.Attach(*this, input, output);
    AttachSolvedModel(output, solvedModel, beamsTakenOut ? &solvedIrradiance : nullptr);
    this->SolvedCollimatedModel = static_cast<int>(solvedModel);
  }
  catch (const translucency::Error& e)
  {
    in.FrontEnd.Reset(); // no warm start nor incremental update from a failed solve
    in.Result.Fluence.clear();
    vtkErrorMacro(<< e.what());
    return 0;
  }
  this->UpdateProgress(1.0);
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
// The phases of RequestData.

translucency::SolveRequest vtkSolveDiffusion::Internals::MakeRequest(
  const vtkSolveDiffusion& self) const
{
  translucency::SolveRequest request;
  std::ostringstream os;
  if (!std::isfinite(self.ModulationFrequency) || self.ModulationFrequency < 0.0)
  {
    os << "ModulationFrequency " << self.ModulationFrequency
       << " Hz: expected a finite value >= 0 (0 = continuous wave)";
    throw translucency::Error(os.str());
  }
  if (!(std::isfinite(self.TimeGatesCountText) &&
        self.TimeGatesCountText == std::floor(self.TimeGatesCountText)))
  {
    os << "TimeGates: the number of gates must be a whole number, got "
       << self.TimeGatesCountText;
    throw translucency::Error(os.str());
  }
  if (!this->BadTimeSnapshots.empty())
  {
    os << "TimeSnapshots: " << this->BadTimeSnapshots.front()
       << " is not a gate (a whole number from 0 to the number of Time Gates - 1)";
    throw translucency::Error(os.str());
  }
  request.Gates.Start = self.TimeGatesStart;
  request.Gates.End = self.TimeGatesEnd;
  request.Gates.Count = self.TimeGatesCount;
  request.Gates.StepsPerGate = self.TimeStepsPerGate;
  if (self.TimeGatesCount != 0)
  {
    const std::string fault = request.Gates.Check();
    if (!fault.empty())
    {
      os << "TimeGates (" << request.Gates.Start << ", " << request.Gates.End << ", "
         << request.Gates.Count << "): " << fault;
      throw translucency::Error(os.str());
    }
    if (self.ModulationFrequency > 0.0)
    {
      os << "ModulationFrequency " << self.ModulationFrequency
         << " Hz and TimeGates together: choose the frequency domain or the time domain";
      throw translucency::Error(os.str());
    }
    request.Domain = translucency::SolveDomain::Time;
    request.Snapshots = this->TimeSnapshots;
  }
  else if (!this->TimeSnapshots.empty())
  {
    throw translucency::Error(
      "time snapshots without TimeGates: call SetTimeGates(T0, T1, N) first");
  }
  else if (self.ModulationFrequency > 0.0)
  {
    request.Domain = translucency::SolveDomain::Frequency;
    request.Frequency = self.ModulationFrequency;
  }
  request.AcceptUnconverged = self.AcceptUnconverged;
  return request;
}

void vtkSolveDiffusion::Internals::AddInteractiveSources(
  vtkSolveDiffusion& self, const translucency::TetMesh* mesh, vtkUnstructuredGrid* piece)
{
  // The listed sources and, while on, the interactive ones (the plugin's widgets).
  this->SolvedSources = this->Sources;
  std::fill(self.InteractivePencilBeamEntry, self.InteractivePencilBeamEntry + 3, 0.0);
  if (self.InteractivePointSource)
  {
    translucency::PointSource source;
    std::copy_n(self.InteractivePointSourcePosition, 3, source.Position.begin());
    std::copy_n(self.InteractivePointSourcePower, 3, source.Power.begin());
    source.Label = "interactive point source";
    this->SolvedSources.AddPointSource(source);
  }
  if (!self.InteractivePencilBeam)
  {
    return;
  }
  std::array<double, 3> point1, point2, power;
  std::copy_n(self.InteractivePencilBeamPoint1, 3, point1.begin());
  std::copy_n(self.InteractivePencilBeamPoint2, 3, point2.begin());
  std::copy_n(self.InteractivePencilBeamPower, 3, power.begin());
  translucency::PencilBeam beam;
  if (mesh)
  {
    beam = translucency::AimPencilBeam(*mesh, point1, point2, power, "interactive pencil beam");
  }
  else
  {
    // A piece of a distributed mesh: aimed by a ray cast over the whole
    // object's surface, the physical boundary all-gathered (every rank casts
    // the same ray on the same triangles: the same entry, or the same error).
    std::string error;
    translucency::BoundarySurface surface;
    if (!vtkTranslucencyDistributedIrradiance::GatherSurface(piece, surface, error))
    {
      throw translucency::Error(error);
    }
    beam = translucency::AimPencilBeam(surface.Points, surface.Triangles,
      translucency::SurfaceTolerance(surface.Points, surface.Triangles), point1, point2, power,
      "interactive pencil beam");
  }
  this->SolvedSources.AddPencilBeam(beam);
  std::copy_n(beam.Position.begin(), 3, self.InteractivePencilBeamEntry);
}

void vtkSolveDiffusion::Internals::AddInteractiveDetector(
  vtkSolveDiffusion& self, const translucency::TetMesh& mesh)
{
  // The listed detectors and, while on, the interactive one (projected).
  this->SolvedDetectors = this->Detectors;
  std::fill(
    self.InteractiveDetectorSurfacePosition, self.InteractiveDetectorSurfacePosition + 3, 0.0);
  if (!self.InteractiveDetector)
  {
    return;
  }
  const double* x = self.InteractiveDetectorPosition;
  if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]) ||
    !std::isfinite(self.InteractiveDetectorRadius) || self.InteractiveDetectorRadius < 0.0)
  {
    std::ostringstream os;
    os << "interactive detector at (" << x[0] << ", " << x[1] << ", " << x[2] << "), radius "
       << self.InteractiveDetectorRadius
       << " mm: expected a finite position and a finite radius >= 0";
    throw translucency::Error(os.str());
  }
  try
  {
    const translucency::SurfacePoint surface = translucency::FindSurfacePoint(mesh, x);
    translucency::Detector detector;
    detector.Position = surface.Position;
    detector.Radius = self.InteractiveDetectorRadius;
    detector.Label = "interactive detector";
    this->SolvedDetectors.push_back(detector);
    std::copy_n(surface.Position.begin(), 3, self.InteractiveDetectorSurfacePosition);
  }
  catch (const translucency::Error& e)
  {
    throw translucency::Error(std::string("interactive detector: ") + e.what());
  }
}

void vtkSolveDiffusion::Internals::Configure(vtkSolveDiffusion& self, int numberOfPoints)
{
  // Validate: the linear solver must be one the chosen solver accepts (its
  // registry entry's list, what the plugin's drop-down offers); a solver
  // without a choice (Monte Carlo) ignores it.
  const auto& entry = SolverEntry(self.Solver);
  // A composition "KRYLOV/PRECONDITIONER" (e.g. "cg/jacobi") names its entry.
  const std::string linearSolver = translucency::ToLower(self.LinearSolver) == "default"
    ? ""
    : translucency::ResolveLinearSolverName(self.LinearSolver);
  if (entry.Properties.HasLinearSolverChoice && !linearSolver.empty())
  {
    try
    {
      translucency::CheckLinearSolverAccepted(entry.Name, self.LinearSolver);
    }
    catch (const translucency::Error& e)
    {
      const std::string byDefault = entry.Properties.UnknownsAtVertices
        ? " for this mesh: " +
          translucency::VertexDiffusionSolver::GetDefaultLinearSolverName(numberOfPoints)
        : "";
      throw translucency::Error(std::string("LinearSolver: ") + e.what() +
        (byDefault.empty() ? "" : " (\"default\"" + byDefault + ")"));
    }
  }
  // The front end keeps the solver, detects the changed tets and
  // warm-starts; the settings go through the interface and its options hook.
  this->FrontEnd.SetSolver(entry.Name);
  // The ranks of a replicated run (the Monte Carlo's photons split over
  // them, vtkTranslucencyParallelPlan::Replicated); else in process.
  this->FrontEnd.SetCommunicator(entry.Properties.Replicated
      ? vtkTranslucency::ReplicatedSolverCommunicator()
      : translucency::Communicator());
  this->FrontEnd.SetIncrementalAssembly(self.IncrementalAssembly);
  this->FrontEnd.SetMaximumChangedFraction(self.MaximumChangedFraction);
  translucency::DiffusionSolver& solver = this->FrontEnd.GetSolver();
  solver.SetNumberOfThreads(self.NumberOfThreads);
  solver.SetRelTol(self.RelTol);
  solver.SetChangeTol(InteractiveChangeTolFor(self.RelTol));
  solver.SetMaxIter(self.MaxIter);
  solver.SetWarmStart(self.WarmStart);
  solver.SetLinearSolver(linearSolver);
  // Every solver-specific property; the selected solver reads its own and
  // leaves the others unused (they do not apply to it).
  translucency::SolverOptions options{
    { translucency::DiffusionOption::GridSpacing, self.GridSpacing },
    { translucency::DiffusionOption::MultiLevel, self.MultiLevel ? 1.0 : 0.0 },
    { translucency::DiffusionOption::TwoPointFlux, self.QuadGraphTwoPointFlux ? 1.0 : 0.0 },
    { translucency::DiffusionOption::Photons, static_cast<double>(self.NumberOfPhotons) },
    { translucency::DiffusionOption::Seed, static_cast<double>(self.Seed) },
    { translucency::DiffusionOption::Anisotropy, self.Anisotropy } };
  solver.SetOptions(options);
  const auto& read = entry.Properties.Options;
  if (self.Anisotropy != 0.0 &&
    std::find(read.begin(), read.end(), translucency::DiffusionOption::Anisotropy) == read.end())
  {
    std::vector<std::string> readers;
    for (const auto& other : translucency::GetDiffusionSolverRegistry().GetEntries())
    {
      const auto& o = other.Properties.Options;
      if (std::find(o.begin(), o.end(), translucency::DiffusionOption::Anisotropy) != o.end())
      {
        readers.push_back(other.Name);
      }
    }
    vtkWarningWithObjectMacro(&self, << "Anisotropy g = " << self.Anisotropy
      << " is ignored by the " << entry.Name << " solver: it applies to "
      << translucency::JoinNames(readers)
      << " only (the diffusion solvers use the reduced scattering coefficient, in which g is "
         "already folded)");
  }
  solver.SetProgressCallback([&self](double fraction) {
    self.UpdateProgress(0.05 + 0.9 * fraction);
    return !self.CheckAbort();
  });
}

bool vtkSolveDiffusion::Internals::SameMaterialArrays(vtkUnstructuredGrid* input) const
{
  const char* names[3] = { vtkTranslucency::AbsorptionName, vtkTranslucency::ScatteringName,
    vtkTranslucency::RefractiveIndexName };
  for (int k = 0; k < 3; ++k)
  {
    vtkDataArray* array = input ? input->GetCellData()->GetArray(names[k]) : nullptr;
    if (!array || array != this->KeptArrays[k] || array->GetMTime() != this->KeptTimes[k])
    {
      return false;
    }
  }
  return true;
}

void vtkSolveDiffusion::Internals::KeepMaterialArrays(vtkUnstructuredGrid* input)
{
  const char* names[3] = { vtkTranslucency::AbsorptionName, vtkTranslucency::ScatteringName,
    vtkTranslucency::RefractiveIndexName };
  for (int k = 0; k < 3; ++k)
  {
    vtkDataArray* array = input ? input->GetCellData()->GetArray(names[k]) : nullptr;
    this->KeptArrays[k] = array;
    this->KeptTimes[k] = array ? array->GetMTime() : 0;
  }
}

void vtkSolveDiffusion::Internals::CheckModelRange(vtkSolveDiffusion& self,
  vtkUnstructuredGrid* input, const std::shared_ptr<const translucency::TetMesh>& mesh,
  const translucency::OpticalProperties& material)
{
  // The diffusion model's range (a stochastic solver solves the transport
  // itself): a warning when the verdict changes (not at every paint stroke);
  // the mesh resolution is a note (GetMeshResolutionNote), printed by the CLI.
  vtkDataArray* absorption = input->GetCellData()->GetArray(vtkTranslucency::AbsorptionName);
  vtkDataArray* scattering = input->GetCellData()->GetArray(vtkTranslucency::ScatteringName);
  const vtkMTimeType absorptionTime = absorption ? absorption->GetMTime() : 0;
  const vtkMTimeType scatteringTime = scattering ? scattering->GetMTime() : 0;
  if (SolverEntry(self.Solver).Properties.IsStochastic)
  {
    self.ModelRangeWarning.clear();
    self.MeshResolutionNote.clear();
    this->RangeMesh.reset(); // checked again when a diffusion solver returns
    return;
  }
  if (this->RangeMesh.lock() == mesh && absorptionTime == this->RangeAbsorptionTime &&
    scatteringTime == this->RangeScatteringTime)
  {
    return;
  }
  if (this->RangeMesh.lock() != mesh)
  {
    this->Sizes = translucency::TetSizes(*mesh);
  }
  this->RangeMesh = mesh;
  this->RangeAbsorptionTime = absorptionTime;
  this->RangeScatteringTime = scatteringTime;
  const translucency::ModelRangeReport range =
    translucency::CheckModelRange(*mesh, material, &this->Sizes);
  const std::string warning = range.AlbedoMessage();
  if (!warning.empty() && warning != self.ModelRangeWarning)
  {
    vtkWarningWithObjectMacro(&self, << warning);
  }
  self.ModelRangeWarning = warning;
  self.MeshResolutionNote = range.ResolutionMessage();
}

void vtkSolveDiffusion::Internals::Sp3Readouts(const translucency::Sp3Solver& sp3,
  const translucency::TetMesh& mesh, const translucency::OpticalProperties& material,
  const std::vector<double>& irradiance)
{
  const std::vector<double>& exitance = sp3.GetExitance();
  if (exitance.size() != this->Result.Fluence.size())
  {
    return;
  }
  const std::vector<std::complex<double>>& modulated = sp3.GetComplexExitance();
  if (!modulated.empty())
  {
    // Frequency domain: the detectors' exitance amplitude and phase from
    // SP3's complex exitance; no power balance (it holds for continuous
    // wave only).
    const auto footprints = translucency::LocateDetectors(mesh, this->SolvedDetectors);
    for (std::size_t k = 0; k < footprints.size() && k < this->Result.Readings.size() &&
         k < this->Result.ExitancePhase.size();
         ++k)
    {
      std::complex<double> reading[3];
      for (const auto& [point, weight] : footprints[k].GetPointWeights(mesh))
      {
        for (int c = 0; c < 3; ++c)
        {
          reading[c] += weight * modulated[3 * static_cast<std::size_t>(point) + c];
        }
      }
      for (int c = 0; c < 3; ++c)
      {
        this->Result.Readings[k].Exitance[c] = std::abs(reading[c]);
        this->Result.ExitancePhase[k][c] = std::arg(reading[c]);
      }
    }
    return;
  }
  if (!this->SolvedDetectors.empty())
  {
    const auto footprints = translucency::LocateDetectors(mesh, this->SolvedDetectors);
    for (std::size_t k = 0; k < footprints.size() && k < this->Result.Readings.size(); ++k)
    {
      this->Result.Readings[k].Exitance = { 0.0, 0.0, 0.0 };
      for (const auto& [point, weight] : footprints[k].GetPointWeights(mesh))
      {
        for (int c = 0; c < 3; ++c)
        {
          this->Result.Readings[k].Exitance[c] +=
            weight * exitance[3 * static_cast<std::size_t>(point) + c];
        }
      }
    }
  }
  // The balance: absorbed and the boundary's injected power as for the
  // diffusion solvers, escaped from SP3's exitance (P1 integral over the
  // surface), the interior sources' power as SP3 injected it.
  const translucency::PowerBalance balance = translucency::ComputePowerBalance(
    mesh, material, this->Result.Fluence, &irradiance, this->Result.Rule);
  const std::array<double, 3> sources = sp3.GetSourcePower();
  std::array<double, 3> escaped{ 0.0, 0.0, 0.0 };
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    const double third = mesh.GetBoundaryTriangleAreas()[f] / 3.0;
    for (int a = 0; a < 3; ++a)
    {
      const std::size_t p = static_cast<std::size_t>(triangles[3 * static_cast<std::size_t>(f) + a]);
      for (int c = 0; c < 3; ++c)
      {
        escaped[c] += third * exitance[3 * p + c];
      }
    }
  }
  this->Result.HasTalliedBalance = true;
  for (int c = 0; c < 3; ++c)
  {
    this->Result.TalliedInjected[c] = balance.BoundaryInjected[c] + sources[c];
    this->Result.TalliedAbsorbed[c] = balance.Absorbed[c];
    this->Result.TalliedEscaped[c] = escaped[c];
  }
}

void vtkSolveDiffusion::Internals::WarnUnconverged(vtkSolveDiffusion& self) const
{
  static const char* channelNames[3] = { "R", "G", "B" };
  const translucency::SolverReport& report = this->Result.Report;
  for (int c = 0; c < 3; ++c)
  {
    if (!report.Converged[c] && report.Iterations[c] > 0)
    {
      vtkWarningWithObjectMacro(&self, << "channel " << channelNames[c]
        << " did not converge: relative residual " << report.Residual[c] << " after "
        << report.Iterations[c] << " iterations (RelTol " << self.RelTol << ", MaxIter "
        << self.MaxIter << "; kept because AcceptUnconverged is on)");
    }
  }
}

namespace
{
/// The time-of-flight field arrays: gate centres and, per detector k,
/// DetectorFluenceTPSF<k>, DetectorExitanceTPSF<k> (and their standard
/// errors for a stochastic solver).
void AttachGateArrays(vtkUnstructuredGrid* output, const translucency::SolveResult& result,
  std::size_t numberOfDetectors)
{
  const translucency::TimeResolvedResult& time = result.Time;
  vtkNew<vtkDoubleArray> centres;
  centres->SetName("TimeGateCentres");
  for (int g = 0; g < time.Gates.Count; ++g)
  {
    centres->InsertNextValue(time.Gates.GetGateCentre(g));
  }
  output->GetFieldData()->AddArray(centres);
  for (std::size_t k = 0; k < numberOfDetectors; ++k)
  {
    std::vector<double> fluence, exitance, fluenceError, exitanceError;
    for (const auto& gate : time.Readings)
    {
      for (int c = 0; c < 3; ++c)
      {
        fluence.push_back(gate[k].Fluence[c]);
        exitance.push_back(gate[k].Exitance[c]);
      }
    }
    for (const auto& gate : result.GateErrors) // stochastic solvers only
    {
      for (int c = 0; c < 3; ++c)
      {
        fluenceError.push_back(gate[k].Fluence[c]);
        exitanceError.push_back(gate[k].Exitance[c]);
      }
    }
    for (const auto& [name, values] : { std::make_pair("DetectorFluenceTPSF", &fluence),
           std::make_pair("DetectorExitanceTPSF", &exitance),
           std::make_pair("DetectorFluenceTPSFStandardError", &fluenceError),
           std::make_pair("DetectorExitanceTPSFStandardError", &exitanceError) })
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
}

void vtkSolveDiffusion::Internals::Attach(
  vtkSolveDiffusion& self, vtkUnstructuredGrid* input, vtkUnstructuredGrid* output)
{
  translucency::SolveResult& result = this->Result;
  output->ShallowCopy(input);
  auto attach = [output](const char* name, const std::vector<double>& values) {
    if (values.size() == 3 * static_cast<size_t>(output->GetNumberOfPoints()))
    {
      vtkDataArray* array = vtkTranslucency::NewTripleArray(name, values);
      output->GetPointData()->AddArray(array);
      array->Delete();
    }
  };
  attach(vtkTranslucency::FluenceName, result.Fluence);
  result.Fluence = std::vector<double>(); // held by the output
  attach("FluenceStandardError", result.Report.FluenceStandardError);
  attach("CollimatedFluence", result.Report.CollimatedFluence);
  attach("CollimatedFluencePhase", result.Report.CollimatedFluencePhase);
  if (result.Rule == translucency::Fresnel::BoundaryRule::Moments)
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
  // sp3 in continuous wave: its composite moments, which vtkOutgoingRadiance
  // reads for the P3 radiance (Sp3OutgoingRadiance) instead of eq. 3.
  output->GetPointData()->RemoveArray("SP3Phi1"); // not this solve's
  output->GetPointData()->RemoveArray("SP3Phi2");
  if (const auto* sp3 = dynamic_cast<const translucency::Sp3Solver*>(&this->FrontEnd.GetSolver()))
  {
    if (result.Amplitude.empty() && sp3->GetComplexExitance().empty())
    {
      attach("SP3Phi1", sp3->GetPhi1());
      attach("SP3Phi2", sp3->GetPhi2());
    }
  }
  attach("MonteCarloRadiance", result.Report.Radiance);
  attach("MonteCarloRadianceStandardError", result.Report.RadianceStandardError);
  attach("FluenceAmplitude", result.Amplitude);
  attach("FluencePhase", result.Phase);
  const translucency::TimeResolvedResult& time = result.Time;
  for (std::size_t k = 0; k < time.Snapshots.size(); ++k)
  {
    attach(("FluenceGate" + std::to_string(time.SnapshotGates[k])).c_str(), time.Snapshots[k]);
  }
  if (this->SolvedDomain == translucency::SolveDomain::Time)
  {
    AttachGateArrays(output, result, this->SolvedDetectors.size());
  }
  AttachDetectorArrays(output, this->SolvedDetectors, result.Readings, result.ReadingErrors,
    result.FluencePhase, result.ExitancePhase,
    this->SolvedDomain == translucency::SolveDomain::Frequency);
  if (self.InteractiveDetector && !result.Readings.empty())
  {
    // What was asked for: the handle's position (DetectorPosition has the surface point).
    if (vtkDataArray* requested = output->GetFieldData()->GetArray("DetectorRequestedPosition"))
    {
      requested->SetTuple(requested->GetNumberOfTuples() - 1, self.InteractiveDetectorPosition);
    }
  }
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
    std::array<double, 3> in{}, abs{}, esc{};
    translucency::DiffusionFrontEnd::ComputePowerBalance(*mesh, material, fluence, irradiance,
      &this->Internal->SolvedSources, this->Internal->Result, this->Internal->SolvedDomain, in,
      abs, esc);
    std::copy_n(in.begin(), 3, injected);
    std::copy_n(abs.begin(), 3, absorbed);
    std::copy_n(esc.begin(), 3, escaped);
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
  in.Result = translucency::SolveResult();
  in.SolvedDomain = translucency::SolveDomain::ContinuousWave;
  in.FrontEnd.Reset();
  this->TopologyTime = this->AssemblyTime = this->SolveTime = 0.0;
  std::string error;
  try
  {
    // The listed sources and the interactive ones (the pencil beam aimed on
    // the all-gathered surface: the same on every rank).
    in.AddInteractiveSources(*this, nullptr, input);
  }
  catch (const translucency::Error& e)
  {
    error = e.what(); // the same on every rank (collective aim)
  }
  if (!error.empty())
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  in.SolvedDetectors = in.Detectors;
  // The lights and the collimated model, the same on every rank (an empty
  // piece may carry no field data), and a default choice decided as in one
  // process (DecideDefaultCollimatedModel): its directional lights' part is
  // taken out of the irradiance by the distributed solve.
  translucency::DiffusionProblem light;
  if (input)
  {
    ReadLights(input, light);
  }
  int byDefault = input && ChosenByDefault(input->GetFieldData()) ? 1 : 0;
  vtkTranslucencyDistributedSolve::AgreeOnLights(input, light, byDefault);
  bool takeOutBeams = false;
  if (byDefault)
  {
    light.Collimated = DefaultModelFor(light, !in.SolvedSources.GetPencilBeams().empty(),
      this->GetSolverName());
    for (const translucency::LightSource& source : light.Lights)
    {
      takeOutBeams = takeOutBeams ||
        (translucency::IsExtendedCollimatedModel(light.Collimated) &&
          source.Type == translucency::LightSource::Kind::Directional);
    }
  }
  std::vector<double> fluence, solvedIrradiance;
  translucency::SolverReport& report = in.Result.Report;
  if (!in.Distributed.Solve(input, SolverEntry(this->Solver).Name, this->RelTol,
        InteractiveChangeTolFor(this->RelTol), this->MaxIter, this->WarmStart,
        this->NumberOfThreads, this->AcceptUnconverged != 0, &in.SolvedSources, in.Detectors,
        light, takeOutBeams, fluence, solvedIrradiance, in.Result.Readings, report, error))
  {
    in.Result = translucency::SolveResult();
    vtkErrorMacro(<< error);
    return 0;
  }
  // Never a non-converged result: the distributed solver re-solved after a
  // full set-up; iterations and residuals are global, so every rank agrees.
  static const char* channelNames[3] = { "R", "G", "B" };
  std::ostringstream unconverged;
  for (int c = 0; c < 3; ++c)
  {
    if (!report.Converged[c] && report.Iterations[c] > 0)
    {
      unconverged << (unconverged.tellp() > 0 ? "; " : "") << "channel " << channelNames[c]
                  << ": relative residual " << report.Residual[c] << " after "
                  << report.Iterations[c] << " iterations";
    }
  }
  if (unconverged.tellp() > 0 && !this->AcceptUnconverged)
  {
    vtkErrorMacro(<< "the distributed " << report.Solver
                  << " solve did not converge, also after a full set-up (" << unconverged.str()
                  << "; RelTol " << this->RelTol << ", MaxIter " << this->MaxIter
                  << "): no result. Raise MaxIter or RelTol");
    return 0;
  }
  in.Result.FluencePhase.assign(in.Result.Readings.size(), { 0.0, 0.0, 0.0 });
  in.Result.ExitancePhase.assign(in.Result.Readings.size(), { 0.0, 0.0, 0.0 });
  this->AssemblyTime = report.SetupMilliseconds;
  this->SolveTime = report.SolveMilliseconds;
  in.WarnUnconverged(*this);
  // The Robin rule of the model (DiffusionFrontEnd::SolveOnce: Moments for
  // extended-moments), read by Attach for vtkOutgoingRadiance.
  in.Result.Rule = light.Collimated == translucency::CollimatedModel::ExtendedMoments
    ? translucency::Fresnel::BoundaryRule::Moments
    : translucency::Fresnel::BoundaryRule::Fit;
  this->SolvedCollimatedModel = static_cast<int>(light.Collimated);
  if (input)
  {
    in.Result.Fluence = std::move(fluence);
    in.Attach(*this, input, output);
    // The model this solve used and, for a default extended model, the
    // irradiance it used (vtkOutgoingRadiance's q of eq. 3), as in one process.
    const bool attachIrradiance = takeOutBeams &&
      solvedIrradiance.size() == 3 * static_cast<size_t>(input->GetNumberOfPoints());
    AttachSolvedModel(output, light.Collimated, attachIrradiance ? &solvedIrradiance : nullptr);
  }
  else
  {
    // On every rank (an empty piece too): the field arrays vtkDetectorReadings reads.
    AttachDetectorArrays(output, in.Detectors, in.Result.Readings, in.Result.ReadingErrors,
      in.Result.FluencePhase, in.Result.ExitancePhase, false);
  }
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
  os << indent << "AcceptUnconverged: " << this->AcceptUnconverged << "\n";
  os << indent << "TimeGates: " << this->TimeGatesStart << ", " << this->TimeGatesEnd << " ns, "
     << this->TimeGatesCount << " gates\n";
  os << indent << "TimeStepsPerGate: " << this->TimeStepsPerGate << "\n";
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}
