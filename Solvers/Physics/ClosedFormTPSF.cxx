#include "ClosedFormTPSF.h"

#include <cmath>

namespace translucency
{
namespace
{
constexpr double Pi = 3.14159265358979323846;
}

double InfiniteMediumFluence(double r, double t, const ClosedFormMedium& medium, double energy)
{
  if (!(t > 0.0))
  {
    return 0.0;
  }
  const double dct = medium.Kappa * medium.Cm * t;
  return energy * medium.Cm * std::pow(4.0 * Pi * dct, -1.5) *
    std::exp(-r * r / (4.0 * dct) - medium.MuA * medium.Cm * t);
}

double SemiInfiniteReflectance(double rho, double t, const ClosedFormMedium& medium, double z0)
{
  if (!(t > 0.0))
  {
    return 0.0;
  }
  const double dct = medium.Kappa * medium.Cm * t;
  return std::pow(4.0 * Pi * medium.Kappa * medium.Cm, -1.5) * z0 * std::pow(t, -2.5) *
    std::exp(-medium.MuA * medium.Cm * t - (rho * rho + z0 * z0) / (4.0 * dct));
}

double SemiInfiniteReflectanceExtrapolated(
  double rho, double t, const ClosedFormMedium& medium, double z0, double zb)
{
  if (!(t > 0.0))
  {
    return 0.0;
  }
  const double dct = medium.Kappa * medium.Cm * t;
  const double z2 = z0 + 2.0 * zb;
  return 0.5 * std::pow(4.0 * Pi * medium.Kappa * medium.Cm, -1.5) * std::pow(t, -2.5) *
    std::exp(-medium.MuA * medium.Cm * t) *
    (z0 * std::exp(-(rho * rho + z0 * z0) / (4.0 * dct)) +
      z2 * std::exp(-(rho * rho + z2 * z2) / (4.0 * dct)));
}

double SemiInfiniteSurfaceFluenceExtrapolated(
  double rho, double t, const ClosedFormMedium& medium, double z0, double zb)
{
  if (!(t > 0.0))
  {
    return 0.0;
  }
  const double dct = medium.Kappa * medium.Cm * t;
  const double z2 = z0 + 2.0 * zb;
  return medium.Cm * std::pow(4.0 * Pi * dct, -1.5) * std::exp(-medium.MuA * medium.Cm * t) *
    (std::exp(-(rho * rho + z0 * z0) / (4.0 * dct)) -
      std::exp(-(rho * rho + z2 * z2) / (4.0 * dct)));
}

double GateAverage(const std::function<double(double)>& f, double t0, double t1, int intervals)
{
  const int n = intervals + intervals % 2;
  const double h = (t1 - t0) / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i)
  {
    const double t = t0 + i * h;
    const double value = t > 0.0 ? f(t) : 0.0;
    sum += (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0)) * value;
  }
  return sum * h / 3.0 / (t1 - t0);
}

double DiscAverage(
  const std::function<double(double)>& f, double rho, double radius, int rings, int sectors)
{
  if (!(radius > 0.0))
  {
    return f(rho);
  }
  double sum = 0.0, weight = 0.0;
  for (int i = 0; i < rings; ++i)
  {
    const double s = radius * (i + 0.5) / rings;
    for (int j = 0; j < sectors; ++j)
    {
      const double angle = 2.0 * Pi * (j + 0.5) / sectors;
      const double x = rho + s * std::cos(angle), y = s * std::sin(angle);
      sum += s * f(std::sqrt(x * x + y * y));
      weight += s;
    }
  }
  return sum / weight;
}

} // namespace translucency
