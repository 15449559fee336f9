/**
 * @file TriangleGeometry.h
 * @brief Point-triangle queries shared by the discretisations (boundary
 * nodes of the regular grid, surface nodes of QuadGraph).
 */
#pragma once

#include <Eigen/Core>

#include <cmath>

namespace translucency
{

/**
 * Closest point to p on the triangle (a, b, c), with its barycentric
 * weights (w[0] a + w[1] b + w[2] c, each >= 0, summing to 1). Voronoi-region
 * tests of Ericson, Real-Time Collision Detection, Sec. 5.1.5: exact on the
 * vertices and edges, no division by a zero area for a degenerate triangle
 * unless the point projects inside it.
 */
inline Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
  const Eigen::Vector3d& b, const Eigen::Vector3d& c, double w[3])
{
  const auto weights = [w](double wa, double wb, double wc) {
    w[0] = wa;
    w[1] = wb;
    w[2] = wc;
  };
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0)
  {
    weights(1.0, 0.0, 0.0);
    return a;
  }
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3)
  {
    weights(0.0, 1.0, 0.0);
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0)
  {
    const double t = d1 / (d1 - d3);
    weights(1.0 - t, t, 0.0);
    return a + t * ab;
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6)
  {
    weights(0.0, 0.0, 1.0);
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0)
  {
    const double t = d2 / (d2 - d6);
    weights(1.0 - t, 0.0, t);
    return a + t * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
  {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    weights(0.0, 1.0 - t, t);
    return b + t * (c - b);
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, u = vc * denom;
  weights(1.0 - v - u, v, u);
  return a + ab * v + ac * u;
}

/**
 * An orthonormal frame (t, b, n) about the unit vector n: t is n x (1, 0, 0)
 * or, when n is close to the x axis, n x (0, 1, 0) (up to sign), normalised;
 * b = n x t. Used to turn hemisphere samples about a normal into directions
 * (light occlusion, form factors, Monte Carlo emission).
 */
inline void OrthonormalFrame(const double n[3], double t[3], double b[3])
{
  if (std::abs(n[0]) < 0.9)
  {
    t[0] = 0.0;
    t[1] = -n[2];
    t[2] = n[1];
  }
  else
  {
    t[0] = n[2];
    t[1] = 0.0;
    t[2] = -n[0];
  }
  const double length = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
  for (int d = 0; d < 3; ++d)
  {
    t[d] /= length;
  }
  b[0] = n[1] * t[2] - n[2] * t[1];
  b[1] = n[2] * t[0] - n[0] * t[2];
  b[2] = n[0] * t[1] - n[1] * t[0];
}

} // namespace translucency
