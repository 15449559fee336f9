/**
 * @file Fresnel.h
 * @brief Fresnel helpers for a smooth dielectric boundary (outside: index 1).
 *
 * Implements the quantities of the diffusive-source boundary condition
 * (TransCut, eq. 2-3; Jensen et al. 2001): the diffuse Fresnel
 * reflectance Fdr, the boundary mismatch term A and the Fresnel transmittance
 * F_t.
 */
#pragma once

#include <array>

namespace translucency
{
namespace Fresnel
{

/// Diffuse Fresnel reflectance Fdr(eta) = -1.440/eta^2 + 0.710/eta + 0.668 +
/// 0.0636 eta (Jensen et al. 2001 fit; TransCut, eq. 2). eta is the relative
/// refractive index of the medium (> 0, dimensionless).
double DiffuseReflectance(double eta);

/// Boundary mismatch A = (1 + Fdr) / (1 - Fdr) (TransCut eq. 2).
double MismatchA(double eta);

/// Fresnel reflectance of unpolarised light crossing a smooth interface
/// between vacuum (index 1) and a medium of index eta. cosOutside is the
/// cosine, against the surface normal, of the direction on the vacuum side
/// (in [0, 1]); by reciprocity the same value holds for light leaving the
/// medium towards that direction. Total internal reflection cannot occur for
/// a direction given on the vacuum side.
double Reflectance(double cosOutside, double eta);

/// Fresnel transmittance F_t = 1 - Reflectance(cosOutside, eta).
double Transmittance(double cosOutside, double eta);

/**
 * The first two angular moments of the Fresnel reflectance seen from inside
 * the medium (relative index eta > 0; total internal reflection counted as
 * R = 1), mu the cosine of the internal direction against the normal:
 *   R_phi = 2 int_0^1 R(mu) mu dmu,    R_J = 3 int_0^1 R(mu) mu^2 dmu
 * (Haskell et al. 1994, JOSA A 11(10); Aronson 1995, JOSA A 12(11)). R_phi
 * is the hemispherical diffuse reflectance that DiffuseReflectance() fits
 * (Fdr), R_J its flux-weighted companion. Gauss-Legendre over the outside
 * cosine (smooth there), exact to round-off; equal to 0 at eta = 1.
 */
double ReflectanceMomentPhi(double eta);
double ReflectanceMomentJ(double eta);

/**
 * The half-range moments r_m = int_0^1 R(mu) mu^m dmu, m = 0..6, of the
 * Fresnel reflectance seen from inside the medium (relative index eta > 0;
 * total internal reflection counted as R = 1; mu the cosine of the internal
 * direction against the normal), by the quadrature of ReflectanceMomentPhi
 * (so R_phi = 2 r_1 and R_J = 3 r_2). The SP3 partly reflecting boundary
 * conditions (Klose & Larsen 2006; Sp3Solver.h) are built from r_1..r_6.
 * All 0 at eta = 1.
 */
std::array<double, 7> ReflectanceHalfRangeMoments(double eta);

/// Which boundary coefficients the Robin condition
/// phi + 2 A kappa dphi/dn = 4 q / (1 - Fdr) uses.
enum class BoundaryRule
{
  /// Fdr = DiffuseReflectance (the fit), A = (1 + Fdr) / (1 - Fdr)
  /// (TransCut eq. 2): the project's default.
  Fit,
  /// The partial-current (Marshak) condition of the P1 radiance with the
  /// Fresnel moments: Fdr = R_phi, A = (1 + R_J) / (1 - R_phi) (Haskell et
  /// al. 1994; DiffuseOptics.md derives it). The extended collimated model
  /// "extended-moments" uses it.
  Moments
};

/// The coefficients of the Robin condition for one refractive index.
struct RobinCoefficients
{
  double A = 1.0;   ///< boundary mismatch (dimensionless, >= 1 for eta >= 1)
  double Fdr = 0.0; ///< diffuse reflectance of the source term 4 q / (1 - Fdr)
};
RobinCoefficients BoundaryCoefficients(double eta, BoundaryRule rule);

/// Hemispherical cosine-weighted transmittance for uniform incident radiance:
/// (1/pi) * integral over the outside hemisphere of F_t(w) (n.w) dw, so that
/// a uniform radiance L (W/mm^2/sr) gives q = pi * L * UniformTransmittance.
double UniformTransmittance(double eta);

} // namespace Fresnel
} // namespace translucency
