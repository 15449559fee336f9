#include "DistributedSources.h"

#include "Error.h"
#include "Strings.h"
#include "Fresnel.h"
#include "TetLocator.h"
#include "TriangleGeometry.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace translucency
{

namespace
{

int RankOf(MPI_Comm comm)
{
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  return rank;
}

int SizeOf(MPI_Comm comm)
{
  int size = 1;
  MPI_Comm_size(comm, &size);
  return size;
}

bool IsPhysical(const DistributedPiece& piece, int f)
{
  return (*piece.Physical)[static_cast<std::size_t>(f)] != 0;
}

/// Half the mean edge of the physical boundary triangles of every rank
/// (SurfaceTolerance of the whole mesh).
double GlobalSurfaceTolerance(MPI_Comm comm, const DistributedPiece& piece)
{
  double local[2] = { 0.0, 0.0 }; // edge length sum, triangles
  if (piece.HasTets)
  {
    const std::vector<int>& triangles = piece.Mesh->GetBoundaryTriangles();
    for (int f = 0; f < piece.Mesh->GetNumberOfBoundaryTriangles(); ++f)
    {
      if (!IsPhysical(piece, f))
        continue;
      for (int e = 0; e < 3; ++e)
      {
        const double* a = piece.Mesh->GetPoint(triangles[3 * f + e]);
        const double* b = piece.Mesh->GetPoint(triangles[3 * f + (e + 1) % 3]);
        local[0] += std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
          (a[2] - b[2]) * (a[2] - b[2]));
      }
      local[1] += 1.0;
    }
  }
  double global[2] = { 0.0, 0.0 };
  MPI_Allreduce(local, global, 2, MPI_DOUBLE, MPI_SUM, comm);
  return global[1] > 0.0 ? 0.5 * global[0] / (3.0 * global[1]) : 0.0;
}

/// The closest point of the physical surface of every rank to x, known on
/// every rank; Triangle and Weights on the winning rank only (-1 elsewhere).
struct GlobalSurfacePoint
{
  double Distance = 0.0;
  int Rank = 0;
  int Triangle = -1; ///< local boundary triangle on Rank
  double Weights[3]{};
  std::array<double, 3> Position{};
  std::array<double, 3> Normal{};
  double Eta = 1.0; ///< of the tet under the point
  std::array<double, NumberOfChannels> MuA{}, MuS{};
};

GlobalSurfacePoint FindGlobalSurfacePoint(MPI_Comm comm, const DistributedPiece& piece, const double x[3])
{
  GlobalSurfacePoint best;
  struct
  {
    double Distance;
    int Rank;
  } local{ std::numeric_limits<double>::infinity(), RankOf(comm) }, global{};
  if (piece.HasTets)
  {
    // The closest of this piece's physical faces (faces between pieces are
    // not surface).
    const SurfacePoint nearest = ClosestBoundaryPoint(
      *piece.Mesh, x, [&piece](int f) { return IsPhysical(piece, f); });
    if (nearest.Triangle >= 0)
    {
      local.Distance = nearest.Distance;
      best.Triangle = nearest.Triangle;
      for (int i = 0; i < 3; ++i)
      {
        best.Weights[i] = nearest.Weights[i];
        best.Position[i] = nearest.Position[i];
      }
    }
  }
  MPI_Allreduce(&local, &global, 1, MPI_DOUBLE_INT, MPI_MINLOC, comm);
  if (std::isinf(global.Distance))
  {
    // No physical face on any rank (or every distance not a number).
    std::ostringstream out;
    out << "no surface point found near " << FormatPoint(x)
        << " (no rank has a boundary triangle at a finite distance)";
    throw Error(out.str());
  }
  best.Distance = global.Distance;
  best.Rank = global.Rank;
  // The winner sends the point, the face's outward normal and the material
  // of the tet under it.
  double buffer[7 + 2 * NumberOfChannels] = {};
  if (best.Rank == RankOf(comm))
  {
    const TetMesh& mesh = *piece.Mesh;
    const int* t = &mesh.GetBoundaryTriangles()[3 * static_cast<std::size_t>(best.Triangle)];
    const Eigen::Vector3d a = Eigen::Map<const Eigen::Vector3d>(mesh.GetPoint(t[0]));
    const Eigen::Vector3d n = (Eigen::Map<const Eigen::Vector3d>(mesh.GetPoint(t[1])) - a)
                                .cross(Eigen::Map<const Eigen::Vector3d>(mesh.GetPoint(t[2])) - a)
                                .normalized();
    const std::size_t tet =
      static_cast<std::size_t>(mesh.GetBoundaryTriangleTets()[static_cast<std::size_t>(best.Triangle)]);
    for (int i = 0; i < 3; ++i)
    {
      buffer[i] = best.Position[i];
      buffer[3 + i] = n[i];
    }
    buffer[6] = piece.Material->RefractiveIndex[tet];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      buffer[7 + c] = piece.Material->AbsorptionCoefficient[3 * tet + c];
      buffer[7 + NumberOfChannels + c] = piece.Material->ReducedScatteringCoefficient[3 * tet + c];
    }
  }
  else
  {
    best.Triangle = -1;
  }
  MPI_Bcast(buffer, 7 + 2 * NumberOfChannels, MPI_DOUBLE, best.Rank, comm);
  for (int i = 0; i < 3; ++i)
  {
    best.Position[i] = buffer[i];
    best.Normal[i] = buffer[3 + i];
  }
  best.Eta = buffer[6];
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    best.MuA[c] = buffer[7 + c];
    best.MuS[c] = buffer[7 + NumberOfChannels + c];
  }
  return best;
}

/// Adds the load of one point source to `load` on the lowest rank whose
/// owned tets contain it; the same error on every rank if none does.
class SourcePlacer
{
public:
  SourcePlacer(MPI_Comm comm, const DistributedPiece& piece)
    : Comm_(comm)
    , Piece_(piece)
  {
    if (piece.HasTets)
    {
      Locator_.Build(*piece.Mesh);
    }
  }

  void Place(const PointSource& source, const std::string& name, const std::string& what,
    std::vector<double>& load)
  {
    const int rank = RankOf(Comm_), size = SizeOf(Comm_);
    int tet = -1;
    double weights[4] = {};
    if (Piece_.HasTets)
    {
      tet = Locator_.Locate(source.Position.data());
      if (tet >= 0 && !Locator_.Barycentric(tet, source.Position.data(), weights))
      {
        tet = -1;
      }
    }
    const int mine = tet >= 0 ? rank : size;
    int winner = size;
    MPI_Allreduce(&mine, &winner, 1, MPI_INT, MPI_MIN, Comm_);
    if (winner == size)
    {
      // The message of the serial Sources::Place, with the whole mesh's
      // tet count and bounds.
      double bounds[6];
      const double* b = Locator_.GetBounds();
      for (int i = 0; i < 3; ++i)
      {
        bounds[i] = Piece_.HasTets ? b[i] : std::numeric_limits<double>::infinity();
        bounds[3 + i] = Piece_.HasTets ? -b[3 + i] : std::numeric_limits<double>::infinity();
      }
      double global[6];
      MPI_Allreduce(bounds, global, 6, MPI_DOUBLE, MPI_MIN, Comm_);
      long long tets = Piece_.HasTets ? Piece_.Mesh->GetNumberOfTets() : 0, allTets = 0;
      MPI_Allreduce(&tets, &allTets, 1, MPI_LONG_LONG, MPI_SUM, Comm_);
      std::ostringstream out;
      out << name << ": " << what << FormatPoint(source.Position.data())
          << " is outside the object (" << allTets << " tets, bounds x " << global[0] << ".."
          << -global[3] << ", y " << global[1] << ".." << -global[4] << ", z " << global[2]
          << ".." << -global[5] << " mm)";
      throw Error(out.str());
    }
    if (winner != rank)
    {
      return;
    }
    // As the serial PlaceAt: clamp the locator's slack, weights summing to 1.
    double sum = 0.0;
    for (double& w : weights)
    {
      w = std::max(w, 0.0);
      sum += w;
    }
    const int* v = Piece_.Mesh->GetTet(tet);
    for (int a = 0; a < 4; ++a)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        load[3 * static_cast<std::size_t>(v[a]) + c] += source.Power[c] * (weights[a] / sum);
      }
    }
  }

private:
  MPI_Comm Comm_;
  const DistributedPiece& Piece_;
  TetLocator Locator_;
};

} // namespace

std::vector<double> ComputeDistributedSourceLoad(
  MPI_Comm comm, const DistributedPiece& piece, const Sources& sources)
{
  std::vector<double> load(3 * static_cast<std::size_t>(piece.NumberOfPoints), 0.0);
  sources.Validate(); // the same lists on every rank: the same outcome
  if (sources.Empty())
  {
    return load;
  }
  SourcePlacer placer(comm, piece);
  const std::vector<PointSource>& points = sources.GetPointSources();
  for (std::size_t k = 0; k < points.size(); ++k)
  {
    placer.Place(points[k], NameOf(points[k].Label, "point source", k), "position ", load);
  }
  const std::vector<PencilBeam>& pencils = sources.GetPencilBeams();
  const double tolerance = pencils.empty() ? 0.0 : GlobalSurfaceTolerance(comm, piece);
  for (std::size_t k = 0; k < pencils.size(); ++k)
  {
    const PencilBeam& beam = pencils[k];
    const std::string name = NameOf(beam.Label, "pencil beam", k);
    // The entry (as LocatePencilEntry, on the physical surface of every
    // rank); its checks, optics and equivalent sources are the serial ones.
    const GlobalSurfacePoint global = FindGlobalSurfacePoint(comm, piece, beam.Position.data());
    SurfacePoint surface;
    surface.Position = global.Position;
    surface.Normal = global.Normal;
    surface.Distance = global.Distance;
    const PencilEntry entry = EnterPencilBeam(beam, name, surface, tolerance, global.Eta);
    for (const EquivalentSource& equivalent :
      PencilEquivalentSources(beam, name, entry, global.MuA.data(), global.MuS.data()))
    {
      placer.Place(equivalent.Source, name, DescribeEquivalentSource(equivalent), load);
    }
  }
  return load;
}

std::vector<DetectorReading> ReadDistributedDetectors(MPI_Comm comm, const DistributedPiece& piece,
  const std::vector<Detector>& detectors, const std::vector<double>& fluence,
  const std::vector<double>* irradiance, Fresnel::BoundaryRule rule)
{
  std::vector<DetectorReading> readings;
  if (detectors.empty())
  {
    return readings;
  }
  const double tolerance = GlobalSurfaceTolerance(comm, piece);
  const int rank = RankOf(comm);
  for (std::size_t k = 0; k < detectors.size(); ++k)
  {
    const Detector& detector = detectors[k];
    const std::string name = NameOf(detector.Label, "detector", k);
    CheckDetector(detector, name); // the serial checks (Detectors.h)
    const GlobalSurfacePoint surface =
      FindGlobalSurfacePoint(comm, piece, detector.Position.data());
    CheckDetector(detector, name, &surface.Position, surface.Distance, tolerance);
    DetectorReading reading;
    reading.SurfacePosition = surface.Position;
    // [area, fluence R G B, exitance R G B] summed over the ranks.
    double local[1 + 2 * NumberOfChannels] = {}, global[1 + 2 * NumberOfChannels] = {};
    if (detector.Radius > 0.0 && piece.HasTets)
    {
      const TetMesh& mesh = *piece.Mesh;
      const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
      const std::vector<double>& areas = mesh.GetBoundaryTriangleAreas();
      std::vector<DetectorFootprint::Sample> samples;
      double area = 0.0;
      for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
      {
        if (!IsPhysical(piece, f))
          continue;
        AppendFibreSamples(mesh.GetPoint(triangles[3 * f]), mesh.GetPoint(triangles[3 * f + 1]),
          mesh.GetPoint(triangles[3 * f + 2]), areas[static_cast<std::size_t>(f)], f,
          surface.Position, surface.Normal, detector.Radius, samples, area);
      }
      DetectorReading partial;
      for (const DetectorFootprint::Sample& sample : samples)
      {
        AccumulateDetectorSample(mesh, *piece.Material, sample.Triangle, sample.Weights,
          sample.Weight, fluence, irradiance, rule, partial);
      }
      local[0] = area;
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        local[1 + c] = partial.Fluence[c];
        local[1 + NumberOfChannels + c] = partial.Exitance[c];
      }
    }
    if (detector.Radius > 0.0)
    {
      MPI_Allreduce(local, global, 1 + 2 * NumberOfChannels, MPI_DOUBLE, MPI_SUM, comm);
    }
    if (global[0] > 0.0)
    {
      reading.Area = global[0];
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        reading.Fluence[c] = global[1 + c] / global[0];
        reading.Exitance[c] = global[1 + NumberOfChannels + c] / global[0];
      }
    }
    else
    {
      // A point detector (or a disc that caught no sub-triangle): the P1
      // value at the surface point, read by the rank that has it.
      double value[2 * NumberOfChannels] = {};
      if (surface.Rank == rank)
      {
        DetectorReading point;
        AccumulateDetectorSample(*piece.Mesh, *piece.Material, surface.Triangle, surface.Weights,
          1.0, fluence, irradiance, rule, point);
        for (int c = 0; c < NumberOfChannels; ++c)
        {
          value[c] = point.Fluence[c];
          value[NumberOfChannels + c] = point.Exitance[c];
        }
      }
      MPI_Bcast(value, 2 * NumberOfChannels, MPI_DOUBLE, surface.Rank, comm);
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        reading.Fluence[c] = value[c];
        reading.Exitance[c] = value[NumberOfChannels + c];
      }
    }
    readings.push_back(reading);
  }
  return readings;
}

} // namespace translucency
