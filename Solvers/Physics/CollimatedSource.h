/**
 * @file CollimatedSource.h
 * @brief The extended-source model of a collimated broad beam (issue 19;
 * Documentation/DiffuseOptics.md, "Collimated beams: the extended source").
 *
 * Instead of entering as the boundary irradiance q, the transmitted part of a
 * directional light travels on, unscattered, along the refracted direction
 * and decays as exp(-mu_t' s) (s the path length inside the medium, mu_t' =
 * mu_a + mu_s'); what it loses to scattering is the isotropic volume source
 * mu_s' E_c of the diffusion equation and what it loses to absorption is
 * absorbed directly (Star 1995, "Diffusion theory of light transport", in
 * Welch & van Gemert, Optical-Thermal Response of Laser-Irradiated Tissue,
 * the collimated-plus-diffuse decomposition with the similarity relation
 * g* = 0: the scattered light of the reduced beam is isotropic, so the
 * first-moment source and its boundary term vanish; DiffuseOptics.md derives
 * the general term for our boundary condition). The total fluence rate is
 * phi_d + E_c.
 */
#pragma once

#include "LightSources.h"
#include "OpticalProperties.h"

#include <array>
#include <vector>

namespace translucency
{

class TetMesh;

/// How a directional (collimated) light enters the diffusion model.
enum class CollimatedModel
{
  Surface,  ///< as boundary irradiance q (TransCut eq. 2), the default
  Extended, ///< as the volume source mu_s' E_c (CollimatedSource.h)
  /// Extended, with the Robin condition of every boundary term of the solve
  /// from the Fresnel moments (Fresnel::BoundaryRule::Moments) instead of
  /// the fit: the consistent P1 (Marshak) condition. DiffuseOptics.md has
  /// the derivation and the gain against Monte Carlo.
  ExtendedMoments
};

/// True for the models with the volume source (Extended, ExtendedMoments).
inline bool IsExtendedCollimatedModel(CollimatedModel model)
{
  return model != CollimatedModel::Surface;
}

/// The unscattered beam of the directional lights and its source terms.
struct CollimatedSource
{
  /// Collimated fluence rate E_c (W/mm^2), 3 per mesh point (R, G, B).
  std::vector<double> Fluence;
  /// Weak-form load integral of mu_s' E_c phi_i dV (W), 3 per mesh point:
  /// the volume source of the diffuse fluence.
  std::vector<double> Load;
  /// Integral of mu_s' E_c (the sum of Load) and of mu_a E_c over the
  /// object (W per channel): the beam's power scattered into the diffuse
  /// field and absorbed directly.
  std::array<double, NumberOfChannels> Scattered{};
  std::array<double, NumberOfChannels> Absorbed{};
  /// Power of the beams transmitted into the object (W per channel): the
  /// sum over the boundary triangles of (S_f / 3) sum of the corner values
  /// of E cos(theta_i) F_t(theta_i) (ComputeTriangleCornerIrradiance of the
  /// directional lights).
  std::array<double, NumberOfChannels> Entering{};
};

/**
 * The extended source of the directional lights in `lights` (the others are
 * ignored: they stay boundary irradiance).
 *
 * Per mesh point x and light (direction of travel d, irradiance E), a ray
 * from x towards the light (-d; from just inside the surface for a boundary
 * point) finds the entry point: the first boundary triangle hit, at distance
 * t, with outward normal n and cos(theta_i) = n . (-d) > 0. With shadows,
 * the light must reach the entry point (a shadow ray as in
 * ComputeBoundaryIrradiance). The beam is refracted at the entry point
 * (Snell: sin(theta_t) = sin(theta_i) / eta) and the path length to the
 * depth t cos(theta_i) below the entry plane is s = t cos(theta_i) /
 * cos(theta_t) (the local-slab approximation: exact for a flat entry face);
 *   E_c = E cos(theta_i) F_t(theta_i) / cos(theta_t) exp(-mu_t' s),
 * with mu_t', eta of the tet under the entry triangle (the homogeneous
 * approximation along the path).
 *
 * The load integrates mu_s'(tet) E_c phi_i over each tet with E_c
 * interpolated log-linearly between the tet's vertices (exact for one beam
 * through a flat face into a homogeneous medium), linearly where a vertex
 * has E_c = 0, by a composite rule: the tet split L times into 8 by its
 * edge midpoints, 4 points of degree 2 in each sub-tet, L the smallest
 * level (<= 4) at which ln E_c varies by at most 0.5 across a sub-tet.
 *
 * Throws translucency::Error on invalid lights or material (sizes,
 * values). OpenMP-parallel over the points.
 */
CollimatedSource ComputeCollimatedSource(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<LightSource>& lights, bool shadows);

/// The lights without the directional ones (what stays boundary irradiance
/// under the extended model).
std::vector<LightSource> NonCollimatedLights(const std::vector<LightSource>& lights);

} // namespace translucency
