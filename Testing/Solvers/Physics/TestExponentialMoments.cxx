// The exact integrals of the extended collimated source (ExponentialMoments.h)
// against independent values: closed forms (equal nodes, two nodes), the
// explicit formula on well-separated nodes, the matrix exponential of the
// Opitz bidiagonal matrix (Eigen's MatrixFunctions: a second method, repeated
// and close nodes included), and a Gauss product quadrature over a tet.

#include "ExponentialMoments.h"

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <iostream>
#include <random>
#include <vector>

namespace
{

using translucency::ExponentialDividedDifference;
using translucency::ExponentialMoments;
using Complex = std::complex<double>;

/// exp[z_0..z_{n-1}] as the top-right entry of exp(Z), Z bidiagonal with the
/// nodes on the diagonal and ones above it (Opitz).
template <class T>
T OpitzDividedDifference(const std::vector<T>& z)
{
  const int n = static_cast<int>(z.size());
  Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> m =
    Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>::Zero(n, n);
  for (int i = 0; i < n; ++i)
  {
    m(i, i) = z[i];
    if (i + 1 < n)
    {
      m(i, i + 1) = T(1.0);
    }
  }
  const Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> e = m.exp();
  return e(0, n - 1);
}

TEST(ExponentialMoments, EqualNodesGiveTheTaylorCoefficient)
{
  // exp[c, ..., c] (n nodes) = e^c / (n - 1)!.
  const double factorial[6] = { 1, 1, 2, 6, 24, 120 };
  for (double c : { -30.0, -1.0, 0.0, 0.7, 12.0 })
  {
    for (int n = 1; n <= 5; ++n)
    {
      std::vector<double> z(n, c);
      EXPECT_NEAR(ExponentialDividedDifference(z.data(), n) / (std::exp(c) / factorial[n - 1]),
        1.0, 1e-14)
        << "c " << c << " n " << n;
    }
  }
  // And the integrals of a constant E_c: V e^c, and V e^c / 4 per vertex.
  const double z[4] = { 0.3, 0.3, 0.3, 0.3 };
  double total = 0.0, moment[4];
  ExponentialMoments(z, 2.5, total, moment);
  EXPECT_NEAR(total, 2.5 * std::exp(0.3), 1e-14);
  for (double m : moment)
  {
    EXPECT_NEAR(m, 2.5 * std::exp(0.3) / 4.0, 1e-14);
  }
}

TEST(ExponentialMoments, TwoNodesAndARepeatedNode)
{
  // exp[a, b] = (e^b - e^a) / (b - a); exp[0, 0, 1] = e - 2.
  for (double d : { 1e-9, 1e-4, 0.3, 0.99, 1.01, 7.0, 40.0 })
  {
    const double z[2] = { -0.5, -0.5 + d };
    const double expected = std::exp(-0.5) * std::expm1(d) / d;
    EXPECT_NEAR(ExponentialDividedDifference(z, 2) / expected, 1.0, 1e-13) << d;
  }
  const double z[3] = { 0.0, 0.0, 1.0 };
  EXPECT_NEAR(ExponentialDividedDifference(z, 3), std::exp(1.0) - 2.0, 1e-14);
}

template <class T>
T ExplicitDividedDifference(const std::vector<T>& z)
{
  // sum_i e^{z_i} / prod_{j != i} (z_i - z_j): accurate for separated nodes.
  T sum = 0.0;
  for (size_t i = 0; i < z.size(); ++i)
  {
    T denominator = 1.0;
    for (size_t j = 0; j < z.size(); ++j)
    {
      if (j != i)
      {
        denominator *= z[i] - z[j];
      }
    }
    sum += std::exp(z[i]) / denominator;
  }
  return sum;
}

TEST(ExponentialMoments, SeparatedNodesMatchTheExplicitFormula)
{
  // Nodes at least 0.25 apart (spreads 0.75 to 12: series and recursion).
  const std::vector<std::vector<double>> cases = { { 0.0, 0.25, 0.5, 0.75 },
    { -3.0, -1.0, 0.5, 4.0 }, { 2.0, -2.0, 1.0, -10.0, 0.4 }, { -12.0, 0.0, -6.0, -3.0 } };
  for (const std::vector<double>& z : cases)
  {
    const double expected = ExplicitDividedDifference(z);
    EXPECT_NEAR(ExponentialDividedDifference(z.data(), static_cast<int>(z.size())) / expected,
      1.0, 1e-12);
  }
  const std::vector<Complex> complexCase = { { 0.0, 0.0 }, { -1.0, -0.8 }, { -2.5, -2.0 },
    { -0.5, -3.0 } };
  const Complex expected = ExplicitDividedDifference(complexCase);
  EXPECT_LT(std::abs(ExponentialDividedDifference(complexCase.data(), 4) - expected),
    1e-12 * std::abs(expected));
}

TEST(ExponentialMoments, MatchTheOpitzMatrixExponentialOnRandomNodes)
{
  // Random nodes at spreads from 1e-8 to 30, with repeated nodes (the 5-node
  // sets of the moments repeat one), real and complex.
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  double worstReal = 0.0, worstComplex = 0.0;
  for (int trial = 0; trial < 600; ++trial)
  {
    const double spread = std::pow(10.0, -8.0 + 9.5 * (trial % 100) / 99.0); // 1e-8 .. 30
    const int n = 4 + trial % 2;
    std::vector<double> z(n);
    std::vector<Complex> w(n);
    for (int i = 0; i < n; ++i)
    {
      z[i] = -2.0 + spread * unit(random);
      w[i] = Complex(z[i], spread * unit(random));
    }
    if (n == 5)
    {
      z[4] = z[trial % 4];
      w[4] = w[trial % 4];
    }
    const double expected = OpitzDividedDifference(z);
    worstReal = std::max(worstReal,
      std::abs(ExponentialDividedDifference(z.data(), n) - expected) / std::abs(expected));
    const Complex expectedComplex = OpitzDividedDifference(w);
    worstComplex = std::max(worstComplex,
      std::abs(ExponentialDividedDifference(w.data(), n) - expectedComplex) /
        std::abs(expectedComplex));
  }
  EXPECT_LT(worstReal, 1e-11);
  EXPECT_LT(worstComplex, 1e-10);
}

/// int_T lambda_k exp(z . lambda) dV by a Gauss product rule on the cube
/// mapped onto the tet (Duffy): t1 = u, t2 = (1 - u) v, t3 = (1 - u)(1 - v) w.
template <class T>
void GaussMoments(const T z[4], double volume, T& total, T moment[4])
{
  // 24-point Gauss-Legendre on [0, 1] by Golub-Welsch on Legendre's Jacobi matrix.
  const int n = 24;
  Eigen::MatrixXd jacobi = Eigen::MatrixXd::Zero(n, n);
  for (int i = 1; i < n; ++i)
  {
    jacobi(i, i - 1) = jacobi(i - 1, i) = i / std::sqrt(4.0 * i * i - 1.0);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(jacobi);
  std::vector<double> x(n), weight(n);
  for (int i = 0; i < n; ++i)
  {
    x[i] = 0.5 * (eig.eigenvalues()[i] + 1.0);
    weight[i] = eig.eigenvectors()(0, i) * eig.eigenvectors()(0, i); // sums to 1
  }
  total = 0.0;
  for (int k = 0; k < 4; ++k)
  {
    moment[k] = 0.0;
  }
  for (int a = 0; a < n; ++a)
  {
    for (int b = 0; b < n; ++b)
    {
      for (int c = 0; c < n; ++c)
      {
        const double u = x[a], v = x[b], w = x[c];
        const double l[4] = { 1.0 - u - (1.0 - u) * v - (1.0 - u) * (1.0 - v) * w, u,
          (1.0 - u) * v, (1.0 - u) * (1.0 - v) * w };
        // dt = (1 - u)^2 (1 - v) du dv dw on the reference tet of volume 1/6.
        const double jac = (1.0 - u) * (1.0 - u) * (1.0 - v) * weight[a] * weight[b] * weight[c];
        const T g = std::exp(z[0] * l[0] + z[1] * l[1] + z[2] * l[2] + z[3] * l[3]);
        total += 6.0 * volume * jac * g;
        for (int k = 0; k < 4; ++k)
        {
          moment[k] += 6.0 * volume * jac * g * l[k];
        }
      }
    }
  }
}

TEST(ExponentialMoments, MatchAGaussQuadratureOverATet)
{
  // E_c falling 0 to 6 e-folds across a tet (the quadrature levels 0 to 4 of
  // the collimated source), and a frequency-domain phase.
  for (double range : { 0.1, 0.9, 2.5, 6.0 })
  {
    const double z[4] = { 0.0, -0.3 * range, -range, -0.6 * range };
    double total = 0.0, moment[4], gTotal = 0.0, gMoment[4];
    ExponentialMoments(z, 0.8, total, moment);
    GaussMoments(z, 0.8, gTotal, gMoment);
    EXPECT_NEAR(total / gTotal, 1.0, 1e-12) << range;
    double sum = 0.0;
    for (int k = 0; k < 4; ++k)
    {
      EXPECT_NEAR(moment[k] / gMoment[k], 1.0, 1e-12) << range << " vertex " << k;
      sum += moment[k];
    }
    EXPECT_NEAR(sum / total, 1.0, 1e-14); // sum_k lambda_k = 1
  }
  const Complex w[4] = { { 0.0, 0.0 }, { -1.0, -1.5 }, { -2.0, -0.5 }, { -0.5, -2.5 } };
  Complex total, moment[4], gTotal, gMoment[4];
  ExponentialMoments(w, 1.3, total, moment);
  GaussMoments(w, 1.3, gTotal, gMoment);
  EXPECT_LT(std::abs(total - gTotal), 1e-12 * std::abs(gTotal));
  for (int k = 0; k < 4; ++k)
  {
    EXPECT_LT(std::abs(moment[k] - gMoment[k]), 1e-12 * std::abs(gMoment[k])) << k;
  }
}

TEST(ExponentialMoments, WideRealTetsTakeTheSeriesAndMatchTheRecursion)
{
  // Real tets 1 to 4 e-folds across (the wide series with up to 32 terms,
  // ExponentialMoments.cxx) and just beyond (the recursion), with two and
  // three equal nodes (a flat-lit face), against the recursion's five divided
  // differences (ExponentialDividedDifference, Hermite-Genocchi) and the
  // Opitz matrix exponential.
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worstRecursion = 0.0, worstOpitz = 0.0;
  for (int trial = 0; trial < 2000; ++trial)
  {
    const double spread = 1.0 + 3.2 * (trial % 200) / 199.0; // 1 .. 4.2
    double z[4] = { 0.0, -spread, -spread * unit(random), -spread * unit(random) };
    if (trial % 5 == 0)
    {
      z[3] = z[2]; // two equal nodes
    }
    if (trial % 7 == 0)
    {
      z[2] = z[3] = z[1]; // three
    }
    const double base = -40.0 + 80.0 * unit(random);
    for (double& x : z)
    {
      x += base;
    }
    const double volume = 0.25 + unit(random);
    double total = 0.0, moment[4];
    ExponentialMoments(z, volume, total, moment);
    double nodes[5] = { z[0], z[1], z[2], z[3], 0.0 };
    const double expectedTotal = 6.0 * volume * ExponentialDividedDifference(nodes, 4);
    worstRecursion = std::max(worstRecursion, std::abs(total / expectedTotal - 1.0));
    const std::vector<double> four(z, z + 4);
    worstOpitz = std::max(worstOpitz,
      std::abs(total / (6.0 * volume * std::exp(base) * OpitzDividedDifference(
                         std::vector<double>{ z[0] - base, z[1] - base, z[2] - base, z[3] - base })) -
        1.0));
    for (int k = 0; k < 4; ++k)
    {
      nodes[4] = z[k];
      const double expected = 6.0 * volume * ExponentialDividedDifference(nodes, 5);
      worstRecursion = std::max(worstRecursion, std::abs(moment[k] / expected - 1.0));
      std::vector<double> five(four);
      five.push_back(z[k]);
      for (double& x : five)
      {
        x -= base;
      }
      worstOpitz = std::max(worstOpitz,
        std::abs(moment[k] / (6.0 * volume * std::exp(base) * OpitzDividedDifference(five)) - 1.0));
    }
  }
  std::cout << "wide real tets: worst relative difference to the recursion " << worstRecursion
            << ", to the Opitz matrix exponential " << worstOpitz << "\n";
  EXPECT_LT(worstRecursion, 1e-12);
  EXPECT_LT(worstOpitz, 1e-11); // Opitz's own accuracy (the random-node test above)
}

TEST(ExponentialMoments, ABrightVertexDoesNotOverflow)
{
  // exp[z] = e^s exp[z - s]: nodes near 705 (e^705 is finite, e^712 is not).
  const double z[4] = { 705.0, 703.0, 700.0, 704.5 };
  const double shifted[4] = { 0.0, -2.0, -5.0, -0.5 };
  const double value = ExponentialDividedDifference(z, 4);
  EXPECT_TRUE(std::isfinite(value));
  EXPECT_NEAR(value / (std::exp(705.0) * ExponentialDividedDifference(shifted, 4)), 1.0, 1e-14);
}

} // namespace
