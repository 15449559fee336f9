#include "Radiance.h"
#include "ResourceLimits.h"

#include "Error.h"
#include "Fresnel.h"
#include "Strings.h"
#include "TetMesh.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace translucency
{

namespace
{

constexpr double Pi = 3.14159265358979323846;

void CheckTetEta(const TetMesh& mesh, const std::vector<double>& tetEta)
{
  if (tetEta.size() != static_cast<size_t>(mesh.GetNumberOfTets()))
  {
    std::ostringstream os;
    os << "RefractiveIndex has " << tetEta.size() << " values but the mesh has "
       << mesh.GetNumberOfTets() << " tets";
    throw Error(os.str());
  }
}

} // namespace

const char* RadianceReadoutName(RadianceReadout readout)
{
  return readout == RadianceReadout::Paper ? "paper" : "energy-conserving";
}

std::vector<std::string> GetRadianceReadoutNames()
{
  return { RadianceReadoutName(RadianceReadout::EnergyConserving),
    RadianceReadoutName(RadianceReadout::Paper) };
}

RadianceReadout RadianceReadoutFromName(const std::string& name)
{
  for (RadianceReadout r : { RadianceReadout::EnergyConserving, RadianceReadout::Paper })
  {
    if (ToLower(name) == RadianceReadoutName(r))
    {
      return r;
    }
  }
  throw Error("unknown radiance read-out '" + name + "': use 'energy-conserving' (eq. 3 / eta^2, " +
    "conserves energy) or 'paper' (TransCut eq. 3 as printed)");
}

double OutgoingRadiance(double phi, double q, double eta, double cosOut, RadianceReadout readout,
  Fresnel::BoundaryRule rule)
{
  if (!(cosOut > 0.0))
  {
    return 0.0;
  }
  const double ft = Fresnel::Transmittance(std::min(cosOut, 1.0), eta);
  double radiance = 0.0;
  if (rule == Fresnel::BoundaryRule::Fit)
  {
    const double fdr = Fresnel::DiffuseReflectance(eta);
    const double a = Fresnel::MismatchA(eta);
    // TransCut eq. 3: L_o = F_t/(4 pi) [ (1 + 1/A) phi - 4/(1 + Fdr) q ]
    radiance = ft / (4.0 * Pi) * ((1.0 + 1.0 / a) * phi - 4.0 / (1.0 + fdr) * q);
  }
  else
  {
    // Eq. 3 written with the exitance of the Robin condition (Radiance.h):
    // L_o = F_t J / (pi (1 - Fdr)), J = q + (phi - 4 q/(1 - Fdr))/(2 A),
    // which is eq. 3 for the fit's A and Fdr, and emits exactly J (after
    // the 1/eta^2 below) when Fdr is the hemispherical internal reflectance
    // R_phi, as with the Fresnel moments.
    const Fresnel::RobinCoefficients robin = Fresnel::BoundaryCoefficients(eta, rule);
    const double exitance = q + (phi - 4.0 * q / (1.0 - robin.Fdr)) / (2.0 * robin.A);
    radiance = ft * exitance / (Pi * (1.0 - robin.Fdr));
  }
  if (readout == RadianceReadout::EnergyConserving)
  {
    radiance /= eta * eta; // radiance from inside to vacuum scales by 1/eta^2 (n^2 law)
  }
  return std::max(0.0, radiance);
}

std::vector<double> BoundaryPointRefractiveIndex(const TetMesh& mesh,
  const std::vector<double>& tetEta)
{
  CheckTetEta(mesh, tetEta);
  std::vector<double> eta(mesh.GetNumberOfPoints(), 0.0);
  const std::vector<int>& boundaryPoints = mesh.GetBoundaryPoints();
  const long long numBoundary = static_cast<long long>(boundaryPoints.size());
#pragma omp parallel for schedule(static)
  for (long long k = 0; k < numBoundary; ++k)
  {
    eta[boundaryPoints[k]] = BoundaryPointRefractiveIndexAt(mesh, tetEta.data(), k);
  }
  return eta;
}

std::vector<double> BoundaryRadiance(const TetMesh& mesh, const std::vector<double>& fluence,
  const std::vector<double>& irradiance, const std::vector<double>& pointEta,
  const double* viewPoint, RadianceReadout readout, Fresnel::BoundaryRule rule)
{
  const size_t numPoints = static_cast<size_t>(mesh.GetNumberOfPoints());
  if (fluence.size() != 3 * numPoints || irradiance.size() != 3 * numPoints ||
    pointEta.size() != numPoints)
  {
    std::ostringstream os;
    os << "BoundaryRadiance: the mesh has " << numPoints << " points but fluence has "
       << fluence.size() << " values, irradiance " << irradiance.size() << " and eta "
       << pointEta.size() << " (3, 3 and 1 per point expected)";
    throw Error(os.str());
  }
  const std::vector<int>& boundary = mesh.GetBoundaryPoints();
  const std::vector<double>& normals = mesh.GetPointNormals();
  const long long n = static_cast<long long>(boundary.size());
  std::vector<double> radiance(3 * boundary.size());
#pragma omp parallel for schedule(static)
  for (long long k = 0; k < n; ++k)
  {
    const size_t i = static_cast<size_t>(boundary[k]);
    const double* nrm = &normals[3 * i];
    const double cosOut = ViewCosine(viewPoint, mesh.GetPoint(static_cast<int>(i)), nrm);
    for (int c = 0; c < 3; ++c)
    {
      radiance[3 * k + c] = OutgoingRadiance(
        fluence[3 * i + c], irradiance[3 * i + c], pointEta[i], cosOut, readout, rule);
    }
  }
  RequireFinite(radiance, "Radiance", OverflowCause());
  return radiance;
}

std::vector<double> PointRefractiveIndex(const TetMesh& mesh, const std::vector<double>& tetEta)
{
  std::vector<double> eta = BoundaryPointRefractiveIndex(mesh, tetEta);
  const int numPoints = mesh.GetNumberOfPoints();
  const std::vector<int>& offsets = mesh.GetPointTetOffsets();
  const std::vector<int>& pointTets = mesh.GetPointTets();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < numPoints; ++i)
  {
    if (mesh.IsBoundaryPoint(i))
    {
      continue;
    }
    const int count = offsets[i + 1] - offsets[i];
    if (count == 0)
    {
      eta[i] = 1.0;
      continue;
    }
    double sum = 0.0;
    for (int k = offsets[i]; k < offsets[i + 1]; ++k)
    {
      sum += tetEta[pointTets[k]];
    }
    eta[i] = sum / count;
  }
  return eta;
}

} // namespace translucency
