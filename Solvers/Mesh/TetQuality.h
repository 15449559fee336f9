/**
 * @file TetQuality.h
 * @brief Shape and size statistics of a tetrahedral mesh: dihedral angles,
 * radius-edge ratios, edge lengths. Used to report and test what a mesher
 * produced (vtkTetrahedralizeSurface, `translucency bench`), whichever
 * mesher it was.
 */
#pragma once

#include <array>
#include <cstddef>
#include <vector>

namespace translucency
{

/// Statistics of a tet mesh's shape and size (lengths in mm, angles in degrees).
struct TetQualityStats
{
  std::size_t NumberOfTets = 0;
  /// Smallest interior dihedral angle over all tets (degrees).
  double MinDihedral = 0.0;
  /// Largest interior dihedral angle over all tets (degrees).
  double MaxDihedral = 0.0;
  /// Number of tets whose smallest dihedral angle lies in [10 k, 10 k + 10)
  /// degrees, k = 0..7 (the last bin also holds 70.53, the regular tet's).
  std::array<std::size_t, 8> MinDihedralHistogram{};
  /// Number of tets whose smallest dihedral angle is below 5 degrees (the
  /// slivers of the mesher criterion in Documentation/Performance.md, "Tetrahedralisers").
  std::size_t TetsBelow5Degrees = 0;
  /// Largest radius-edge ratio (circumradius / shortest edge; 0.612 for the
  /// regular tet; TetGen's -q bound applies to it).
  double MaxRadiusEdge = 0.0;
  /// Mean radius-edge ratio.
  double MeanRadiusEdge = 0.0;
  /// Fraction of tets whose radius-edge ratio exceeds the bound given to
  /// ComputeTetQuality (0 when no bound was given).
  double FractionAboveRadiusEdgeBound = 0.0;
  /// Mean edge length over all tets' edges (an interior edge counts once per tet).
  double MeanEdgeLength = 0.0;
  /// Coefficient of variation (standard deviation / mean) of those edge lengths.
  double EdgeLengthCV = 0.0;
  /// Smallest and largest tet volume (mm^3).
  double MinVolume = 0.0;
  double MaxVolume = 0.0;
};

/**
 * Computes TetQualityStats for tets (4 point ids per tet, 0-based, either
 * orientation) over points (x, y, z per point, mm). A tet with a point id out
 * of range throws translucency::Error naming the tet; a flat tet counts with
 * dihedral angles 0 / 180 and an infinite radius-edge ratio.
 * @param radiusEdgeBound if > 0, FractionAboveRadiusEdgeBound counts the tets
 *        above it (with a relative slack of 1e-9 for rounding).
 * Runs in parallel (OpenMP); the result does not depend on the thread count
 * except for the last bits of the means.
 */
TetQualityStats ComputeTetQuality(const std::vector<double>& points, const std::vector<int>& tets,
  double radiusEdgeBound = 0.0);

} // namespace translucency
