#include "DistributedCollimatedSource.h"

#include "DistributedBoundarySurface.h"
#include "Error.h"
#include "TetMesh.h"

#include <cmath>
#include <sstream>
#include <string>

namespace translucency
{

namespace
{

/// Doubles per packed light: type, direction, position, power, cutoff, exponent.
constexpr int LightDoubles = 12;

double Seconds()
{
  return MPI_Wtime();
}

double MillisecondsSince(double start)
{
  return 1000.0 * (MPI_Wtime() - start);
}

} // namespace

void AgreeOnLights(MPI_Comm comm, bool have, std::vector<LightSource>& lights,
  double& uniformIrradiance, bool& shadows, CollimatedModel& model, int& flag)
{
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  int mine = have ? rank : size, root = size;
  MPI_Allreduce(&mine, &root, 1, MPI_INT, MPI_MIN, comm);
  if (root == size)
    root = 0;
  std::vector<double> packed;
  if (rank == root)
  {
    packed = { static_cast<double>(lights.size()), uniformIrradiance, shadows ? 1.0 : 0.0,
      static_cast<double>(static_cast<int>(model)), static_cast<double>(flag) };
    for (const LightSource& light : lights)
    {
      packed.push_back(static_cast<double>(static_cast<int>(light.Type)));
      packed.insert(packed.end(), light.Direction.begin(), light.Direction.end());
      packed.insert(packed.end(), light.Position.begin(), light.Position.end());
      packed.insert(packed.end(), light.Power.begin(), light.Power.end());
      packed.push_back(light.SpotCutoff);
      packed.push_back(light.SpotExponent);
    }
  }
  int count = static_cast<int>(packed.size());
  MPI_Bcast(&count, 1, MPI_INT, root, comm);
  packed.resize(static_cast<std::size_t>(count));
  MPI_Bcast(packed.data(), count, MPI_DOUBLE, root, comm);
  if (rank == root)
    return;
  const std::size_t n = static_cast<std::size_t>(packed[0]);
  uniformIrradiance = packed[1];
  shadows = packed[2] != 0.0;
  model = static_cast<CollimatedModel>(static_cast<int>(packed[3]));
  flag = static_cast<int>(packed[4]);
  lights.assign(n, LightSource());
  for (std::size_t l = 0; l < n; ++l)
  {
    const double* p = &packed[5 + LightDoubles * l];
    LightSource& light = lights[l];
    light.Type = static_cast<LightSource::Kind>(static_cast<int>(p[0]));
    for (int k = 0; k < 3; ++k)
    {
      light.Direction[k] = p[1 + k];
      light.Position[k] = p[4 + k];
      light.Power[k] = p[7 + k];
    }
    light.SpotCutoff = p[10];
    light.SpotExponent = p[11];
  }
}

void DistributedCollimatedSource::Clear()
{
  Valid_ = false;
  Keys_.clear();
  Surface_ = BoundarySurface();
  Extinction_.clear();
  PointArea_.clear();
  PointNormal_.clear();
  SurfacePoint_.clear();
  Rotations_.clear();
  MyTriangles_.clear();
  MyValues_.clear();
  RaysValid_ = false;
  RayBeams_.clear();
  Entries_.clear();
  Fluence_.clear();
  Entering_ = {};
  Loads_.Clear();
}

std::size_t DistributedCollimatedSource::GetMemoryBytes() const
{
  std::size_t bytes = Surface_.Points.size() * sizeof(double) +
    Surface_.Triangles.size() * sizeof(int) + Surface_.TriangleEta.size() * sizeof(double) +
    sizeof(double) *
      (Extinction_.size() + PointArea_.size() + PointNormal_.size() + Rotations_.size() +
        MyValues_.size() + Fluence_.size()) +
    sizeof(int) * (SurfacePoint_.size() + MyTriangles_.size()) + sizeof(PointKey) * Keys_.size() +
    Loads_.GetMemoryBytes();
  for (const std::vector<int>& entries : Entries_)
    bytes += sizeof(int) * entries.size();
  return bytes;
}

bool DistributedCollimatedSource::GeometryKept(
  MPI_Comm comm, const TetMesh* mesh, const std::vector<PointKey>& keys) const
{
  const std::uint64_t revision = mesh ? mesh->GetGeometryRevision() : 0;
  int mine = Valid_ && revision == Revision_ && keys == Keys_ ? 1 : 0;
  int all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, comm);
  return all != 0;
}

std::vector<double> DistributedCollimatedSource::TriangleValues(
  const TetMesh* mesh, const OpticalProperties& material) const
{
  std::vector<double> values;
  if (!mesh || mesh->GetNumberOfTets() == 0)
    return values;
  const std::vector<int>& triangleTets = mesh->GetBoundaryTriangleTets();
  values.reserve(4 * MyTriangles_.size());
  for (const int f : MyTriangles_)
  {
    const std::size_t t = static_cast<std::size_t>(triangleTets[static_cast<std::size_t>(f)]);
    values.push_back(material.RefractiveIndex[t]);
    for (int c = 0; c < NumberOfChannels; ++c)
      values.push_back(
        material.AbsorptionCoefficient[3 * t + c] + material.ReducedScatteringCoefficient[3 * t + c]);
  }
  return values;
}

bool DistributedCollimatedSource::RefreshValues(
  MPI_Comm comm, const TetMesh* mesh, const OpticalProperties& material)
{
  // The surface's geometry is kept; its triangles' eta and mu_t' are this
  // call's material (a paint under the surface changes them). Each rank
  // sends its own physical triangles' values in the order of the gather, so
  // the concatenation in rank order is surface.Triangles' order.
  std::vector<double> mine = TriangleValues(mesh, material);
  int changed = mine != MyValues_ ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &changed, 1, MPI_INT, MPI_MAX, comm);
  if (!changed)
    return false;
  std::string error;
  for (std::size_t k = 0; k < MyTriangles_.size() && error.empty(); ++k)
  {
    const double eta = mine[4 * k];
    if (!(eta > 0.0) || !std::isfinite(eta))
    {
      std::ostringstream msg;
      msg << "RefractiveIndex of tet "
          << mesh->GetBoundaryTriangleTets()[static_cast<std::size_t>(MyTriangles_[k])]
          << " (under a boundary face) is " << eta << ": must be finite and > 0";
      error = msg.str();
    }
  }
  AgreeOnError(comm, error);
  int size = 1;
  MPI_Comm_size(comm, &size);
  const int count = static_cast<int>(mine.size());
  std::vector<int> counts(static_cast<std::size_t>(size)), displs(static_cast<std::size_t>(size), 0);
  MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  for (int r = 1; r < size; ++r)
    displs[r] = displs[r - 1] + counts[r - 1];
  std::vector<double> all(static_cast<std::size_t>(displs[size - 1] + counts[size - 1]));
  MPI_Allgatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), displs.data(),
    MPI_DOUBLE, comm);
  if (all.size() != 4 * Surface_.GetNumberOfTriangles())
    throw Error("distributed collimated source: the surface's values do not match its triangles");
  for (std::size_t f = 0; f < Surface_.GetNumberOfTriangles(); ++f)
  {
    Surface_.TriangleEta[f] = all[4 * f];
    for (int c = 0; c < NumberOfChannels; ++c)
      Extinction_[3 * f + c] = all[4 * f + 1 + c];
  }
  MyValues_ = std::move(mine);
  return true;
}

void DistributedCollimatedSource::Gather(MPI_Comm comm, const TetMesh* mesh,
  const std::vector<PointKey>& keys, const std::vector<char>& used,
  const OpticalProperties& material)
{
  Clear();
  // This rank's boundary triangles (of its own tets: partition faces
  // included, the count over the ranks sorts them out) with eta and
  // mu_t' = mu_a + mu_s' of their tets.
  static const std::vector<double> noPoints;
  static const std::vector<int> noTriangles;
  static const std::vector<PointKey> noKeys;
  static const std::vector<char> noUsed;
  const bool hasTets = mesh && mesh->GetNumberOfTets() > 0;
  const std::vector<int>& triangles = hasTets ? mesh->GetBoundaryTriangles() : noTriangles;
  const std::vector<int>& triangleTets = hasTets ? mesh->GetBoundaryTriangleTets() : noTriangles;
  std::vector<double> eta(triangleTets.size()), extinction(3 * triangleTets.size());
  for (std::size_t f = 0; f < triangleTets.size(); ++f)
  {
    const std::size_t t = static_cast<std::size_t>(triangleTets[f]);
    eta[f] = material.RefractiveIndex[t];
    for (int c = 0; c < NumberOfChannels; ++c)
      extinction[3 * f + c] =
        material.AbsorptionCoefficient[3 * t + c] + material.ReducedScatteringCoefficient[3 * t + c];
  }
  BoundarySurfaceReport report;
  std::vector<int> surfacePoint;
  GatherBoundarySurface(comm, hasTets ? mesh->GetPoints() : noPoints, hasTets ? keys : noKeys,
    hasTets ? used : noUsed, triangles, eta, triangleTets, Surface_, surfacePoint, Rotations_,
    report, &extinction, 3, &Extinction_, &MyTriangles_);
  MyValues_ = TriangleValues(hasTets ? mesh : nullptr, material);
  SurfacePoint_.assign(keys.size(), -1);
  for (std::size_t i = 0; i < surfacePoint.size() && i < keys.size(); ++i)
    SurfacePoint_[i] = surfacePoint[i];

  // Per surface point: S_p and the outward unit normal, the normalised sum
  // of the area vectors of the triangles around it (TetMesh::ComputeMeasures).
  const std::size_t numSurfacePoints = Surface_.GetNumberOfPoints();
  PointArea_.assign(numSurfacePoints, 0.0);
  PointNormal_.assign(3 * numSurfacePoints, 0.0);
  const std::vector<double>& x = Surface_.Points;
  for (std::size_t f = 0; f < Surface_.GetNumberOfTriangles(); ++f)
  {
    const int* tri = &Surface_.Triangles[3 * f];
    double n[3];
    const double area = TriangleHalfNormal(&x[3 * static_cast<std::size_t>(tri[0])],
      &x[3 * static_cast<std::size_t>(tri[1])], &x[3 * static_cast<std::size_t>(tri[2])], n);
    for (int m = 0; m < 3; ++m)
    {
      const std::size_t p = static_cast<std::size_t>(tri[m]);
      PointArea_[p] += area;
      for (int k = 0; k < 3; ++k)
        PointNormal_[3 * p + k] += n[k];
    }
  }
  for (std::size_t p = 0; p < numSurfacePoints; ++p)
  {
    double* n = &PointNormal_[3 * p];
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; length > 0.0 && k < 3; ++k)
      n[k] /= length;
  }
  Revision_ = hasTets ? mesh->GetGeometryRevision() : 0;
  Keys_ = keys;
  Valid_ = true;
}

std::array<double, NumberOfChannels> DistributedCollimatedSource::Entering(
  MPI_Comm comm, const std::vector<LightSource>& beams, bool shadows) const
{
  // The serial entering power is sum_f S_f (q_f0 + q_f1 + q_f2) / 3 over the
  // boundary triangles, which is sum_p S_p q_p / 3 over the surface points
  // with the projected irradiance q_p = sum_f S_f q_f(p) / S_p of the beams
  // (ProjectCornerIrradiance): the surface's points are split over the ranks
  // (point p on rank p mod size) and each rank lights its share.
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  std::vector<int> mine;
  std::vector<double> rotations;
  for (std::size_t p = static_cast<std::size_t>(rank); p < Surface_.GetNumberOfPoints();
       p += static_cast<std::size_t>(size))
  {
    mine.push_back(static_cast<int>(p));
    rotations.push_back(Rotations_[p]);
  }
  std::array<double, NumberOfChannels> entering{};
  std::string error;
  try
  {
    std::vector<double> q;
    if (!mine.empty())
      ComputeSurfacePointIrradiance(Surface_, mine, rotations, beams, 0.0, 0, shadows, q);
    for (std::size_t k = 0; k < mine.size(); ++k)
    {
      const double s = PointArea_[static_cast<std::size_t>(mine[k])];
      for (int c = 0; c < NumberOfChannels; ++c)
        entering[c] += s * q[3 * k + c] / 3.0;
    }
  }
  catch (const Error& e)
  {
    error = e.what();
  }
  AgreeOnError(comm, error);
  MPI_Allreduce(MPI_IN_PLACE, entering.data(), NumberOfChannels, MPI_DOUBLE, MPI_SUM, comm);
  return entering;
}

void DistributedCollimatedSource::SumOverRanks(MPI_Comm comm, bool raysCast, CollimatedSource& out)
{
  std::array<double, 2 * NumberOfChannels> sums{};
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    sums[c] = out.Scattered[c];
    sums[NumberOfChannels + c] = out.Absorbed[c];
  }
  MPI_Allreduce(MPI_IN_PLACE, sums.data(), 2 * NumberOfChannels, MPI_DOUBLE, MPI_SUM, comm);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    out.Scattered[c] = sums[c];
    out.Absorbed[c] = sums[NumberOfChannels + c];
  }
  // What the loads did: the most any rank did (kept < loads < full).
  const bool loaded = !out.Load.empty() && Loads_.GetBeams().size() == out.Beams.size();
  const std::string update = loaded ? Loads_.GetLastUpdate() : "kept";
  int code = raysCast || update == "full" ? 2 : update == "loads" ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &code, 1, MPI_INT, MPI_MAX, comm);
  long long tets = loaded ? Loads_.GetTetsIntegrated() : 0;
  MPI_Allreduce(MPI_IN_PLACE, &tets, 1, MPI_LONG_LONG, MPI_SUM, comm);
  LastUpdate_ = code == 2 ? "full" : code == 1 ? "loads" : "kept";
  TetsIntegrated_ = tets;
}

void DistributedCollimatedSource::Compute(MPI_Comm comm, const TetMesh* mesh,
  const std::vector<PointKey>& keys, const std::vector<char>& used,
  const OpticalProperties& material, const std::vector<LightSource>& lights, bool shadows,
  CollimatedSource& out)
{
  GatherMs_ = RayMs_ = LoadMs_ = EnteringMs_ = 0.0;
  Gathered_ = ValuesGathered_ = false;
  LastUpdate_ = "full";
  TetsIntegrated_ = 0;
  const std::size_t numPoints = keys.size();
  const bool hasTets = mesh && mesh->GetNumberOfTets() > 0;
  out = CollimatedSource();
  out.Fluence.assign(3 * numPoints, 0.0);
  out.Load.assign(3 * numPoints, 0.0);
  // The beams (the lights are the same on every rank: so is this choice).
  std::vector<LightSource> beams;
  for (std::size_t l = 0; l < lights.size(); ++l)
  {
    ValidateLight(lights[l], l);
    if (lights[l].Type == LightSource::Kind::Directional)
      beams.push_back(lights[l]);
  }
  out.Beams.resize(beams.size());
  for (CollimatedSource::Beam& beam : out.Beams)
  {
    beam.Fluence.assign(3 * numPoints, 0.0);
    beam.OpticalPath.assign(numPoints, 0.0);
  }
  // What is kept is of the last complete call only.
  const bool raysValid = RaysValid_;
  RaysValid_ = false;
  if (beams.empty())
    return;

  // 1. The physical boundary with each triangle's eta and mu_t', on every
  // rank: its geometry kept while every rank's piece is the same, its
  // values gathered again when they changed (a paint under the surface).
  double start = Seconds();
  const bool geometryKept = GeometryKept(comm, mesh, keys);
  bool valuesChanged = false, etaChanged = false;
  if (!geometryKept)
  {
    Gather(comm, mesh, keys, used, material);
    Gathered_ = true;
  }
  else
  {
    const std::vector<double> eta = Surface_.TriangleEta;
    valuesChanged = RefreshValues(comm, mesh, material);
    ValuesGathered_ = valuesChanged;
    etaChanged = valuesChanged && Surface_.TriangleEta != eta;
  }
  GatherMs_ = MillisecondsSince(start);
  if (Surface_.GetNumberOfTriangles() == 0)
    return; // no surface on any rank: no beam enters (as serial)

  // 2. E_c at this rank's points: the rays cast against the whole surface
  // (kept while the surface, the directions and the shadow flag are), E_c
  // from their entry triangles (kept while the values under the surface
  // and the powers are). The same choice on every rank (agreed inputs).
  start = Seconds();
  bool sameDirections = raysValid && geometryKept && RayShadows_ == shadows &&
    RayBeams_.size() == beams.size();
  bool samePowers = sameDirections;
  for (std::size_t b = 0; sameDirections && b < beams.size(); ++b)
  {
    sameDirections = beams[b].Direction == RayBeams_[b].Direction;
    samePowers = samePowers && beams[b].Power == RayBeams_[b].Power;
  }
  const bool raysKept = sameDirections;
  samePowers = samePowers && raysKept;
  if (hasTets)
  {
    CollimatedEntrySurface entry;
    entry.Points = &Surface_.Points;
    entry.Triangles = &Surface_.Triangles;
    entry.Eta = Surface_.TriangleEta;
    entry.Extinction = Extinction_;
    entry.Diagonal = Surface_.Diagonal;
    if (!raysKept)
    {
      std::vector<char> onBoundary(numPoints, 0);
      std::vector<double> normals(3 * numPoints, 0.0);
      for (std::size_t i = 0; i < numPoints; ++i)
      {
        const int p = SurfacePoint_[i];
        if (p < 0)
          continue;
        onBoundary[i] = 1;
        for (int k = 0; k < 3; ++k)
          normals[3 * i + k] = PointNormal_[3 * static_cast<std::size_t>(p) + k];
      }
      Entries_ = CastCollimatedBeamEntries(
        entry, beams, shadows, mesh->GetPoints(), onBoundary, normals);
    }
    if (samePowers && !valuesChanged && Fluence_.size() == out.Fluence.size() &&
      Loads_.GetBeams().size() == beams.size())
    {
      out.Fluence = Fluence_;
      out.Beams = Loads_.GetBeams();
    }
    else
    {
      EvaluateCollimatedBeamField(entry, beams, mesh->GetPoints(), Entries_, out);
    }
  }
  RayMs_ = MillisecondsSince(start);

  // 3. The load of this rank's tets (summed at the owners by the caller):
  // the tets whose material or vertex E_c changed and their ring; the
  // beam's scattered and absorbed power, summed over the ranks.
  start = Seconds();
  if (hasTets)
    Loads_.Update(*mesh, material, raysKept, out);
  else
    Loads_.Clear();
  SumOverRanks(comm, !raysKept, out);
  LoadMs_ = MillisecondsSince(start);

  // 4. The power entering through the whole surface (kept while the
  // surface's geometry and eta, the beams and the shadow flag are).
  start = Seconds();
  out.Entering = samePowers && !etaChanged ? Entering_ : Entering(comm, beams, shadows);
  EnteringMs_ = MillisecondsSince(start);

  Fluence_ = out.Fluence;
  Entering_ = out.Entering;
  RayBeams_ = beams;
  RayShadows_ = shadows;
  RaysValid_ = true;
}

} // namespace translucency
