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

/// Hemispherical cosine-weighted transmittance for uniform incident radiance:
/// (1/pi) * integral over the outside hemisphere of F_t(w) (n.w) dw, so that
/// a uniform radiance L (W/mm^2/sr) gives q = pi * L * UniformTransmittance.
double UniformTransmittance(double eta);

} // namespace Fresnel
} // namespace translucency
