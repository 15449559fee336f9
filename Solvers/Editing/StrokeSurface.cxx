#include "StrokeSurface.h"

#include "Error.h"

#include <cmath>
#include <limits>
#include <string>

namespace translucency
{

void StrokeSurface::SetStroke(const std::vector<double>& points, const double viewDirection[3])
{
  const std::size_t n = points.size() / 3;
  if (points.size() % 3 != 0 || n < 2)
  {
    throw Error("stroke has " + std::to_string(n) + " point(s): at least 2 are required");
  }
  const double len = std::sqrt(viewDirection[0] * viewDirection[0] +
    viewDirection[1] * viewDirection[1] + viewDirection[2] * viewDirection[2]);
  if (!(len > 0.0) || !std::isfinite(len))
  {
    throw Error("view direction (" + std::to_string(viewDirection[0]) + ", " +
      std::to_string(viewDirection[1]) + ", " + std::to_string(viewDirection[2]) +
      ") is zero or not finite");
  }
  const double d[3] = { viewDirection[0] / len, viewDirection[1] / len, viewDirection[2] / len };
  // v: the world axis least aligned with d, made orthogonal to d; u = d x v
  // so that u x v = -d.
  int axis = 0;
  for (int k = 1; k < 3; ++k)
  {
    if (std::abs(d[k]) < std::abs(d[axis]))
    {
      axis = k;
    }
  }
  double v[3] = { 0.0, 0.0, 0.0 };
  v[axis] = 1.0;
  const double dv = v[0] * d[0] + v[1] * d[1] + v[2] * d[2];
  for (int k = 0; k < 3; ++k)
  {
    v[k] -= dv * d[k];
  }
  const double vl = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  for (int k = 0; k < 3; ++k)
  {
    V_[k] = v[k] / vl;
  }
  U_ = { d[1] * V_[2] - d[2] * V_[1], d[2] * V_[0] - d[0] * V_[2],
    d[0] * V_[1] - d[1] * V_[0] };
  Origin_ = { points[0], points[1], points[2] };

  Stroke2D_.clear();
  double scale = 0.0;
  for (std::size_t i = 0; i < n; ++i)
  {
    const double* p = &points[3 * i];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
    {
      throw Error("stroke point " + std::to_string(i) + " is not finite");
    }
    double r[3] = { p[0] - Origin_[0], p[1] - Origin_[1], p[2] - Origin_[2] };
    const double a = r[0] * U_[0] + r[1] * U_[1] + r[2] * U_[2];
    const double b = r[0] * V_[0] + r[1] * V_[1] + r[2] * V_[2];
    scale = std::max(scale, std::max(std::abs(a), std::abs(b)));
    Stroke2D_.push_back(a);
    Stroke2D_.push_back(b);
  }
  // Drop consecutive points that coincide on the screen.
  const double tol = 1e-12 * std::max(scale, 1e-300);
  std::vector<double> kept = { Stroke2D_[0], Stroke2D_[1] };
  for (std::size_t i = 1; i < n; ++i)
  {
    const double a = Stroke2D_[2 * i], b = Stroke2D_[2 * i + 1];
    if (std::hypot(a - kept[kept.size() - 2], b - kept.back()) > tol)
    {
      kept.push_back(a);
      kept.push_back(b);
    }
  }
  if (kept.size() < 4)
  {
    throw Error("stroke projects to a single point along the view direction: draw it across "
                "the screen, not along the view direction");
  }
  Stroke2D_.swap(kept);
}

double StrokeSurface::Evaluate(const double* x) const
{
  const double r[3] = { x[0] - Origin_[0], x[1] - Origin_[1], x[2] - Origin_[2] };
  const double qx = r[0] * U_[0] + r[1] * U_[1] + r[2] * U_[2];
  const double qy = r[0] * V_[0] + r[1] * V_[1] + r[2] * V_[2];
  const std::size_t segments = Stroke2D_.size() / 2 - 1;
  double best = std::numeric_limits<double>::infinity();
  double side = 0.0;
  for (std::size_t s = 0; s < segments; ++s)
  {
    const double ax = Stroke2D_[2 * s], ay = Stroke2D_[2 * s + 1];
    const double ex = Stroke2D_[2 * s + 2] - ax, ey = Stroke2D_[2 * s + 3] - ay;
    const double wx = qx - ax, wy = qy - ay;
    double t = (wx * ex + wy * ey) / (ex * ex + ey * ey);
    // The end segments extend to infinity beyond the stroke's ends.
    if (t < 0.0 && s != 0)
    {
      t = 0.0;
    }
    if (t > 1.0 && s + 1 != segments)
    {
      t = 1.0;
    }
    const double dx = wx - t * ex, dy = wy - t * ey;
    const double dist = std::hypot(dx, dy);
    if (dist < best)
    {
      best = dist;
      // Left of the segment direction: positive 2D cross product.
      side = ex * wy - ey * wx;
    }
  }
  return side > 0.0 ? best : -best;
}

} // namespace translucency
