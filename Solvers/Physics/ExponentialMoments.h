/**
 * @file ExponentialMoments.h
 * @brief Exact integrals over a tetrahedron of exp(z . lambda) and of
 * lambda_k exp(z . lambda), lambda the barycentric coordinates, z real or
 * complex: the unscattered beam E_c = exp(ln E_c . lambda) of the extended
 * collimated source (CollimatedSource.cxx) interpolated log-linearly, and
 * its modulation exp(-i k path) in the frequency domain.
 *
 * By the Hermite-Genocchi formula, the integral of f^(n) over the standard
 * n-simplex at sum_i t_i x_i is the divided difference f[x_0, ..., x_n]; for
 * f = exp every derivative is exp, and d/dx_k f[x_0..x_n] = f[x_0..x_n, x_k]
 * (the node repeated). On a tet of volume V (dV = 6 V dt):
 *
 *   int_T exp(z . lambda) dV          = 6 V exp[z_0, z_1, z_2, z_3],
 *   int_T lambda_k exp(z . lambda) dV = 6 V exp[z_0, z_1, z_2, z_3, z_k].
 *
 * The divided differences are evaluated stably (repeated and close nodes
 * included): a set of nodes whose spread (largest pairwise distance) is at
 * most 1 by the series exp[x] = e^c sum_m h_m(x - c) / (n + m)! about their
 * mean c (h_m the complete homogeneous symmetric polynomials; 19 terms give
 * 1/(n! 19!) < 1e-17 relative), a wider set by the recursion
 * f[S] = (f[S \ a] - f[S \ b]) / (z_b - z_a) on its two most distant nodes
 * a, b (|z_b - z_a| > 1, so the difference loses little), the subsets
 * memoised. ExponentialMoments takes its five at once: from one series
 * about the four nodes' mean when they lie within 1 of each other (real
 * nodes: 4, the series' terms then chosen by a bound of its truncation
 * error, at most 32), else for real nodes by the same recursion on the
 * sorted nodes with series leaves up to 4 apart and one table for all five
 * (ExponentialMoments.cxx: RealSeriesTerms, RealRuns).
 * Documentation/DiffuseOptics.md, "The extended source's integrals".
 */
#pragma once

#include <complex>

namespace translucency
{

/**
 * The divided difference exp[z_0, ..., z_{n-1}] of n (1 to 5) nodes, real or
 * complex, repeated nodes allowed.
 */
template <class T>
T ExponentialDividedDifference(const T* z, int n);

/**
 * The exact integrals over a tet of volume `volume` of g = exp(sum_i
 * lambda_i z_i): `total` = int_T g dV and moment[k] = int_T lambda_k g dV
 * (sum_k moment[k] = total).
 */
template <class T>
void ExponentialMoments(const T z[4], double volume, T& total, T moment[4]);

extern template double ExponentialDividedDifference<double>(const double*, int);
extern template std::complex<double> ExponentialDividedDifference<std::complex<double>>(
  const std::complex<double>*, int);
extern template void ExponentialMoments<double>(const double[4], double, double&, double[4]);
extern template void ExponentialMoments<std::complex<double>>(
  const std::complex<double>[4], double, std::complex<double>&, std::complex<double>[4]);

} // namespace translucency
