/**
 * @file ModelRange.h
 * @brief Is the diffusion model (and the mesh) in its range for a material?
 *
 * The diffusion approximation of the radiative transfer equation needs
 * scattering to dominate absorption: the transport albedo
 * a' = mu_s' / (mu_a + mu_s') close to 1 (the textbook condition is
 * mu_a << mu_s'; below about 0.9 the fluence near sources and boundaries is
 * off by tens of per cent: Documentation/Solvers.md). The vertex
 * discretisations also need tets no larger than a few transport mean free
 * paths l* = 1 / (mu_a + mu_s'), the scale of the boundary layer where the
 * lit surface's light becomes diffuse, checked for the tets under the
 * surface (inside, the fluence varies on the much longer diffusion length
 * 1/mu_eff, and graded meshes are coarse there on purpose).
 * CheckModelRange() measures the volume outside the albedo range and the
 * surface over too coarse tets, so that vtkSolveDiffusion can
 * warn (a 1 mm skin layer over marble disagreed with Monte Carlo by 2x with
 * no warning: issue 20).
 */
#pragma once

#include <string>
#include <vector>

namespace translucency
{

class TetMesh;
struct OpticalProperties;

/// Transport albedo below which a tet is outside the diffusion model's range.
constexpr double DiffusionMinimumAlbedo = 0.9;
/// Tet size (edge of the regular tet of the same volume) in transport mean
/// free paths above which a tet is too coarse for the boundary layer.
constexpr double DiffusionMaximumTetSizeInMeanFreePaths = 3.0;
/// Fraction of the volume (albedo) or of the surface (tet size) outside a
/// range that triggers the warning.
constexpr double DiffusionToleratedVolumeFraction = 0.01;

/// What CheckModelRange() found (channels 0, 1, 2 = R, G, B).
struct ModelRangeReport
{
  double LowAlbedoVolumeFraction = 0.0; ///< volume fraction with a' < 0.9 in some channel
  double MinimumAlbedo = 1.0;           ///< smallest a' of any tet and channel
  int MinimumAlbedoTet = -1;
  int MinimumAlbedoChannel = 0;
  /// Fraction of the surface area whose tet has size > 3 l* in some channel.
  double CoarseAreaFraction = 0.0;
  /// Largest size / l* of a tet under the surface (any channel).
  double LargestSizeInMeanFreePaths = 0.0;
  int LargestSizeTet = -1;
  int LargestSizeChannel = 0;

  /// The model's range: a sentence when the albedo is below 0.9 on more
  /// than 1 % of the volume (worst tet and channel), else empty.
  std::string AlbedoMessage() const;
  /// The mesh's resolution: a sentence when the tets under more than 1 % of
  /// the surface exceed 3 l* (worst tet and channel), else empty.
  std::string ResolutionMessage() const;
  /// Both, separated by a space (empty when both are).
  std::string Message() const;
};

/// Size of every tet: the edge of the regular tet of the same volume (mm).
std::vector<double> TetSizes(const TetMesh& mesh);

/**
 * Measure the volume outside the model's range. `sizes` are TetSizes(mesh)
 * (pass them to avoid recomputing on every solve; computed when null).
 */
ModelRangeReport CheckModelRange(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<double>* sizes = nullptr);

} // namespace translucency
