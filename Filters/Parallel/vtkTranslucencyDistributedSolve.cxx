#include "vtkTranslucencyDistributedSolve.h"


#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
#include "DiffusionFrontEnd.h"
#include "DistributedCollimatedSource.h"
#include "HypreSolver.h" // MakeCommunicator: the MPI side of translucency::Communicator
#include "Error.h"
#include "vtkTranslucencyDistributedIrradiance.h"
#include "vtkTranslucencyMPI.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyPieceFaces.h"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDataSetAttributes.h>
#include <vtkMPI.h>
#include <vtkMPICommunicator.h>
#include <vtkMultiProcessController.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

struct vtkTranslucencyDistributedSolve::Impl
{
  /// The core's one front end, on the controller's communicator: it takes
  /// the registry's distributed variant of the solver (trait Distributed).
  translucency::DiffusionFrontEnd FrontEnd;
  /// The piece's mesh (owned tets), kept while its points and tets are the
  /// same: the front end keeps the hierarchy for the same mesh object.
  std::shared_ptr<const translucency::TetMesh> Mesh;
  std::vector<double> Points;
  std::vector<int> Tets;
  /// The piece's geometry key (vtkTranslucency::PieceGeometryKey) and owned
  /// cells of Mesh: an unchanged piece (a relight, a paint) is not
  /// converted again.
  std::string Geometry;
  std::vector<vtkIdType> Kept;
  translucency::SolveResult Result;
  bool Solved = false;
  /// The directional lights' irradiance taken out of a default model's
  /// Irradiance: the gathered surface and each light's terms kept across
  /// executions (a relight computes the changed light only).
  vtkTranslucencyDistributedIrradiance::State BeamIrradiance;
  /// What the last TakeOutBeams was of (the piece, its RefractiveIndex and
  /// Irradiance arrays and their times, the directional lights, the shadows)
  /// and its result: a paint, which changes none of them, reuses it when
  /// every rank can (TakeOutBeamsOnce).
  struct BeamInputs
  {
    std::string Geometry;
    vtkDataArray* Eta = nullptr;
    vtkMTimeType EtaTime = 0;
    vtkDataArray* Irradiance = nullptr;
    vtkMTimeType IrradianceTime = 0;
    std::vector<translucency::LightSource> Beams;
    bool Shadows = false;
    bool operator==(const BeamInputs& other) const;
  };
  bool HaveBeamFree = false;
  BeamInputs BeamFreeInputs;
  std::vector<double> BeamFree;
  /// Collective: `irradiance` without the directional lights' (TakeOutBeams),
  /// or the kept result when its inputs are the same on every rank.
  void TakeOutBeamsOnce(MPI_Comm comm, vtkUnstructuredGrid* input, const std::string& geometry,
    const translucency::DiffusionProblem& lights, std::vector<double>& irradiance);
  /// The coefficient arrays of the last successful solve and their times:
  /// when the next input carries the same ones, unmodified, on the same
  /// piece (a relight), the front end's kept material is solved again
  /// instead of converting, validating and comparing the piece's material
  /// (issues 31, 32; vtkSolveDiffusion's serial rule).
  long long MaterialConversions = 0;
  long long BeamReuses = 0; ///< TakeOutBeamsOnce's reuses of its kept result
  vtkDataArray* MaterialArrays[3] = { nullptr, nullptr, nullptr };
  vtkMTimeType MaterialTimes[3] = { 0, 0, 0 };

  bool SameMaterialArrays(vtkUnstructuredGrid* input) const
  {
    for (int k = 0; k < 3; ++k)
    {
      vtkDataArray* array = input ? input->GetCellData()->GetArray(MaterialArrayName(k)) : nullptr;
      if (!array || array != this->MaterialArrays[k] || array->GetMTime() != this->MaterialTimes[k])
        return false;
    }
    return true;
  }
  void KeepMaterialArrays(vtkUnstructuredGrid* input)
  {
    for (int k = 0; k < 3; ++k)
    {
      vtkDataArray* array = input ? input->GetCellData()->GetArray(MaterialArrayName(k)) : nullptr;
      this->MaterialArrays[k] = array;
      this->MaterialTimes[k] = array ? array->GetMTime() : 0;
    }
  }
  /// Collective-free, may throw translucency::Error: the piece's geometry
  /// converted (points, owned tets, Kept) and its TetMesh kept or acquired.
  void SetPieceMesh(vtkUnstructuredGrid* input, const std::string& geometry,
    std::vector<double>& points, std::vector<int>& tets);
  /// Collective-free, may throw translucency::Error: the piece's material
  /// (unless the kept one is solved again: returns true) and irradiance.
  bool ReadPieceValues(vtkUnstructuredGrid* input, bool reuse,
    translucency::OpticalProperties& material, std::vector<double>& irradiance);
  static const char* MaterialArrayName(int k)
  {
    static const char* names[3] = { vtkTranslucency::AbsorptionName,
      vtkTranslucency::ScatteringName, vtkTranslucency::RefractiveIndexName };
    return names[k];
  }
};

namespace
{
/// This rank's piece's geometry in the core's types: its points and owned
/// tets (ghost copies left out), and the owned cells' ids. Throws
/// translucency::Error (on this rank only).
void ConvertGeometry(vtkUnstructuredGrid* input, std::vector<double>& points,
  std::vector<int>& tets, std::vector<vtkIdType>& kept)
{
  std::string local;
  std::vector<int> cells;
  const vtkIdType numPoints = input ? input->GetNumberOfPoints() : 0;
  if (numPoints > 0 && !vtkTranslucency::ToTetArrays(input, points, cells, local))
  {
    throw translucency::Error(local);
  }
  // Owned cells only: a ghost copy is another rank's tet.
  kept = vtkTranslucency::OwnedTets(input, cells, tets);
}

/// The owned cells' material and the points' irradiance. Throws
/// translucency::Error (on this rank only).
void ConvertValues(vtkUnstructuredGrid* input, const std::vector<vtkIdType>& kept,
  bool readMaterial, translucency::OpticalProperties& material, std::vector<double>& irradiance)
{
  std::string local;
  const vtkIdType numPoints = input ? input->GetNumberOfPoints() : 0;
  if (!kept.empty() && readMaterial)
  {
    translucency::OpticalProperties all;
    if (!vtkTranslucency::ToOpticalProperties(input, all, local))
    {
      throw translucency::Error(local);
    }
    material.AbsorptionCoefficient.reserve(3 * kept.size());
    material.ReducedScatteringCoefficient.reserve(3 * kept.size());
    material.RefractiveIndex.reserve(kept.size());
    for (vtkIdType c : kept)
    {
      for (int k = 0; k < 3; ++k)
      {
        material.AbsorptionCoefficient.push_back(all.AbsorptionCoefficient[3 * c + k]);
        material.ReducedScatteringCoefficient.push_back(
          all.ReducedScatteringCoefficient[3 * c + k]);
      }
      material.RefractiveIndex.push_back(all.RefractiveIndex[c]);
    }
  }
  if (!kept.empty() &&
    !vtkTranslucency::ReadPointArray(input, vtkTranslucency::IrradianceName, 3, irradiance, local))
  {
    if (local.find("no point array") != std::string::npos)
    {
      local += ": compute it with vtkSurfaceIrradiance or supply your own";
    }
    throw translucency::Error(local);
  }
  if (kept.empty())
  {
    irradiance.assign(3 * static_cast<size_t>(numPoints), 0.0); // no tet reads it
  }
}
}

namespace
{
/// Whether `kept` (the owned cells) is every cell of `input`, in order.
bool OwnsEveryCell(vtkUnstructuredGrid* input, const std::vector<vtkIdType>& kept)
{
  if (!input || static_cast<vtkIdType>(kept.size()) != input->GetNumberOfCells())
    return false;
  for (std::size_t c = 0; c < kept.size(); ++c)
  {
    if (kept[c] != static_cast<vtkIdType>(c))
      return false;
  }
  return true;
}

/**
 * Collective. The default model's irradiance: `irradiance` (every light)
 * without the directional lights' projected irradiance at this rank's
 * points, as vtkSolveDiffusion's serial DecideDefaultCollimatedModel takes
 * it out (term for term the serial ComputeProjectedIrradiance: the
 * distributed Surface Irradiance's kernel). Throws translucency::Error (the
 * same on every rank).
 */
void TakeOutBeams(vtkUnstructuredGrid* input, const translucency::DiffusionProblem& lights,
  vtkTranslucencyDistributedIrradiance::State& state, std::vector<double>& irradiance)
{
  std::vector<translucency::LightSource> beams;
  for (const translucency::LightSource& light : lights.Lights)
  {
    if (light.Type == translucency::LightSource::Kind::Directional)
      beams.push_back(light);
  }
  std::vector<double> q;
  vtkTranslucencyDistributedIrradiance::Report report;
  std::string error;
  if (!vtkTranslucencyDistributedIrradiance::Compute(
        input, beams, 0.0, 0, lights.Shadows, {}, q, report, error, &state))
  {
    throw translucency::Error(error.empty() ? std::string("aborted") : error);
  }
  if (q.size() != irradiance.size())
  {
    // (An empty piece: no tet reads its irradiance.)
    return;
  }
  for (std::size_t i = 0; i < irradiance.size(); ++i)
  {
    // What is left is the other lights' q; a point only the beams reach
    // keeps a rounding residue of their sum, set to 0 (the serial rule).
    const double rest = irradiance[i] - q[i];
    irradiance[i] = rest > 1e-12 * irradiance[i] ? rest : 0.0;
  }
}
}

bool vtkTranslucencyDistributedSolve::Impl::BeamInputs::operator==(const BeamInputs& other) const
{
  auto sameLight = [](const translucency::LightSource& a, const translucency::LightSource& b) {
    return a.Type == b.Type && a.Direction == b.Direction && a.Position == b.Position &&
      a.Power == b.Power && a.SpotCutoff == b.SpotCutoff && a.SpotExponent == b.SpotExponent;
  };
  return this->Geometry == other.Geometry && this->Eta == other.Eta &&
    this->EtaTime == other.EtaTime && this->Irradiance == other.Irradiance &&
    this->IrradianceTime == other.IrradianceTime && this->Shadows == other.Shadows &&
    std::equal(this->Beams.begin(), this->Beams.end(), other.Beams.begin(), other.Beams.end(),
      sameLight);
}

void vtkTranslucencyDistributedSolve::Impl::TakeOutBeamsOnce(MPI_Comm comm,
  vtkUnstructuredGrid* input, const std::string& geometry,
  const translucency::DiffusionProblem& lights, std::vector<double>& irradiance)
{
  BeamInputs inputs;
  inputs.Geometry = geometry;
  if (input)
  {
    inputs.Eta = input->GetCellData()->GetArray(vtkTranslucency::RefractiveIndexName);
    inputs.Irradiance = input->GetPointData()->GetArray(vtkTranslucency::IrradianceName);
  }
  inputs.EtaTime = inputs.Eta ? inputs.Eta->GetMTime() : 0;
  inputs.IrradianceTime = inputs.Irradiance ? inputs.Irradiance->GetMTime() : 0;
  for (const translucency::LightSource& light : lights.Lights)
  {
    if (light.Type == translucency::LightSource::Kind::Directional)
      inputs.Beams.push_back(light);
  }
  inputs.Shadows = lights.Shadows;
  // The same arrays (objects and modification times), piece and lights give
  // the same result; a paint changes only the coefficient arrays.
  if (vtkTranslucency::SameOnEveryRank(comm,
        this->HaveBeamFree && inputs == this->BeamFreeInputs &&
          this->BeamFree.size() == irradiance.size()))
  {
    irradiance = this->BeamFree;
    ++this->BeamReuses;
    return;
  }
  this->HaveBeamFree = false;
  TakeOutBeams(input, lights, this->BeamIrradiance, irradiance);
  this->BeamFree = irradiance;
  this->BeamFreeInputs = std::move(inputs);
  this->HaveBeamFree = true;
}

void vtkTranslucencyDistributedSolve::AgreeOnLights(
  vtkUnstructuredGrid* input, translucency::DiffusionProblem& problem, int& flag)
{
  const MPI_Comm* handle = vtkTranslucency::MPIHandle(vtkTranslucencyCommunicator::World());
  if (!handle)
  {
    return; // one process
  }
  translucency::AgreeOnLights(*handle, input && input->GetNumberOfCells() > 0, problem.Lights,
    problem.UniformIrradiance, problem.Shadows, problem.Collimated, flag);
}

void vtkTranslucencyDistributedSolve::Impl::SetPieceMesh(vtkUnstructuredGrid* input,
  const std::string& geometry, std::vector<double>& points, std::vector<int>& tets)
{
  this->Geometry.clear();
  std::vector<vtkIdType> kept;
  ConvertGeometry(input, points, tets, kept);
  // The piece's TetMesh, kept while the piece is the same (a relight, a paint).
  if (tets.empty())
  {
    this->Mesh.reset();
  }
  else if (!this->Mesh || points != this->Points || tets != this->Tets)
  {
    this->Mesh.reset();
    if (OwnsEveryCell(input, kept))
    {
      // No ghost cells: the piece's tets are its cells, in order, and the
      // topology is the one the distributed Surface Irradiance already
      // built for this piece (vtkTranslucency::AcquireTetMesh's cache;
      // vtkTranslucencyPieceFaces), not built a second time.
      std::string acquireError;
      this->Mesh = vtkTranslucency::AcquireTetMesh(input, acquireError);
      if (!this->Mesh || this->Mesh->GetTets() != tets)
      {
        this->Mesh.reset(); // (not expected) built from the owned tets below
      }
    }
    if (!this->Mesh)
    {
      auto mesh = std::make_shared<translucency::TetMesh>();
      mesh->SetGeometry(points, tets);
      this->Mesh = std::move(mesh);
    }
    this->Points = points;
    this->Tets = tets;
  }
  this->Kept = std::move(kept);
  if (this->Mesh)
    this->Geometry = geometry;
}

bool vtkTranslucencyDistributedSolve::Impl::ReadPieceValues(vtkUnstructuredGrid* input,
  bool reuse, translucency::OpticalProperties& material, std::vector<double>& irradiance)
{
  // A relight: the same coefficient arrays, unmodified, on the same piece.
  const bool kept = reuse && this->Mesh && this->FrontEnd.HasKeptMaterial(this->Mesh);
  bool sameMaterial = kept && this->SameMaterialArrays(input);
  if (kept && !sameMaterial && OwnsEveryCell(input, this->Kept))
  {
    // A paint stroke on a piece without ghost cells (its cells are the
    // mesh's tets, in order): the new arrays compared with the kept material
    // in place and the changed tets written into it, as in one process
    // (DiffusionFrontEnd::UpdateKeptMaterial), instead of copying,
    // validating and gathering the piece's material.
    const vtkTranslucency::CoefficientValues values =
      vtkTranslucency::CoefficientArraysInPlace(input, this->Mesh->GetNumberOfTets());
    sameMaterial = this->FrontEnd.UpdateKeptMaterial(
      this->Mesh, values.Absorption, values.Scattering, values.RefractiveIndex);
  }
  this->KeepMaterialArrays(nullptr); // until this solve succeeds
  ConvertValues(input, this->Kept, !sameMaterial, material, irradiance);
  this->MaterialConversions += sameMaterial || this->Kept.empty() ? 0 : 1;
  return sameMaterial;
}

bool vtkTranslucencyDistributedSolve::Solve(vtkUnstructuredGrid* input,
  const std::string& discretization, double relTol, double changeTol, int maxIter, bool warmStart,
  int threads,
  bool acceptUnconverged, const translucency::Sources* sources,
  const std::vector<translucency::Detector>& detectors,
  const translucency::DiffusionProblem& lights, bool takeOutBeams, std::vector<double>& fluence,
  std::vector<double>& solvedIrradiance, std::vector<translucency::DetectorReading>& readings,
  translucency::SolverReport& report, std::string& error)
{
  readings.clear();
  solvedIrradiance.clear();
  Impl& in = *this->Internal;
  in.Solved = false;
  const MPI_Comm* handle = vtkTranslucency::MPIHandle(vtkTranslucencyCommunicator::World());
  if (!handle)
  {
    handle = translucency::GetSelfCommunicator(); // one process: a communicator of size one
  }
  const MPI_Comm comm = *handle;
  std::string local;
  std::vector<double> points;
  std::vector<int> tets;
  translucency::OpticalProperties material;
  std::vector<double> irradiance;
  std::vector<translucency::PointKey> keys;
  // The piece's geometry is converted again only when it changed
  // (vtkTranslucency::PieceGeometryKey: its VTK objects and their times).
  const std::string geometry = vtkTranslucency::PieceGeometryKey(input);
  const bool reuse = in.Mesh && !in.Geometry.empty() && geometry == in.Geometry;
  bool sameMaterial = false;
  try
  {
    if (!reuse)
    {
      in.SetPieceMesh(input, geometry, points, tets);
    }
    sameMaterial = in.ReadPieceValues(input, reuse, material, irradiance);
  }
  catch (const std::exception& e)
  {
    local = e.what();
    in.Mesh.reset();
    in.Geometry.clear();
  }
  // Global ids when every rank with points has them, else coordinates.
  vtkTranslucency::MakePointKeys(comm, input, reuse ? in.Points : points, !local.empty(), keys);
  try
  {
    translucency::AgreeOnError(comm, local);
    if (takeOutBeams)
    {
      in.TakeOutBeamsOnce(comm, input, geometry, lights, irradiance);
      solvedIrradiance = irradiance;
    }
    // The solver by name, its distributed variant by the registry's trait.
    in.FrontEnd.SetSolver(discretization);
    in.FrontEnd.SetCommunicator(translucency::MakeCommunicator(handle));
    if (sameMaterial && !in.FrontEnd.HasKeptMaterial(in.Mesh))
    {
      // Another solver or communicator forgot the kept material: the same
      // arrays (valid at the last solve) are read after all.
      std::vector<double> unused;
      ConvertValues(input, in.Kept, true, material, unused);
      ++in.MaterialConversions;
      sameMaterial = false;
    }
    translucency::DiffusionSolver& solver = in.FrontEnd.GetSolver();
    solver.SetRelTol(relTol);
    solver.SetChangeTol(changeTol);
    solver.SetMaxIter(maxIter);
    solver.SetWarmStart(warmStart);
    solver.SetNumberOfThreads(threads);
    translucency::DiffusionProblem light;
    light.Lights = lights.Lights;
    light.UniformIrradiance = lights.UniformIrradiance;
    light.Shadows = lights.Shadows;
    light.Collimated = lights.Collimated;
    light.InteriorSources = sources;
    light.PointKeys = &keys;
    translucency::SolveRequest request;
    request.Detectors = detectors;
    request.AcceptUnconverged = acceptUnconverged;
    in.Result = translucency::SolveResult();
    if (sameMaterial)
    {
      in.FrontEnd.SolveKeptMaterial(in.Mesh, std::move(irradiance), light, request, in.Result);
    }
    else
    {
      in.FrontEnd.Solve(in.Mesh, std::move(material), std::move(irradiance), light, request,
        in.Result);
    }
  }
  catch (const translucency::Error& e)
  {
    local = e.what();
  }
  // A failure inside the collective solve is already the same on every
  // rank; one after it (a check of this rank's field) is agreed here.
  int failed = local.empty() ? 0 : 1, allFailed = 0, anyFailed = 0;
  MPI_Allreduce(&failed, &allFailed, 1, MPI_INT, MPI_MIN, comm);
  MPI_Allreduce(&failed, &anyFailed, 1, MPI_INT, MPI_MAX, comm);
  if (anyFailed && !allFailed)
  {
    try
    {
      translucency::AgreeOnError(comm, local);
    }
    catch (const translucency::Error& e)
    {
      local = e.what();
    }
  }
  if (anyFailed)
  {
    error = local;
    in.Result = translucency::SolveResult();
    in.FrontEnd.Reset();
    in.Mesh.reset();
    in.Geometry.clear();
    return false;
  }
  in.KeepMaterialArrays(input);
  fluence = std::move(in.Result.Fluence);
  in.Result.Fluence.clear();
  readings = in.Result.Readings;
  report = in.Result.Report;
  in.Solved = true;
  return true;
}

long long vtkTranslucencyDistributedSolve::GetNumberOfMaterialConversions() const
{
  return this->Internal->MaterialConversions;
}

long long vtkTranslucencyDistributedSolve::GetNumberOfBeamIrradianceReuses() const
{
  return this->Internal->BeamReuses;
}

bool vtkTranslucencyDistributedSolve::GetPowerBalance(
  double injected[3], double absorbed[3], double escaped[3]) const
{
  const Impl& in = *this->Internal;
  if (!in.Solved || !in.Result.HasTalliedBalance)
  {
    return false;
  }
  // The distributed solver's balance, summed over the ranks (its tallies).
  for (int c = 0; c < 3; ++c)
  {
    injected[c] = in.Result.TalliedInjected[c];
    absorbed[c] = in.Result.TalliedAbsorbed[c];
    escaped[c] = in.Result.TalliedEscaped[c];
  }
  return true;
}

#else // no distributed solve in this build

struct vtkTranslucencyDistributedSolve::Impl
{
};

void vtkTranslucencyDistributedSolve::AgreeOnLights(
  vtkUnstructuredGrid*, translucency::DiffusionProblem&, int&)
{
}

bool vtkTranslucencyDistributedSolve::Solve(vtkUnstructuredGrid*, const std::string&, double,
  double, int, bool, int, bool, const translucency::Sources*, const std::vector<translucency::Detector>&,
  const translucency::DiffusionProblem&, bool, std::vector<double>&, std::vector<double>&,
  std::vector<translucency::DetectorReading>&, translucency::SolverReport&, std::string& error)
{
  error = "this build has no distributed solve (hypre or VTK's ParallelMPI missing)";
  return false;
}

bool vtkTranslucencyDistributedSolve::GetPowerBalance(double*, double*, double*) const
{
  return false;
}

long long vtkTranslucencyDistributedSolve::GetNumberOfMaterialConversions() const
{
  return 0;
}

long long vtkTranslucencyDistributedSolve::GetNumberOfBeamIrradianceReuses() const
{
  return 0;
}

#endif

vtkTranslucencyDistributedSolve::vtkTranslucencyDistributedSolve()
  : Internal(new Impl)
{
}

vtkTranslucencyDistributedSolve::~vtkTranslucencyDistributedSolve() = default;

