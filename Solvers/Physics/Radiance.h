/**
 * @file Radiance.h
 * @brief Outgoing radiance read-out (TransCut eq. 3, after Arbree et al.).
 */
#pragma once

#include "Fresnel.h"
#include "TetMesh.h"

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace translucency
{

/**
 * Which form of the radiance read-out to evaluate.
 *  - EnergyConserving (the default): TransCut eq. 3 divided by eta^2, the n^2
 *    law of radiance leaving a medium of index eta into vacuum. A
 *    non-absorbing object then emits the power it receives (up to the Fdr
 *    fit); the Monte Carlo reference agrees with it.
 *  - Paper: eq. 3 as printed, which omits the 1/eta^2 and so emits eta^2
 *    times the power that entered (1.69x at eta = 1.3; Documentation/Solvers.md).
 *    Kept by name to reproduce TransCut's figures.
 */
enum class RadianceReadout
{
  EnergyConserving,
  Paper
};

/// "energy-conserving" or "paper" (the CLI's and the plugin's names).
const char* RadianceReadoutName(RadianceReadout readout);
/// The names of RadianceReadoutName(), the default first.
std::vector<std::string> GetRadianceReadoutNames();
/**
 * The read-out named `name` (case-insensitive). Throws translucency::Error
 * naming the valid choices for any other name.
 */
RadianceReadout RadianceReadoutFromName(const std::string& name);

/**
 * L_o = F_t(w_o)/(4 pi) [ (1 + 1/A) phi - 4/(1 + Fdr) q ]   (TransCut eq. 3),
 * divided by eta^2 unless `readout` is RadianceReadout::Paper,
 * with the fit's A = (1 + Fdr)/(1 - Fdr) (Fresnel::BoundaryRule::Fit). With
 * another rule (`rule`, the Robin coefficients the solve used: Moments for
 * the "extended-moments" collimated model) the same read-out is written with
 * the exitance of that Robin condition, J = q + (phi - 4 q/(1 - Fdr))/(2 A):
 * L_o = F_t J / (pi (1 - Fdr)), which is eq. 3 for the fit (J = (phi -
 * 2 q)/(2 A) there) and, divided by eta^2, emits exactly J over the
 * hemisphere when Fdr is the internal hemispherical reflectance R_phi (the
 * moments: pi eta^2 (1 - R_phi) is the integral of F_t cos, by
 * reciprocity). The earlier form F_t/(4 pi) [phi + (phi - 4 q/(1 - Fdr))/A]
 * emitted (A + 1)(1 - R_phi)/2 = 0.93 J with the moments at eta 1.3.
 * @param phi fluence at the point (W/mm^2)
 * @param q boundary irradiance at the point (W/mm^2)
 * @param eta refractive index at the point
 * @param cosOut cosine between the outgoing direction and the outward normal
 *        (<= 0 gives 0: the point is not seen from that side)
 * @param readout EnergyConserving (default: divide by eta^2, the n^2 law) or
 *        Paper (eq. 3 as printed; see RadianceReadout)
 * @return radiance (W/mm^2/sr), clamped below at 0
 */
double OutgoingRadiance(double phi, double q, double eta, double cosOut,
  RadianceReadout readout = RadianceReadout::EnergyConserving,
  Fresnel::BoundaryRule rule = Fresnel::BoundaryRule::Fit);

/**
 * The cosOut of OutgoingRadiance() for a boundary point x with unit outward
 * normal `normal` seen from `viewPoint`: the cosine between the normal and
 * the direction from x to the view point (0 at the view point itself); 1
 * (seen along the normal) when viewPoint is null. The one definition the
 * diffusion, SP3 and per-piece read-outs share.
 */
inline double ViewCosine(const double* viewPoint, const double* x, const double* normal)
{
  if (!viewPoint)
  {
    return 1.0;
  }
  const double d[3] = { viewPoint[0] - x[0], viewPoint[1] - x[1], viewPoint[2] - x[2] };
  const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  return len > 0 ? (d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2]) / len : 0.0;
}

/**
 * OutgoingRadiance() at every boundary point of the mesh, in the order of
 * mesh.GetBoundaryPoints(): 3 values (R, G, B, W/mm^2/sr) per boundary point.
 * @param fluence, irradiance 3 values per mesh point (W/mm^2)
 * @param pointEta refractive index per mesh point (PointRefractiveIndex())
 * @param viewPoint null: every point seen along its normal (cosOut = 1);
 *        else seen from this point (mm): cosOut is the cosine between the
 *        point normal and the direction to it (0 at the view point itself)
 * @param readout, rule see OutgoingRadiance()
 * OpenMP-parallel over the points (each value independent: same bits at any
 * thread count). Throws translucency::Error on wrong array sizes.
 */
std::vector<double> BoundaryRadiance(const TetMesh& mesh, const std::vector<double>& fluence,
  const std::vector<double>& irradiance, const std::vector<double>& pointEta,
  const double* viewPoint, RadianceReadout readout = RadianceReadout::EnergyConserving,
  Fresnel::BoundaryRule rule = Fresnel::BoundaryRule::Fit);

/**
 * Refractive index seen by each mesh point: the area-weighted mean of the
 * RefractiveIndex of the tets owning the boundary triangles around it
 * (interior points get the mean over their tets; points used by no tet get 1).
 * Throws translucency::Error if tetEta does not hold one value per tet.
 */
std::vector<double> PointRefractiveIndex(const TetMesh& mesh, const std::vector<double>& tetEta);

/**
 * PointRefractiveIndex restricted to the boundary points (the only ones the
 * boundary condition needs); other points get 0. Cheaper: it reads only the
 * boundary triangles.
 */
std::vector<double> BoundaryPointRefractiveIndex(
  const TetMesh& mesh, const std::vector<double>& tetEta);

/**
 * The value BoundaryPointRefractiveIndex gives boundary point
 * mesh.GetBoundaryPoints()[k] (same bits): the area-weighted mean eta of
 * the tets owning its boundary triangles. `tetEta` has one value per tet.
 * For loops over the boundary points that need no per-point array.
 */
inline double BoundaryPointRefractiveIndexAt(const TetMesh& mesh, const double* tetEta, size_t k)
{
  const int* offsets = mesh.GetBoundaryPointTriangleOffsets().data();
  const int* triangles = mesh.GetBoundaryPointTriangles().data();
  const int* owners = mesh.GetBoundaryTriangleTets().data();
  const double* areas = mesh.GetBoundaryTriangleAreas().data();
  double sum = 0.0;
  for (int m = offsets[k]; m < offsets[k + 1]; ++m)
  {
    sum += areas[triangles[m]] * tetEta[owners[triangles[m]]];
  }
  return sum / mesh.GetBoundaryAreas()[mesh.GetBoundaryPoints()[k]];
}

} // namespace translucency
