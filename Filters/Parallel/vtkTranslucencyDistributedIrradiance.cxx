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

bool vtkTranslucencyDistributedIrradiance::Compute(vtkUnstructuredGrid* input,
  const std::vector<translucency::LightSource>& lights, double uniformIrradiance,
  int uniformSamples, bool shadows, const std::function<bool()>& abort, std::vector<double>& q,
  Report& report, std::string& error)
{
  MPI_Comm comm = *vtkTranslucency::MPIHandle(vtkTranslucencyCommunicator::World());
  report = Report();
  std::string local;
  const vtkIdType numPoints = input ? input->GetNumberOfPoints() : 0;
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
  try
  {
    translucency::AgreeOnError(comm, local);
    if (totalTets == 0)
    {
      throw translucency::Error("the input mesh is empty (no points or no cells)");
    }
    translucency::BoundarySurface surface;
    std::vector<int> surfacePoint;
    std::vector<double> rotations;
    translucency::BoundarySurfaceReport gathered;
    translucency::GatherBoundarySurface(comm, points, keys, faces.Used,
      faces.Triangles, faces.TriangleEta, faces.TriangleTets, surface, surfacePoint, rotations,
      gathered);
    report.SurfaceTriangles = gathered.Triangles;
    report.SurfacePoints = gathered.Points;
    report.GatheredBytes = gathered.GatheredBytes;
    report.GatherMilliseconds = gathered.Milliseconds;

    // This rank's distinct surface points, computed once each.
    const translucency::Timer timer;
    std::vector<int> wanted;
    for (int s : surfacePoint)
    {
      if (s >= 0)
        wanted.push_back(s);
    }
    std::sort(wanted.begin(), wanted.end());
    wanted.erase(std::unique(wanted.begin(), wanted.end()), wanted.end());
    std::vector<double> wantedRotations(wanted.size());
    for (size_t k = 0; k < wanted.size(); ++k)
      wantedRotations[k] = rotations[static_cast<size_t>(wanted[k])];
    std::vector<double> values;
    int aborted = 0;
    local.clear();
    try
    {
      aborted = translucency::ComputeSurfacePointIrradiance(surface, wanted, wantedRotations,
                  lights, uniformIrradiance, uniformSamples, shadows, values, abort)
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
      const int s = surfacePoint[static_cast<size_t>(i)];
      if (s < 0)
        continue;
      const size_t k = static_cast<size_t>(
        std::lower_bound(wanted.begin(), wanted.end(), s) - wanted.begin());
      std::copy(values.begin() + 3 * k, values.begin() + 3 * k + 3, q.begin() + 3 * i);
    }
    report.RayMilliseconds = timer.GetMilliseconds();
  }
  catch (const translucency::Error& e)
  {
    error = e.what(); // the same on every rank (AgreeOnError)
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

bool vtkTranslucencyDistributedIrradiance::Compute(vtkUnstructuredGrid*,
  const std::vector<translucency::LightSource>&, double, int, bool,
  const std::function<bool()>&, std::vector<double>&, Report&, std::string& error)
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
