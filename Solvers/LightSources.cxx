#include "LightSources.h"

#include "Fresnel.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace translucency
{

bool DirectIrradiance(const LightSource& light, const double x[3], const double n[3], double eta,
  double q[3], double toLight[3], double& distance)
{
  double scale = 1.0;
  if (light.Type == LightSource::Kind::Directional)
  {
    const double len = std::sqrt(light.Direction[0] * light.Direction[0] +
      light.Direction[1] * light.Direction[1] + light.Direction[2] * light.Direction[2]);
    for (int k = 0; k < 3; ++k)
    {
      toLight[k] = -light.Direction[k] / len;
    }
    distance = std::numeric_limits<double>::infinity();
  }
  else
  {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k)
    {
      toLight[k] = light.Position[k] - x[k];
      d2 += toLight[k] * toLight[k];
    }
    distance = std::sqrt(d2);
    for (int k = 0; k < 3; ++k)
    {
      toLight[k] /= distance;
    }
    scale = 1.0 / d2; // inverse-square fall-off of a point source
  }
  const double cosIn = n[0] * toLight[0] + n[1] * toLight[1] + n[2] * toLight[2];
  if (cosIn <= 0.0)
  {
    q[0] = q[1] = q[2] = 0.0;
    return false;
  }
  // q = L_i (n . w_i) F_t(w_i) integrated over a delta distribution of directions.
  const double transmitted = cosIn * Fresnel::Transmittance(cosIn, eta) * scale;
  for (int c = 0; c < 3; ++c)
  {
    q[c] = light.Power[c] * transmitted;
  }
  return true;
}

double HemisphereDirection(const double n[3], int k, int count, double rotation, double w[3])
{
  // Orthonormal frame (t, b, n).
  double t[3];
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
  const double tl = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
  for (double& v : t)
  {
    v /= tl;
  }
  const double b[3] = { n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2],
    n[0] * t[1] - n[1] * t[0] };
  // Cosine-weighted: r = sqrt(u) on the unit disk, lifted to the hemisphere.
  const double golden = 2.399963229728653; // pi (3 - sqrt 5)
  const double u = (k + 0.5) / count;
  const double r = std::sqrt(u);
  const double phi = golden * k + 2.0 * 3.141592653589793 * rotation;
  const double cosTheta = std::sqrt(std::max(0.0, 1.0 - u));
  const double a = r * std::cos(phi), c = r * std::sin(phi);
  for (int d = 0; d < 3; ++d)
  {
    w[d] = a * t[d] + c * b[d] + cosTheta * n[d];
  }
  return cosTheta;
}

} // namespace translucency
