#include "Detectors.h"

#include "Error.h"
#include "Fresnel.h"
#include "TetMesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace translucency
{

namespace
{

void CheckPointArray(const TetMesh& mesh, const std::vector<double>* values, const char* what)
{
  if (values && values->size() != 3 * static_cast<std::size_t>(mesh.GetNumberOfPoints()))
  {
    std::ostringstream out;
    out << what << " has " << values->size() << " values, expected 3 per mesh point ("
        << 3 * static_cast<std::size_t>(mesh.GetNumberOfPoints()) << ")";
    throw Error(out.str());
  }
}

/// The exitance of the Robin condition: (phi - 2 q) / (2 A) with the fit
/// (as always), q + (phi - 4 q / (1 - Fdr)) / (2 A) in general (equal when
/// A = (1 + Fdr) / (1 - Fdr)).
double Exitance(double phi, double q, const Fresnel::RobinCoefficients& robin,
  Fresnel::BoundaryRule rule)
{
  if (rule == Fresnel::BoundaryRule::Fit)
  {
    return (phi - 2.0 * q) / (2.0 * robin.A);
  }
  return q + (phi - 4.0 * q / (1.0 - robin.Fdr)) / (2.0 * robin.A);
}

} // namespace

PowerBalance ComputePowerBalance(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<double>& fluence, const std::vector<double>* irradiance,
  Fresnel::BoundaryRule rule, const std::vector<char>* boundaryFaces)
{
  material.Validate(mesh.GetNumberOfTets());
  return ComputePowerBalanceOfValidMaterial(
    mesh, material, fluence, irradiance, rule, boundaryFaces);
}

PowerBalance ComputePowerBalanceOfValidMaterial(const TetMesh& mesh,
  const OpticalProperties& material, const std::vector<double>& fluence,
  const std::vector<double>* irradiance, Fresnel::BoundaryRule rule,
  const std::vector<char>* boundaryFaces)
{
  const int numTets = mesh.GetNumberOfTets();
  const std::size_t n = static_cast<std::size_t>(numTets);
  if (material.AbsorptionCoefficient.size() != 3 * n ||
    material.ReducedScatteringCoefficient.size() != 3 * n || material.RefractiveIndex.size() != n)
  {
    material.Validate(numTets); // names the array and its size
  }
  CheckPointArray(mesh, &fluence, "fluence");
  CheckPointArray(mesh, irradiance, "irradiance");
  PowerBalance balance;
  // Absorbed: sum_t mu_a V_t mean(phi at the 4 vertices) (exact for P1 phi).
  for (int t = 0; t < numTets; ++t)
  {
    const int* tet = mesh.GetTet(t);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double sum = 0.0;
      for (int a = 0; a < 4; ++a)
      {
        sum += fluence[3 * static_cast<std::size_t>(tet[a]) + c];
      }
      balance.Absorbed[c] +=
        material.AbsorptionCoefficient[3 * t + c] * mesh.GetTetVolume(t) * 0.25 * sum;
    }
  }
  // Escaped and entering: the P1 integrals over each boundary triangle, A of
  // the tet that owns it.
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const std::vector<double>& areas = mesh.GetBoundaryTriangleAreas();
  const std::vector<int>& owners = mesh.GetBoundaryTriangleTets();
  if (boundaryFaces &&
    boundaryFaces->size() != static_cast<std::size_t>(mesh.GetNumberOfBoundaryTriangles()))
  {
    throw Error("power balance: " + std::to_string(boundaryFaces->size()) +
      " boundary face flags for " + std::to_string(mesh.GetNumberOfBoundaryTriangles()) +
      " boundary triangles");
  }
  for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
  {
    if (boundaryFaces && !(*boundaryFaces)[static_cast<std::size_t>(f)])
      continue;
    const Fresnel::RobinCoefficients robin =
      Fresnel::BoundaryCoefficients(material.RefractiveIndex[owners[f]], rule);
    const double a = robin.A;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double phi = 0.0, q = 0.0;
      for (int v = 0; v < 3; ++v)
      {
        const std::size_t i = 3 * static_cast<std::size_t>(triangles[3 * f + v]) + c;
        phi += fluence[i];
        q += irradiance ? (*irradiance)[i] : 0.0;
      }
      phi *= areas[f] / 3.0;
      q *= areas[f] / 3.0;
      balance.Escaped[c] += Exitance(phi, q, robin, rule);
      balance.BoundaryInjected[c] += q;
    }
  }
  return balance;
}

void AppendFibreSamples(const double* a, const double* b, const double* c, double triangleArea,
  int f, const std::array<double, 3>& centre, const std::array<double, 3>& normal, double radius,
  std::vector<DetectorFootprint::Sample>& samples, double& area)
{
  const Eigen::Vector3d s = Eigen::Map<const Eigen::Vector3d>(centre.data());
  const Eigen::Vector3d ns = Eigen::Map<const Eigen::Vector3d>(normal.data());
  const Eigen::Vector3d p0 = Eigen::Map<const Eigen::Vector3d>(a);
  const Eigen::Vector3d p1 = Eigen::Map<const Eigen::Vector3d>(b);
  const Eigen::Vector3d p2 = Eigen::Map<const Eigen::Vector3d>(c);
  const Eigen::Vector3d centroid = (p0 + p1 + p2) / 3.0;
  const double reach =
    std::max({ (p0 - centroid).norm(), (p1 - centroid).norm(), (p2 - centroid).norm() });
  if ((centroid - s).norm() > radius + reach || (p1 - p0).cross(p2 - p0).dot(ns) <= 0.0)
  {
    return;
  }
  const double edge = std::max({ (p1 - p0).norm(), (p2 - p1).norm(), (p0 - p2).norm() });
  const int m = std::clamp(static_cast<int>(std::ceil(4.0 * edge / radius)), 1, 64);
  const double subArea = triangleArea / (static_cast<double>(m) * m);
  // The m^2 sub-triangles of a uniform split: upward ones with centroid
  // ((i + 1/3)/m, (j + 1/3)/m), downward ones ((i + 2/3)/m, (j + 2/3)/m).
  for (int up = 0; up < 2; ++up)
  {
    const double shift = up == 0 ? 1.0 / 3.0 : 2.0 / 3.0;
    for (int i = 0; i < m; ++i)
    {
      for (int j = 0; i + j <= m - 1 - up; ++j)
      {
        const double u = (i + shift) / m, v = (j + shift) / m;
        const Eigen::Vector3d y = p0 + u * (p1 - p0) + v * (p2 - p0);
        if ((y - s).norm() <= radius)
        {
          samples.push_back({ f, { 1.0 - u - v, u, v }, subArea });
          area += subArea;
        }
      }
    }
  }
}

void AccumulateDetectorSample(const TetMesh& mesh, const OpticalProperties& material, int f,
  const double w[3], double weight, const std::vector<double>& fluence,
  const std::vector<double>* irradiance, Fresnel::BoundaryRule rule, DetectorReading& reading)
{
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const Fresnel::RobinCoefficients robin = Fresnel::BoundaryCoefficients(
    material.RefractiveIndex[mesh.GetBoundaryTriangleTets()[static_cast<std::size_t>(f)]], rule);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    double phi = 0.0, q = 0.0;
    for (int v = 0; v < 3; ++v)
    {
      const std::size_t i = 3 * static_cast<std::size_t>(triangles[3 * static_cast<std::size_t>(f) + v]) + c;
      phi += w[v] * fluence[i];
      q += irradiance ? w[v] * (*irradiance)[i] : 0.0;
    }
    reading.Fluence[c] += weight * phi;
    reading.Exitance[c] += weight * Exitance(phi, q, robin, rule);
  }
}

void CheckDetector(const Detector& detector, const std::string& name,
  const std::array<double, 3>* nearest, double distance, double tolerance)
{
  const double* x = detector.Position.data();
  if (!nearest)
  {
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
    {
      throw Error(name + ": position is not finite");
    }
    if (!std::isfinite(detector.Radius) || detector.Radius < 0.0)
    {
      std::ostringstream out;
      out << name << ": fibre radius " << detector.Radius << " mm (expected a finite value >= 0)";
      throw Error(out.str());
    }
    return;
  }
  if (distance > tolerance)
  {
    const std::array<double, 3>& p = *nearest;
    std::ostringstream out;
    out.precision(6);
    out << name << ": (" << x[0] << ", " << x[1] << ", " << x[2] << ") is off the surface, "
        << distance << " mm from its nearest surface point (" << p[0] << ", " << p[1] << ", "
        << p[2] << "); at most " << tolerance << " mm (half the mean surface edge) is allowed";
    throw Error(out.str());
  }
}

std::vector<DetectorFootprint> LocateDetectors(
  const TetMesh& mesh, const std::vector<Detector>& detectors)
{
  std::vector<DetectorFootprint> footprints;
  if (detectors.empty())
  {
    return footprints;
  }
  const double tolerance = SurfaceTolerance(mesh);
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const std::vector<double>& areas = mesh.GetBoundaryTriangleAreas();
  for (std::size_t k = 0; k < detectors.size(); ++k)
  {
    const Detector& detector = detectors[k];
    const std::string name =
      detector.Label.empty() ? "detector " + std::to_string(k + 1) : detector.Label;
    CheckDetector(detector, name);
    const SurfacePoint surface = FindSurfacePoint(mesh, detector.Position.data());
    CheckDetector(detector, name, &surface.Position, surface.Distance, tolerance);
    DetectorFootprint footprint;
    footprint.SurfacePosition = surface.Position;
    const double radius = detector.Radius;
    if (radius > 0.0)
    {
      double area = 0.0;
      for (int f = 0; f < mesh.GetNumberOfBoundaryTriangles(); ++f)
      {
        AppendFibreSamples(mesh.GetPoint(triangles[3 * f]), mesh.GetPoint(triangles[3 * f + 1]),
          mesh.GetPoint(triangles[3 * f + 2]), areas[f], f, surface.Position, surface.Normal,
          radius, footprint.Samples, area);
      }
      if (area > 0.0)
      {
        footprint.Area = area;
        footprints.push_back(std::move(footprint));
        continue;
      }
      footprint.Samples.clear();
    }
    footprint.Samples.push_back(
      { surface.Triangle, { surface.Weights[0], surface.Weights[1], surface.Weights[2] }, 1.0 });
    footprints.push_back(std::move(footprint));
  }
  return footprints;
}

std::vector<std::pair<int, double>> DetectorFootprint::GetPointWeights(const TetMesh& mesh) const
{
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const double scale = Area > 0.0 ? 1.0 / Area : 1.0;
  std::vector<std::pair<int, double>> weights;
  for (const Sample& sample : Samples)
  {
    for (int v = 0; v < 3; ++v)
    {
      weights.emplace_back(
        triangles[3 * static_cast<std::size_t>(sample.Triangle) + v], sample.Weight * sample.Weights[v] * scale);
    }
  }
  std::sort(weights.begin(), weights.end());
  std::vector<std::pair<int, double>> merged;
  for (const auto& [point, weight] : weights)
  {
    if (!merged.empty() && merged.back().first == point)
    {
      merged.back().second += weight;
    }
    else if (weight != 0.0)
    {
      merged.emplace_back(point, weight);
    }
  }
  return merged;
}

std::vector<DetectorReading> ReadDetectors(const TetMesh& mesh,
  const OpticalProperties& material, const std::vector<Detector>& detectors,
  const std::vector<double>& fluence, const std::vector<double>* irradiance,
  Fresnel::BoundaryRule rule)
{
  material.Validate(mesh.GetNumberOfTets());
  CheckPointArray(mesh, &fluence, "fluence");
  CheckPointArray(mesh, irradiance, "irradiance");
  return ReadDetectorFootprints(
    mesh, material, LocateDetectors(mesh, detectors), fluence, irradiance, rule);
}

std::vector<DetectorReading> ReadDetectorFootprints(const TetMesh& mesh,
  const OpticalProperties& material, const std::vector<DetectorFootprint>& footprints,
  const std::vector<double>& fluence, const std::vector<double>* irradiance,
  Fresnel::BoundaryRule rule)
{
  CheckPointArray(mesh, &fluence, "fluence");
  CheckPointArray(mesh, irradiance, "irradiance");
  std::vector<DetectorReading> readings;
  for (const DetectorFootprint& footprint : footprints)
  {
    DetectorReading reading;
    reading.SurfacePosition = footprint.SurfacePosition;
    for (const DetectorFootprint::Sample& sample : footprint.Samples)
    {
      AccumulateDetectorSample(mesh, material, sample.Triangle, sample.Weights, sample.Weight,
        fluence, irradiance, rule, reading);
    }
    if (footprint.Area > 0.0)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        reading.Fluence[c] /= footprint.Area;
        reading.Exitance[c] /= footprint.Area;
      }
      reading.Area = footprint.Area;
    }
    readings.push_back(reading);
  }
  return readings;
}

} // namespace translucency
