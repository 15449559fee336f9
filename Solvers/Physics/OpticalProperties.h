/**
 * @file OpticalProperties.h
 * @brief Piecewise-constant optical coefficients, one value set per tet.
 */
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace translucency
{

/// Number of colour channels (R, G, B) solved for.
constexpr int NumberOfChannels = 3;

/// The speed of light in vacuum, mm/ns (the time-resolved solves, the Monte
/// Carlo time of flight and the collimated beam's delay).
constexpr double SpeedOfLightMillimetresPerNanosecond = 299.792458;

/**
 * Per-tet optical coefficients (TransCut, eq. 1). Arrays are owned here.
 * AbsorptionCoefficient and ReducedScatteringCoefficient hold 3 values per
 * tet (R, G, B, 1/mm); RefractiveIndex holds 1 value per tet (dimensionless).
 */
struct OpticalProperties
{
  std::vector<double> AbsorptionCoefficient;        ///< mu_a, 1/mm, >= 0
  std::vector<double> ReducedScatteringCoefficient; ///< sigma_s', 1/mm, >= 0
  std::vector<double> RefractiveIndex;              ///< eta, > 0
  /**
   * Optional anisotropy g of the phase function (mean cosine of the
   * scattering angle, dimensionless), 3 per tet (R, G, B), in (-1, 1);
   * empty (the default) = 0 everywhere. Only the SP3 solver reads it: with
   * it, the scattering coefficient is mu_s = sigma_s' / (1 - g) (so
   * sigma_s' stays the reduced one every other solver uses).
   */
  std::vector<double> Anisotropy;

  /// g of tet t, channel c (0 when Anisotropy is empty).
  double GetAnisotropy(int t, int c) const
  {
    return Anisotropy.empty() ? 0.0 : Anisotropy[3 * static_cast<std::size_t>(t) + c];
  }

  /// Uniform material on numTets tets.
  static OpticalProperties Uniform(
    int numTets, const double muA[3], const double sigmaS[3], double eta);

  /**
   * Throw translucency::Error unless the arrays have the sizes for numTets
   * tets and every value is finite, mu_a >= 0, mu_a + sigma_s' > 0 and
   * eta > 0, and Anisotropy is empty or has 3 finite values per tet in
   * (-1, 1). The message names the array, the tet, the channel and the value.
   */
  void Validate(int numTets) const;

  /**
   * Validate for a material of which only `tets` can have changed since it
   * was last validated (a paint of a kept material): the sizes for numTets
   * tets and the listed tets' values; an invalid one gets Validate's
   * message (its lowest invalid tet).
   */
  void ValidateTets(int numTets, const std::vector<int>& tets) const;

  /// Whether mu_a, sigma_s' and eta equal `other`'s bit for bit (the
  /// anisotropy is not compared): the kept-material tests of the solvers.
  bool SameCoefficients(const OpticalProperties& other) const;

  /// kappa = 1 / (3 (mu_a + sigma_s')) of tet t, channel c (mm).
  double Kappa(int t, int c) const
  {
    return 1.0 / (3.0 * (AbsorptionCoefficient[3 * t + c] + ReducedScatteringCoefficient[3 * t + c]));
  }
};

/// A named measured material (Jensen et al. 2001; Documentation/Materials.md).
struct MaterialPreset
{
  std::string Name;
  double ReducedScattering[3]; ///< 1/mm
  double Absorption[3];        ///< 1/mm
  double RefractiveIndex;
};

/// The measured presets (marble, skin1, ketchup, wholemilk, ...).
const std::vector<MaterialPreset>& GetMaterialPresets();

/// Look up a preset by (case-insensitive) name; throws translucency::Error
/// listing the known names when there is none.
const MaterialPreset& FindMaterialPreset(const std::string& name);

} // namespace translucency
