/**
 * @file StrokeSurface.h
 * @brief The cutting surface swept by a screen stroke (TransCut, Sec. 5.1).
 *
 * A polyline stroke (world coordinates, mm) and a view direction d sweep a
 * ruled surface: every point of the stroke extended along d. Evaluate(x)
 * projects x along d onto the plane through the first stroke point normal to
 * d, takes the nearest stroke segment in that plane (the first and last
 * segments extended to infinity beyond the stroke's ends, so the surface
 * splits all of space) and returns the signed distance to it: > 0 on the
 * left of the stroke as the viewer looking along d sees it (the side the
 * paper removes), < 0 on the right. Plane axes: u, v with u x v = -d
 * (u to the right, v up on the screen).
 */
#pragma once

#include <array>
#include <vector>

namespace translucency
{

class StrokeSurface
{
public:
  /**
   * Set the stroke (3 coordinates per point, in drawing order) and the view
   * direction (any length > 0). Throws translucency::Error if there are
   * fewer than 2 points, d is zero or not finite, or every segment is
   * parallel to d (the stroke projects to a single point).
   */
  void SetStroke(const std::vector<double>& points, const double viewDirection[3]);

  /// Signed distance (mm) of x to the swept surface, > 0 on the left (removed) side.
  double Evaluate(const double* x) const;

private:
  std::array<double, 3> Origin_{};
  std::array<double, 3> U_{};
  std::array<double, 3> V_{};
  /// Projected stroke, 2 coordinates per point, consecutive duplicates removed.
  std::vector<double> Stroke2D_;
};

} // namespace translucency
