#include "vtkTranslucencyDistributedIrradiance.h"


#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
#include "DistributedBoundarySurface.h"
#include "Error.h"
#include "TetMesh.h"
#include "Timer.h"
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

#include <algorithm>
#include <memory>

struct vtkTranslucencyDistributedIrradiance::State::Impl
{
  bool Valid = false;
  vtkTranslucency::PieceIdentity Identity; ///< of the piece the surface is of
  vtkIdType NumberOfPoints = 0;
  std::vector<int> SurfacePoint; ///< per piece point: its surface point, -1 if none
  std::vector<int> Wanted;       ///< this rank's distinct surface points (sorted)
  std::vector<int> WantedIndex;  ///< per piece point: its index in Wanted, -1 if none
  translucency::SurfacePointIrradianceCache Kernel;
  Report Gathered;               ///< the gather's figures
  bool SurfaceGathered = false;  ///< by the last Compute
};

vtkTranslucencyDistributedIrradiance::State::State()
  : In(new Impl)
{
}

vtkTranslucencyDistributedIrradiance::State::~State() = default;

int vtkTranslucencyDistributedIrradiance::State::GetNumberOfLightsComputed() const
{
  return this->In->Kernel.GetNumberOfLightsComputed();
}

bool vtkTranslucencyDistributedIrradiance::State::GetUniformComputed() const
{
  return this->In->Kernel.GetUniformComputed();
}

bool vtkTranslucencyDistributedIrradiance::State::GetSurfaceGathered() const
{
  return this->In->SurfaceGathered;
}

void vtkTranslucencyDistributedIrradiance::State::Clear()
{
  this->In.reset(new Impl);
}

namespace
{
/// Collective. Gathers the physical boundary surface into `state` (this
/// rank's points on it, their sample rotations). Throws translucency::Error
/// (the same on every rank).
void GatherInto(MPI_Comm comm, vtkUnstructuredGrid* input,
  vtkTranslucencyDistributedIrradiance::State::Impl& state)
{
  std::string local;
  vtkTranslucency::PieceFaces faces;
  try
  {
    vtkTranslucency::ExtractPieceFaces(input, faces);
  }
  catch (const std::exception& e)
  {
    local = e.what();
  }
  const std::vector<double>& points = faces.Points;
  const long long ownedTets = faces.OwnedTets;
  long long totalTets = 0;
  std::vector<translucency::PointKey> keys;
  vtkTranslucency::MakePointKeys(comm, input, points, !local.empty(), keys);
  MPI_Allreduce(&ownedTets, &totalTets, 1, MPI_LONG_LONG, MPI_SUM, comm);
  translucency::AgreeOnError(comm, local);
  if (totalTets == 0)
  {
    throw translucency::Error("the input mesh is empty (no points or no cells)");
  }
  translucency::BoundarySurface surface;
  std::vector<double> rotations;
  translucency::BoundarySurfaceReport gathered;
  translucency::GatherBoundarySurface(comm, points, keys, faces.Used, faces.Triangles,
    faces.TriangleEta, faces.TriangleTets, surface, state.SurfacePoint, rotations, gathered);
  state.Gathered = vtkTranslucencyDistributedIrradiance::Report();
  state.Gathered.SurfaceTriangles = gathered.Triangles;
  state.Gathered.SurfacePoints = gathered.Points;
  state.Gathered.GatheredBytes = gathered.GatheredBytes;
  state.Gathered.GatherMilliseconds = gathered.Milliseconds;

  // This rank's distinct surface points, computed once each.
  state.Wanted.clear();
  for (int s : state.SurfacePoint)
  {
    if (s >= 0)
      state.Wanted.push_back(s);
  }
  std::sort(state.Wanted.begin(), state.Wanted.end());
  state.Wanted.erase(std::unique(state.Wanted.begin(), state.Wanted.end()), state.Wanted.end());
  // Each piece point's place among them, found once per gather (not per
  // execution: a relight or a paint reads it).
  state.WantedIndex.assign(state.SurfacePoint.size(), -1);
  for (size_t i = 0; i < state.SurfacePoint.size(); ++i)
  {
    const int s = state.SurfacePoint[i];
    if (s >= 0)
      state.WantedIndex[i] = static_cast<int>(
        std::lower_bound(state.Wanted.begin(), state.Wanted.end(), s) - state.Wanted.begin());
  }
  std::vector<double> wantedRotations(state.Wanted.size());
  for (size_t k = 0; k < state.Wanted.size(); ++k)
    wantedRotations[k] = rotations[static_cast<size_t>(state.Wanted[k])];
  local.clear();
  try
  {
    state.Kernel.SetSurface(std::move(surface), state.Wanted, std::move(wantedRotations));
  }
  catch (const translucency::Error& e)
  {
    local = e.what();
  }
  translucency::AgreeOnError(comm, local);
}
}

bool vtkTranslucencyDistributedIrradiance::Compute(vtkUnstructuredGrid* input,
  const std::vector<translucency::LightSource>& lights, double uniformIrradiance,
  int uniformSamples, bool shadows, const std::function<bool()>& abort, std::vector<double>& q,
  Report& report, std::string& error, State* kept)
{
  MPI_Comm comm = *vtkTranslucency::MPIHandle(vtkTranslucencyCommunicator::World());
  report = Report();
  State temporary;
  State::Impl& state = *(kept ? kept : &temporary)->In;
  state.SurfaceGathered = false;
  const vtkIdType numPoints = input ? input->GetNumberOfPoints() : 0;

  // The kept surface while every rank's piece and its refractive index are
  // the same (a relight); else gathered again.
  const vtkTranslucency::PieceIdentity identity = vtkTranslucency::PieceIdentity::Of(input);
  const bool same = vtkTranslucency::SameOnEveryRank(comm,
    state.Valid && state.Kernel.HasSurface() && identity == state.Identity &&
      numPoints == state.NumberOfPoints);
  try
  {
    if (!same)
    {
      state.Valid = false;
      GatherInto(comm, input, state);
      state.SurfaceGathered = true;
      state.Identity = identity;
      state.NumberOfPoints = numPoints;
      state.Valid = true;
      report.GatherMilliseconds = state.Gathered.GatherMilliseconds;
    }
    report.SurfaceTriangles = state.Gathered.SurfaceTriangles;
    report.SurfacePoints = state.Gathered.SurfacePoints;
    report.GatheredBytes = state.Gathered.GatheredBytes;

    // This rank's surface points: the kept terms of unchanged lights.
    const translucency::Timer timer;
    std::vector<double> values;
    int aborted = 0;
    std::string local;
    try
    {
      aborted = state.Kernel.Compute(lights, uniformIrradiance, uniformSamples, shadows, values,
                  abort)
        ? 0
        : 1;
    }
    catch (const translucency::Error& e)
    {
      local = e.what();
    }
    translucency::AgreeOnError(comm, local);
    MPI_Allreduce(MPI_IN_PLACE, &aborted, 1, MPI_INT, MPI_MAX, comm);
    if (aborted)
    {
      error.clear();
      return false;
    }
    q.assign(3 * static_cast<size_t>(numPoints), 0.0);
    for (vtkIdType i = 0; i < numPoints; ++i)
    {
      const int k = state.WantedIndex[static_cast<size_t>(i)];
      if (k < 0)
        continue;
      std::copy(values.begin() + 3 * static_cast<size_t>(k),
        values.begin() + 3 * static_cast<size_t>(k) + 3, q.begin() + 3 * i);
    }
    report.RayMilliseconds = timer.GetMilliseconds();
  }
  catch (const translucency::Error& e)
  {
    error = e.what(); // the same on every rank (AgreeOnError)
    if (!state.Valid)
      state.Kernel.Clear(); // a failed gather; a light's error keeps the surface
    return false;
  }
  return true;
}

bool vtkTranslucencyDistributedIrradiance::GatherSurface(
  vtkUnstructuredGrid* input, translucency::BoundarySurface& surface, std::string& error)
{
  MPI_Comm comm = *vtkTranslucency::MPIHandle(vtkTranslucencyCommunicator::World());
  std::string local;
  vtkTranslucency::PieceFaces faces;
  const bool eta = input && input->GetCellData()->GetArray(vtkTranslucency::RefractiveIndexName);
  try
  {
    vtkTranslucency::ExtractPieceFaces(input, faces, eta);
  }
  catch (const std::exception& e)
  {
    local = e.what();
  }
  std::vector<translucency::PointKey> keys;
  vtkTranslucency::MakePointKeys(comm, input, faces.Points, !local.empty(), keys);
  try
  {
    translucency::AgreeOnError(comm, local);
    std::vector<int> surfacePoint;
    std::vector<double> rotations;
    translucency::BoundarySurfaceReport report;
    translucency::GatherBoundarySurface(comm, faces.Points, keys, faces.Used,
      faces.Triangles, faces.TriangleEta, faces.TriangleTets, surface, surfacePoint, rotations,
      report);
  }
  catch (const translucency::Error& e)
  {
    error = e.what(); // the same on every rank (AgreeOnError)
    return false;
  }
  return true;
}

#else // no distributed path in this build

struct vtkTranslucencyDistributedIrradiance::State::Impl
{
};

vtkTranslucencyDistributedIrradiance::State::State()
  : In(new Impl)
{
}

vtkTranslucencyDistributedIrradiance::State::~State() = default;

int vtkTranslucencyDistributedIrradiance::State::GetNumberOfLightsComputed() const
{
  return 0;
}

bool vtkTranslucencyDistributedIrradiance::State::GetUniformComputed() const
{
  return false;
}

bool vtkTranslucencyDistributedIrradiance::State::GetSurfaceGathered() const
{
  return false;
}

void vtkTranslucencyDistributedIrradiance::State::Clear() {}

bool vtkTranslucencyDistributedIrradiance::Compute(vtkUnstructuredGrid*,
  const std::vector<translucency::LightSource>&, double, int, bool,
  const std::function<bool()>&, std::vector<double>&, Report&, std::string& error, State*)
{
  error = "this build has no distributed surface irradiance (hypre or VTK's ParallelMPI missing)";
  return false;
}

bool vtkTranslucencyDistributedIrradiance::GatherSurface(
  vtkUnstructuredGrid*, translucency::BoundarySurface&, std::string& error)
{
  error = "this build has no distributed boundary surface (hypre or VTK's ParallelMPI missing)";
  return false;
}

#endif
