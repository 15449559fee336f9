#include "vtkTranslucencyDistributedRadiance.h"

#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
#include "DistributedBoundarySurface.h"
#include "Error.h"
#include "vtkTranslucencyMPI.h"
#include "vtkTranslucencyPieceFaces.h"

#include <vtkUnstructuredGrid.h>

namespace
{
MPI_Comm* GlobalCommunicator()
{
  return vtkTranslucency::MPIHandle(vtkTranslucencyCommunicator::World());
}
}

bool vtkTranslucencyDistributedRadiance::FindSurface(
  vtkUnstructuredGrid* input, Surface& surface, std::string& error)
{
  MPI_Comm comm = *GlobalCommunicator();
  surface = Surface();
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
  std::vector<translucency::PointKey> keys;
  vtkTranslucency::MakePointKeys(comm, input, faces.Points, !local.empty(), keys);
  MPI_Allreduce(&faces.OwnedTets, &surface.TotalTets, 1, MPI_LONG_LONG, MPI_SUM, comm);
  try
  {
    translucency::AgreeOnError(comm, local);
    if (surface.TotalTets == 0)
    {
      throw translucency::Error("the input mesh is empty (no points or no cells)");
    }
    translucency::PieceBoundary boundary;
    translucency::FindPieceBoundary(comm, faces.Points, keys, faces.Used, faces.Triangles,
      faces.TriangleEta, faces.TriangleTets, "TRANSLUCENCY_GATHERED_RADIANCE=1", boundary);
    for (size_t f = 0; f < boundary.Physical.size(); ++f)
    {
      if (boundary.Physical[f])
      {
        for (int m = 0; m < 3; ++m)
          surface.Triangles.push_back(faces.Triangles[3 * f + m]);
      }
    }
    surface.OnBoundary.resize(boundary.PointArea.size());
    for (size_t i = 0; i < boundary.PointArea.size(); ++i)
      surface.OnBoundary[i] = boundary.PointArea[i] > 0.0 ? 1 : 0;
    surface.Owned = std::move(boundary.Owned);
    surface.Normals = std::move(boundary.PointNormal);
    surface.Eta = std::move(boundary.PointEta);
    surface.TotalTriangles = boundary.Triangles;
  }
  catch (const translucency::Error& e)
  {
    error = e.what(); // the same on every rank (AgreeOnError)
    return false;
  }
  return true;
}

struct vtkTranslucencyDistributedRadiance::SurfaceCache::Impl
{
  bool Valid = false;
  vtkTranslucency::PieceIdentity Identity;
  Surface Kept;
};

vtkTranslucencyDistributedRadiance::SurfaceCache::SurfaceCache()
  : In(new Impl)
{
}

vtkTranslucencyDistributedRadiance::SurfaceCache::~SurfaceCache() = default;

void vtkTranslucencyDistributedRadiance::SurfaceCache::Clear()
{
  this->In.reset(new Impl);
}

bool vtkTranslucencyDistributedRadiance::SurfaceCache::Find(
  vtkUnstructuredGrid* input, const Surface*& surface, std::string& error)
{
  Impl& in = *this->In;
  vtkTranslucency::PieceIdentity identity = vtkTranslucency::PieceIdentity::Of(input);
  this->Searched = !vtkTranslucency::SameOnEveryRank(
    *GlobalCommunicator(), in.Valid && identity == in.Identity);
  surface = &in.Kept;
  if (!this->Searched)
  {
    return true;
  }
  in.Valid = false;
  if (!FindSurface(input, in.Kept, error))
  {
    in.Kept = Surface();
    return false;
  }
  in.Identity = std::move(identity);
  in.Valid = true;
  return true;
}

std::vector<double> vtkTranslucencyDistributedRadiance::AllGather(const std::vector<double>& local)
{
  MPI_Comm comm = *GlobalCommunicator();
  int size = 1;
  MPI_Comm_size(comm, &size);
  int mine = static_cast<int>(local.size());
  std::vector<int> counts(static_cast<size_t>(size)), displs(static_cast<size_t>(size), 0);
  MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  for (int r = 1; r < size; ++r)
    displs[r] = displs[r - 1] + counts[r - 1];
  std::vector<double> all(static_cast<size_t>(displs[size - 1] + counts[size - 1]));
  MPI_Allgatherv(local.data(), mine, MPI_DOUBLE, all.data(), counts.data(), displs.data(),
    MPI_DOUBLE, comm);
  return all;
}

void vtkTranslucencyDistributedRadiance::AllMax(std::vector<double>& values)
{
  MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_MAX,
    *GlobalCommunicator());
}

#else // no per-piece path in this build

struct vtkTranslucencyDistributedRadiance::SurfaceCache::Impl
{
};

vtkTranslucencyDistributedRadiance::SurfaceCache::SurfaceCache()
  : In(new Impl)
{
}

vtkTranslucencyDistributedRadiance::SurfaceCache::~SurfaceCache() = default;

void vtkTranslucencyDistributedRadiance::SurfaceCache::Clear() {}

bool vtkTranslucencyDistributedRadiance::SurfaceCache::Find(
  vtkUnstructuredGrid*, const Surface*& surface, std::string& error)
{
  surface = nullptr;
  error = "this build has no distributed outgoing radiance (hypre or VTK's ParallelMPI missing)";
  return false;
}

bool vtkTranslucencyDistributedRadiance::FindSurface(vtkUnstructuredGrid*, Surface&, std::string& error)
{
  error = "this build has no distributed outgoing radiance (hypre or VTK's ParallelMPI missing)";
  return false;
}

std::vector<double> vtkTranslucencyDistributedRadiance::AllGather(const std::vector<double>& local)
{
  return local;
}

void vtkTranslucencyDistributedRadiance::AllMax(std::vector<double>&) {}

#endif
