#include "Fresnel.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace translucency
{
namespace Fresnel
{

namespace
{

constexpr int QuadratureOrder = 64;
constexpr double Pi = 3.14159265358979323846;

/// Gauss-Legendre nodes and weights on [0, 1], computed once by Newton's
/// iteration on the Legendre polynomial P_n (Golub-Welsch would do too).
struct GaussLegendre
{
  std::array<double, QuadratureOrder> Nodes;
  std::array<double, QuadratureOrder> Weights;

  GaussLegendre()
  {
    const int n = QuadratureOrder;
    for (int i = 0; i < n; ++i)
    {
      // Initial guess: Chebyshev-like approximation of the i-th root.
      double x = std::cos(Pi * (i + 0.75) / (n + 0.5));
      double dp = 0.0;
      for (int iter = 0; iter < 100; ++iter)
      {
        double p0 = 1.0;
        double p1 = x;
        for (int k = 2; k <= n; ++k)
        {
          const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        // p1 = P_n(x), p0 = P_{n-1}(x)
        dp = n * (x * p1 - p0) / (x * x - 1.0);
        const double dx = p1 / dp;
        x -= dx;
        if (std::abs(dx) < 1e-16)
        {
          break;
        }
      }
      // Map from [-1, 1] to [0, 1].
      Nodes[i] = 0.5 * (x + 1.0);
      Weights[i] = 0.5 * 2.0 / ((1.0 - x * x) * dp * dp);
    }
  }
};

const GaussLegendre& Quadrature()
{
  static const GaussLegendre rule;
  return rule;
}

} // namespace

double DiffuseReflectance(double eta)
{
  // Jensen et al. 2001 fit, used by TransCut, eq. 2.
  return -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
}

double MismatchA(double eta)
{
  const double fdr = DiffuseReflectance(eta);
  return (1.0 + fdr) / (1.0 - fdr); // TransCut eq. 2: A = (1 + Fdr)/(1 - Fdr)
}

double Reflectance(double cosOutside, double eta)
{
  if (eta == 1.0)
  {
    return 0.0; // index matched: no interface
  }
  const double cosI = std::clamp(cosOutside, 0.0, 1.0);
  const double sinI2 = std::max(0.0, 1.0 - cosI * cosI);
  // Snell: sin_t = sin_i / eta (vacuum -> medium): never total reflection
  // for eta >= 1; for eta < 1 a grazing vacuum-side direction can exceed the
  // critical angle, which means total reflection.
  const double sinT2 = sinI2 / (eta * eta);
  if (sinT2 > 1.0)
  {
    return 1.0;
  }
  const double cosT = std::sqrt(1.0 - sinT2);
  const double rs = (cosI - eta * cosT) / (cosI + eta * cosT);
  const double rp = (eta * cosI - cosT) / (eta * cosI + cosT);
  return 0.5 * (rs * rs + rp * rp);
}

double Transmittance(double cosOutside, double eta)
{
  return 1.0 - Reflectance(cosOutside, eta);
}

double UniformTransmittance(double eta)
{
  // (1/pi) int_{H} F_t (n.w) dw = 2 int_0^{pi/2} F_t(theta) cos sin dtheta
  //                             = 2 int_0^1 F_t(mu) mu dmu  (mu = cos theta).
  const GaussLegendre& rule = Quadrature();
  double sum = 0.0;
  for (int i = 0; i < QuadratureOrder; ++i)
  {
    const double mu = rule.Nodes[i];
    sum += rule.Weights[i] * Transmittance(mu, eta) * mu;
  }
  return 2.0 * sum;
}

namespace
{

/// R_phi and R_J (ReflectanceMomentPhi/J), both at once.
std::array<double, 2> ReflectanceMoments(double eta)
{
  const GaussLegendre& rule = Quadrature();
  double phi = 0.0, j = 0.0;
  if (eta >= 1.0)
  {
    // Inside directions with mu < mu_c = sqrt(1 - 1/eta^2) are totally
    // reflected: 2 int_0^mu_c mu dmu = mu_c^2, 3 int_0^mu_c mu^2 dmu = mu_c^3.
    // The rest maps onto the outside cosine c (mu^2 = 1 - (1 - c^2)/eta^2,
    // mu dmu = c dc / eta^2), on which R(c) is smooth.
    const double muC2 = 1.0 - 1.0 / (eta * eta);
    const double muC = std::sqrt(muC2);
    double sumPhi = 0.0, sumJ = 0.0;
    for (int i = 0; i < QuadratureOrder; ++i)
    {
      const double c = rule.Nodes[i];
      const double r = Reflectance(c, eta);
      const double mu = std::sqrt(1.0 - (1.0 - c * c) / (eta * eta));
      sumPhi += rule.Weights[i] * r * c;
      sumJ += rule.Weights[i] * r * c * mu;
    }
    phi = muC2 + 2.0 * sumPhi / (eta * eta);
    j = muC2 * muC + 3.0 * sumJ / (eta * eta);
  }
  else
  {
    // No total internal reflection: every inside direction leaves, towards
    // the outside cosine c = sqrt(1 - eta^2 (1 - mu^2)).
    for (int i = 0; i < QuadratureOrder; ++i)
    {
      const double mu = rule.Nodes[i];
      const double r = Reflectance(std::sqrt(1.0 - eta * eta * (1.0 - mu * mu)), eta);
      phi += 2.0 * rule.Weights[i] * r * mu;
      j += 3.0 * rule.Weights[i] * r * mu * mu;
    }
  }
  return { phi, j };
}

} // namespace

double ReflectanceMomentPhi(double eta)
{
  return ReflectanceMoments(eta)[0];
}

double ReflectanceMomentJ(double eta)
{
  return ReflectanceMoments(eta)[1];
}

std::array<double, 7> ReflectanceHalfRangeMoments(double eta)
{
  const GaussLegendre& rule = Quadrature();
  std::array<double, 7> r{};
  if (eta == 1.0)
  {
    return r; // index matched: R = 0
  }
  if (eta > 1.0)
  {
    // Totally reflected below mu_c = sqrt(1 - 1/eta^2): int_0^mu_c mu^m dmu
    // = mu_c^(m+1) / (m+1); the rest on the outside cosine c as in
    // ReflectanceMoments (mu dmu = c dc / eta^2, R(c) smooth).
    const double muC = std::sqrt(1.0 - 1.0 / (eta * eta));
    double power = muC;
    for (int m = 0; m < 7; ++m)
    {
      r[m] = power / (m + 1);
      power *= muC;
    }
    for (int i = 0; i < QuadratureOrder; ++i)
    {
      const double c = rule.Nodes[i];
      const double mu = std::sqrt(1.0 - (1.0 - c * c) / (eta * eta));
      double term = rule.Weights[i] * Reflectance(c, eta) * c / (eta * eta * mu); // mu^(m-1), m = 0
      for (int m = 0; m < 7; ++m)
      {
        r[m] += term;
        term *= mu;
      }
    }
    return r;
  }
  // eta < 1: no total internal reflection, R smooth in mu.
  for (int i = 0; i < QuadratureOrder; ++i)
  {
    const double mu = rule.Nodes[i];
    double term = rule.Weights[i] * Reflectance(std::sqrt(1.0 - eta * eta * (1.0 - mu * mu)), eta);
    for (int m = 0; m < 7; ++m)
    {
      r[m] += term;
      term *= mu;
    }
  }
  return r;
}

RobinCoefficients BoundaryCoefficients(double eta, BoundaryRule rule)
{
  RobinCoefficients out;
  if (rule == BoundaryRule::Fit)
  {
    out.Fdr = DiffuseReflectance(eta);
    out.A = MismatchA(eta);
    return out;
  }
  // The assemblers ask per boundary point or triangle, almost always with
  // one eta, or its neighbours in the last bits: a boundary point's eta is
  // the area-weighted mean over its triangles (BoundaryPointRefractiveIndexAt),
  // whose rounding gives a few distinct values where every tet has 1.3. Keep
  // the last few per thread (a memo of exact values: the result does not
  // depend on what a thread asked before). With one entry, the 1M-tet bunny's
  // relight recomputed the moments at most of its 54,686 boundary points (3 %
  // of a relight's samples in `perf`, session 30).
  constexpr int Kept = 8;
  thread_local double etas[Kept] = { -1.0, -1.0, -1.0, -1.0, -1.0, -1.0, -1.0, -1.0 };
  thread_local RobinCoefficients kept[Kept];
  thread_local int next = 0;
  for (int i = 0; i < Kept; ++i)
  {
    if (etas[i] == eta)
    {
      return kept[i];
    }
  }
  const std::array<double, 2> moments = ReflectanceMoments(eta);
  RobinCoefficients& slot = kept[next];
  slot.Fdr = moments[0];
  slot.A = (1.0 + moments[1]) / (1.0 - moments[0]);
  etas[next] = eta;
  next = (next + 1) % Kept;
  return slot;
}

} // namespace Fresnel
} // namespace translucency
