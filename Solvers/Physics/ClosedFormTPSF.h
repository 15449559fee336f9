/**
 * @file ClosedFormTPSF.h
 * @brief Closed-form time-resolved diffusion (Patterson, Chance & Wilson
 * 1989, Appl. Opt. 28(12) 2331-2336): the infinite-medium Green's function
 * and the semi-infinite reflectance of a pencil beam, with the zero and the
 * extrapolated boundary; gate and fibre averages of them.
 *
 * Shared by the time-resolved tests (TestTimeResolved, TestMonteCarloSources)
 * and `translucency compare`'s TPSF plot (Documentation/DiffuseOptics.md).
 * Units: lengths in mm, times in ns, coefficients in 1/mm, c_m the speed of
 * light in the medium in mm/ns (SpeedOfLightMillimetresPerNanosecond / eta),
 * D = kappa = 1 / (3 (mu_a + mu_s')) in mm. A pulse of energy P (J) at t = 0
 * gives a fluence rate in J/(mm^2 ns) and a reflectance (flux) in
 * J/(mm^2 ns) per J: the normalisation of the solvers' TPSFs.
 */
#pragma once

#include <cmath>
#include <functional>

namespace translucency
{

/// The medium of a closed form: mu_a (1/mm), kappa = D (mm), c_m (mm/ns).
struct ClosedFormMedium
{
  double MuA = 0.0;
  double Kappa = 1.0;
  double Cm = 1.0;
};

/**
 * Patterson et al. 1989, eq. 2: the fluence rate (J/(mm^2 ns)) at distance
 * r (mm) and time t (ns, > 0) of a pulse of energy `energy` (J) emitted at
 * r = 0, t = 0 in an infinite medium:
 *   P c_m (4 pi D c_m t)^(-3/2) exp(-r^2 / (4 D c_m t) - mu_a c_m t).
 * 0 for t <= 0.
 */
double InfiniteMediumFluence(double r, double t, const ClosedFormMedium& medium, double energy);

/**
 * Patterson et al. 1989, eq. 4: the reflectance (flux, J/(mm^2 ns) per J)
 * at distance rho (mm) from a pencil beam on a semi-infinite medium, with
 * zero fluence at the surface and the isotropic source at depth z0 (mm):
 *   (4 pi D c_m)^(-3/2) z0 t^(-5/2) exp(-mu_a c_m t) exp(-(rho^2 + z0^2) / (4 D c_m t)).
 * 0 for t <= 0.
 */
double SemiInfiniteReflectance(double rho, double t, const ClosedFormMedium& medium, double z0);

/**
 * The same with the extrapolated boundary (the fluence vanishes at z = -zb,
 * zb = 2 A D for the project's Robin condition; image source at
 * -(z0 + 2 zb); Farrell et al. 1992's dipole in the time domain), the flux
 * -D dphi/dz at the surface:
 *   (4 pi D c_m)^(-3/2) t^(-5/2) exp(-mu_a c_m t)
 *     [z0 exp(-(rho^2 + z0^2) / 4Dc_m t) + (z0 + 2 zb) exp(-(rho^2 + (z0 + 2 zb)^2) / 4Dc_m t)] / 2.
 * 0 for t <= 0.
 */
double SemiInfiniteReflectanceExtrapolated(
  double rho, double t, const ClosedFormMedium& medium, double z0, double zb);

/**
 * The fluence rate at the surface (J/(mm^2 ns) per J) of the extrapolated-
 * boundary dipole: c_m (4 pi D c_m t)^(-3/2) exp(-mu_a c_m t)
 * [exp(-(rho^2 + z0^2) / 4Dc_m t) - exp(-(rho^2 + (z0 + 2 zb)^2) / 4Dc_m t)].
 * 0 for t <= 0.
 */
double SemiInfiniteSurfaceFluenceExtrapolated(
  double rho, double t, const ClosedFormMedium& medium, double z0, double zb);

/**
 * The average of f over the gate [t0, t1] (ns, t1 > t0): composite Simpson
 * with `intervals` (even, default 64) intervals; f is taken as 0 at t <= 0
 * (the closed forms' singular start).
 */
double GateAverage(const std::function<double(double)>& f, double t0, double t1,
  int intervals = 64);

/**
 * The average of f(d) over a disc of radius `radius` (mm) whose centre is
 * at distance rho (mm) from the source axis, d the distance of a disc point
 * from the axis: a polar grid of `rings` x `sectors` cells at the cell
 * centres (default 8 x 16), weighted by area. radius 0: f(rho).
 */
double DiscAverage(const std::function<double(double)>& f, double rho, double radius,
  int rings = 8, int sectors = 16);

} // namespace translucency
