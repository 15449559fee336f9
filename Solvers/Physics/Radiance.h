/**
 * @file Radiance.h
 * @brief Outgoing radiance read-out (TransCut eq. 3, after Arbree et al.).
 */
#pragma once

#include "Fresnel.h"
#include "TetMesh.h"

#include <cstddef>
#include <vector>

namespace translucency
{

/**
 * L_o = F_t(w_o)/(4 pi) [ (1 + 1/A) phi - 4/(1 + Fdr) q ]   (TransCut eq. 3)
 * with the fit's A = (1 + Fdr)/(1 - Fdr) (Fresnel::BoundaryRule::Fit). With
 * another rule (`rule`, the Robin coefficients the solve used: Moments for
 * the "extended-moments" collimated model) the same read-out is written
 * L_o = F_t/(4 pi) [ phi + (phi - 4 q/(1 - Fdr)) / A ], which is eq. 3 for
 * the fit and the matching flux of the Robin condition otherwise.
 * @param phi fluence at the point (W/mm^2)
 * @param q boundary irradiance at the point (W/mm^2)
 * @param eta refractive index at the point
 * @param cosOut cosine between the outgoing direction and the outward normal
 *        (<= 0 gives 0: the point is not seen from that side)
 * @param nSquaredLaw divide by eta^2 (radiance leaving a medium of index eta
 *        into vacuum, the n^2 law). Eq. 3 as printed omits it, and then does
 *        not conserve energy: with mu_a = 0 its exitance is eta^2 times the
 *        power that entered (1.69x at eta = 1.3; see Documentation/Solvers.md).
 *        Default false (the paper's formula).
 * @return radiance (W/mm^2/sr), clamped below at 0
 */
double OutgoingRadiance(double phi, double q, double eta, double cosOut, bool nSquaredLaw = false,
  Fresnel::BoundaryRule rule = Fresnel::BoundaryRule::Fit);

/**
 * OutgoingRadiance() at every boundary point of the mesh, in the order of
 * mesh.GetBoundaryPoints(): 3 values (R, G, B, W/mm^2/sr) per boundary point.
 * @param fluence, irradiance 3 values per mesh point (W/mm^2)
 * @param pointEta refractive index per mesh point (PointRefractiveIndex())
 * @param viewPoint null: every point seen along its normal (cosOut = 1);
 *        else seen from this point (mm): cosOut is the cosine between the
 *        point normal and the direction to it (0 at the view point itself)
 * @param nSquaredLaw, rule see OutgoingRadiance()
 * OpenMP-parallel over the points (each value independent: same bits at any
 * thread count). Throws translucency::Error on wrong array sizes.
 */
std::vector<double> BoundaryRadiance(const TetMesh& mesh, const std::vector<double>& fluence,
  const std::vector<double>& irradiance, const std::vector<double>& pointEta,
  const double* viewPoint, bool nSquaredLaw = false,
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
