#include "InteriorSources.h"

#include "Error.h"
#include "Strings.h"
#include "Fresnel.h"
#include "TetLocator.h"
#include "TetMesh.h"
#include "TriangleGeometry.h"

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <sstream>

namespace translucency
{

namespace
{

bool AllFinite(const double* x, int n)
{
  for (int i = 0; i < n; ++i)
  {
    if (!std::isfinite(x[i]))
    {
      return false;
    }
  }
  return true;
}

void CheckPower(const std::array<double, NumberOfChannels>& power, const std::string& name)
{
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    if (!std::isfinite(power[c]) || power[c] < 0.0)
    {
      std::ostringstream out;
      out << name << ": power " << power[c] << " W in channel " << c
          << " (expected a finite value >= 0)";
      throw Error(out.str());
    }
  }
}

/// Place x in the mesh or throw naming the source.
PlacedSource PlaceAt(const TetLocator& locator, const TetMesh& mesh, const PointSource& source,
  const std::string& name, const std::string& what)
{
  PlacedSource placed;
  placed.Source = source;
  placed.Tet = locator.Locate(source.Position.data());
  if (placed.Tet < 0 || !locator.Barycentric(placed.Tet, source.Position.data(), placed.Weights))
  {
    const double* b = locator.GetBounds();
    std::ostringstream out;
    out << name << ": " << what << FormatPoint(source.Position.data())
        << " is outside the object (" << mesh.GetNumberOfTets() << " tets, bounds x "
        << b[0] << ".." << b[3] << ", y " << b[1] << ".." << b[4] << ", z " << b[2] << ".."
        << b[5] << " mm)";
    throw Error(out.str());
  }
  // Clamp the slack of the locator's tolerance so the weights sum to 1 and
  // none is negative (the load then sums to P exactly).
  double sum = 0.0;
  for (double& w : placed.Weights)
  {
    w = std::max(w, 0.0);
    sum += w;
  }
  for (double& w : placed.Weights)
  {
    w /= sum;
  }
  return placed;
}

} // namespace

void Sources::Validate() const
{
  for (std::size_t k = 0; k < Points_.size(); ++k)
  {
    const std::string name = NameOf(Points_[k].Label, "point source", k);
    if (!AllFinite(Points_[k].Position.data(), 3))
    {
      throw Error(name + ": position " + FormatPoint(Points_[k].Position.data()) +
        " is not finite");
    }
    CheckPower(Points_[k].Power, name);
  }
  for (std::size_t k = 0; k < Pencils_.size(); ++k)
  {
    const PencilBeam& beam = Pencils_[k];
    const std::string name = NameOf(beam.Label, "pencil beam", k);
    if (!AllFinite(beam.Position.data(), 3))
    {
      throw Error(name + ": entry point " + FormatPoint(beam.Position.data()) +
        " is not finite");
    }
    const double* d = beam.Direction.data();
    const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!std::isfinite(length) || !(length > 0.0))
    {
      throw Error(name + ": direction " + FormatPoint(d) +
        " is not a finite non-zero vector");
    }
    CheckPower(beam.Power, name);
  }
}

SurfacePoint ClosestBoundaryPoint(
  const TetMesh& mesh, const double x[3], const std::function<bool(int)>& include)
{
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const Eigen::Vector3d p(x[0], x[1], x[2]);
  SurfacePoint best;
  best.Distance = std::numeric_limits<double>::infinity();
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    if (include && !include(f))
    {
      continue;
    }
    const double* a = mesh.GetPoint(triangles[3 * f]);
    const double* b = mesh.GetPoint(triangles[3 * f + 1]);
    const double* c = mesh.GetPoint(triangles[3 * f + 2]);
    double w[3];
    const Eigen::Vector3d q = ClosestPointOnTriangle(p, Eigen::Vector3d(a[0], a[1], a[2]),
      Eigen::Vector3d(b[0], b[1], b[2]), Eigen::Vector3d(c[0], c[1], c[2]), w);
    // stableNorm: a point 1e300 mm away must not overflow to inf (with every
    // distance inf no triangle would be chosen).
    const double distance = (q - p).stableNorm();
    if (distance < best.Distance)
    {
      best.Distance = distance;
      best.Triangle = f;
      for (int i = 0; i < 3; ++i)
      {
        best.Weights[i] = w[i];
        best.Position[i] = q[i];
      }
    }
  }
  return best;
}

SurfacePoint FindSurfacePoint(const TetMesh& mesh, const double x[3])
{
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  if (numTriangles == 0)
  {
    throw Error("the mesh has no surface (no boundary triangles)");
  }
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  SurfacePoint best = ClosestBoundaryPoint(mesh, x);
  if (best.Triangle < 0 || best.Triangle >= numTriangles)
  {
    std::ostringstream out;
    out << "no surface point found near " << FormatPoint(x)
        << " (its distance to every boundary triangle is not a number)";
    throw Error(out.str());
  }
  const int* t = &triangles[3 * best.Triangle];
  const Eigen::Vector3d a = Eigen::Map<const Eigen::Vector3d>(mesh.GetPoint(t[0]));
  const Eigen::Vector3d n = (Eigen::Map<const Eigen::Vector3d>(mesh.GetPoint(t[1])) - a)
                              .cross(Eigen::Map<const Eigen::Vector3d>(mesh.GetPoint(t[2])) - a)
                              .normalized();
  for (int i = 0; i < 3; ++i)
  {
    best.Normal[i] = n[i];
  }
  return best;
}

double SurfaceTolerance(const std::vector<double>& points, const std::vector<int>& triangles)
{
  const std::size_t numTriangles = triangles.size() / 3;
  double sum = 0.0;
  for (std::size_t f = 0; f < numTriangles; ++f)
  {
    for (int e = 0; e < 3; ++e)
    {
      const double* a = &points[3 * static_cast<std::size_t>(triangles[3 * f + e])];
      const double* b = &points[3 * static_cast<std::size_t>(triangles[3 * f + (e + 1) % 3])];
      sum += std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
        (a[2] - b[2]) * (a[2] - b[2]));
    }
  }
  return numTriangles > 0 ? 0.5 * sum / (3.0 * static_cast<double>(numTriangles)) : 0.0;
}

double SurfaceTolerance(const TetMesh& mesh)
{
  return SurfaceTolerance(mesh.GetPoints(), mesh.GetBoundaryTriangles());
}

PencilEntry EnterPencilBeam(const PencilBeam& beam, const std::string& name,
  const SurfacePoint& entry, double tolerance, double eta)
{
  PencilEntry result;
  if (entry.Distance > tolerance)
  {
    std::ostringstream out;
    out << name << ": entry point " << FormatPoint(beam.Position.data()) << " is "
        << entry.Distance << " mm from the surface (nearest surface point "
        << FormatPoint(entry.Position.data()) << "; at most " << tolerance
        << " mm, half the mean surface edge, is allowed)";
    throw Error(out.str());
  }
  const Eigen::Vector3d d = Eigen::Map<const Eigen::Vector3d>(beam.Direction.data()).normalized();
  const Eigen::Vector3d n = Eigen::Map<const Eigen::Vector3d>(entry.Normal.data());
  const double cosIn = -d.dot(n); // cosine of the angle of incidence
  if (!(cosIn > 1e-6))
  {
    std::ostringstream out;
    out << name << ": direction " << FormatPoint(beam.Direction.data())
        << " does not point into the object at " << FormatPoint(entry.Position.data())
        << " (outward surface normal " << FormatPoint(entry.Normal.data()) << ")";
    throw Error(out.str());
  }
  result.Surface = entry;
  // Snell's law from vacuum (index 1) into eta: the refracted direction
  // t = r d + (r cos_i - cos_t) n with r = 1/eta, n the outward normal.
  const double r = 1.0 / eta;
  const double cosT = std::sqrt(std::max(0.0, 1.0 - r * r * (1.0 - cosIn * cosIn)));
  const Eigen::Vector3d refracted = (r * d + (r * cosIn - cosT) * n).normalized();
  for (int i = 0; i < 3; ++i)
  {
    result.Refracted[i] = refracted[i];
  }
  result.Transmitted = 1.0 - Fresnel::Reflectance(cosIn, eta);
  return result;
}

PencilEntry LocatePencilEntry(const TetMesh& mesh, const OpticalProperties& material,
  const PencilBeam& beam, const std::string& name, double tolerance)
{
  const SurfacePoint entry = FindSurfacePoint(mesh, beam.Position.data());
  // The tet under the entry only when the entry is valid (the checks first).
  const int tet = entry.Distance > tolerance ? -1 : mesh.GetBoundaryTriangleTets()[entry.Triangle];
  PencilEntry result =
    EnterPencilBeam(beam, name, entry, tolerance, tet >= 0 ? material.RefractiveIndex[tet] : 1.0);
  result.Tet = tet;
  return result;
}

std::vector<EquivalentSource> PencilEquivalentSources(const PencilBeam& beam,
  const std::string& name, const PencilEntry& entry, const double muA[3], const double muS[3])
{
  std::vector<EquivalentSource> sources;
  // One equivalent source per distinct depth (Farrell et al. 1992: z0 = 1/mu_t').
  bool done[NumberOfChannels] = {};
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    if (done[c])
    {
      continue;
    }
    EquivalentSource equivalent;
    equivalent.Depth = 1.0 / (muA[c] + muS[c]);
    equivalent.Channel = c;
    PointSource& source = equivalent.Source;
    source.Power = { 0.0, 0.0, 0.0 };
    for (int c2 = c; c2 < NumberOfChannels; ++c2)
    {
      if (1.0 / (muA[c2] + muS[c2]) == equivalent.Depth)
      {
        source.Power[c2] = entry.Transmitted * beam.Power[c2];
        done[c2] = true;
      }
    }
    for (int i = 0; i < 3; ++i)
    {
      source.Position[i] = entry.Surface.Position[i] + equivalent.Depth * entry.Refracted[i];
    }
    source.Label = name;
    sources.push_back(equivalent);
  }
  return sources;
}

std::string DescribeEquivalentSource(const EquivalentSource& source)
{
  std::ostringstream what;
  what << "the equivalent point source one transport mean free path (" << source.Depth
       << " mm, channel " << source.Channel << ") below the entry point, at ";
  return what.str();
}

std::vector<PlacedSource> Sources::Place(
  const TetMesh& mesh, const OpticalProperties& material) const
{
  Validate();
  std::vector<PlacedSource> placed;
  if (Empty())
  {
    return placed;
  }
  const int numTets = mesh.GetNumberOfTets();
  material.Validate(numTets);
  TetLocator locator;
  locator.Build(mesh);
  for (std::size_t k = 0; k < Points_.size(); ++k)
  {
    placed.push_back(
      PlaceAt(locator, mesh, Points_[k], NameOf(Points_[k].Label, "point source", k), "position "));
  }
  const double tolerance = Pencils_.empty() ? 0.0 : SurfaceTolerance(mesh);
  for (std::size_t k = 0; k < Pencils_.size(); ++k)
  {
    const PencilBeam& beam = Pencils_[k];
    const std::string name = NameOf(beam.Label, "pencil beam", k);
    const PencilEntry pencil = LocatePencilEntry(mesh, material, beam, name, tolerance);
    const int tet = pencil.Tet;
    for (const EquivalentSource& equivalent : PencilEquivalentSources(beam, name, pencil,
           &material.AbsorptionCoefficient[3 * static_cast<std::size_t>(tet)],
           &material.ReducedScatteringCoefficient[3 * static_cast<std::size_t>(tet)]))
    {
      placed.push_back(PlaceAt(
        locator, mesh, equivalent.Source, name, DescribeEquivalentSource(equivalent)));
    }
  }
  return placed;
}

std::vector<double> Sources::ComputeLoad(const TetMesh& mesh, const OpticalProperties& material) const
{
  std::vector<double> load(3 * static_cast<std::size_t>(mesh.GetNumberOfPoints()), 0.0);
  for (const PlacedSource& placed : Place(mesh, material))
  {
    const int* tet = mesh.GetTet(placed.Tet);
    for (int a = 0; a < 4; ++a)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        load[3 * static_cast<std::size_t>(tet[a]) + c] += placed.Source.Power[c] * placed.Weights[a];
      }
    }
  }
  return load;
}

std::array<double, NumberOfChannels> Sources::InjectedPower(
  const TetMesh& mesh, const OpticalProperties& material) const
{
  std::array<double, NumberOfChannels> total{};
  for (const PlacedSource& placed : Place(mesh, material))
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      total[c] += placed.Source.Power[c];
    }
  }
  return total;
}

} // namespace translucency
