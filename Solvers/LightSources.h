/**
 * @file LightSources.h
 * @brief Boundary irradiance q from simple light sources (SPEC "The physics":
 * q(x) = integral of L_i (n . w_i) F_t(w_i) dw_i; TransCut eq. 2).
 *
 * Visibility (self-shadowing) is the caller's business: these functions give
 * the unoccluded contribution and the direction to test.
 */
#pragma once

#include <array>

namespace translucency
{

/// A white or coloured light. Units per type:
/// - Directional: irradiance E (W/mm^2) on a surface facing the light;
///   Direction is the direction the light travels (need not be unit length).
/// - Point: radiant intensity I (W/sr) at Position (mm).
/// - Uniform: irradiance E (W/mm^2) an unoccluded flat surface receives from
///   uniform incident radiance L = E / pi from every direction.
struct LightSource
{
  enum class Kind
  {
    Directional,
    Point,
    Uniform
  };
  Kind Type = Kind::Directional;
  std::array<double, 3> Direction{ 0.0, 0.0, -1.0 };
  std::array<double, 3> Position{ 0.0, 0.0, 0.0 };
  std::array<double, 3> Power{ 1.0, 1.0, 1.0 }; ///< E or I per channel (see above)
};

/**
 * Unoccluded irradiance transmitted into the medium at a boundary point
 * (W/mm^2 per channel) for a directional or point light.
 * @param x point (mm), @param n outward unit normal, @param eta refractive index
 * @param toLight unit direction from x towards the light (output)
 * @param distance distance to the light (mm; infinity for directional) (output)
 * @return false (and q = 0) if the light is behind the surface.
 */
bool DirectIrradiance(const LightSource& light, const double x[3], const double n[3], double eta,
  double q[3], double toLight[3], double& distance);

/**
 * Cosine-weighted direction number k of `count` on the hemisphere around n
 * (stratified over a Fibonacci spiral, rotated by `rotation` in [0, 1) to
 * decorrelate neighbouring points). Returns the cosine to n.
 */
double HemisphereDirection(const double n[3], int k, int count, double rotation, double w[3]);

} // namespace translucency
