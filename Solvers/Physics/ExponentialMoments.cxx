#include "ExponentialMoments.h"

#include "Error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>

namespace translucency
{

namespace
{

constexpr int MaxNodes = 5;
/// Terms of the series: |h_m(y)| <= C(n+m, m) for |y_i| <= 1, so the term m
/// is at most 1 / (n! m!) of e^c: m = 19 is below 1e-17.
constexpr int SeriesTerms = 20;
/// The most terms of a series (the wide real sets' series, RealSeriesTerms:
/// 32 at r = 3).
constexpr int MaxSeriesTerms = 36;
/// Size of the table of 1 / k!: the denominators (n + m)!, n <= 4, m < MaxSeriesTerms.
constexpr int MaxFactorial = MaxSeriesTerms + 5;

/// 1 / k! for k < MaxFactorial.
const std::array<double, MaxFactorial>& InverseFactorials()
{
  static const std::array<double, MaxFactorial> table = [] {
    std::array<double, MaxFactorial> t{};
    double f = 1.0;
    for (int k = 0; k < MaxFactorial; ++k)
    {
      f *= k > 0 ? static_cast<double>(k) : 1.0;
      t[k] = 1.0 / f;
    }
    return t;
  }();
  return table;
}

/// The largest spread (largest |z_q - z_p|) of real nodes that a series
/// takes (SharedCentreMoments, and the recursion's leaves); wider sets are
/// split by the recursion. At spread s, n nodes lie within r <= (n - 1) s / n
/// of their mean: r <= 3 for a tet's four, 3.2 for five (the bounds below).
constexpr double RealSeriesSpread = 4.0;

/**
 * The number of terms M of a series about a centre c for real nodes within
 * r of c (RealSeriesTerms reads it from a table): the smallest M with
 * e^{r/5} r^M / M! / (1 - r / (M + 1)) <= 1e-17; SeriesTerms (20) for r <= 1
 * (the rule of the complex and the narrow real sets). Why this bounds the
 * relative truncation error (n + 1 nodes, n <= 4): |h_m(y)| <= C(n + m, m)
 * r^m, so the terms m >= M sum to at most (1 / n!) sum_{m >= M} r^m / m! <=
 * (1 / n!) r^M / M! / (1 - r / (M + 1)); and for real nodes the divided
 * difference is the mean of exp over the simplex (Hermite-Genocchi) divided
 * by n!, which by Jensen is at least exp(mean of the nodes) / n!: 1 / n!
 * about the nodes' own mean (the recursion's leaves, the four nodes of
 * SharedCentreMoments) and e^{y_k / 5} / n! >= e^{-r/5} / n! for its five
 * with z_k repeated about the four's mean. The same bounds give the
 * rounding: the terms' magnitudes sum to at most e^r / n!, so the
 * recurrences lose at most about 5 (r + 1) e^{6 r / 5} ulps (r = 3: 9e-14
 * relative; about the own mean, r = 3.2: 5 (r + 1) e^r ulps, 6e-14).
 */
int TermsForRadius(double r)
{
  const double scale = std::exp(0.2 * r);
  double term = 1.0; // r^m / m!
  for (int m = 1; m < MaxSeriesTerms; ++m)
  {
    term *= r / static_cast<double>(m);
    if (static_cast<double>(m + 1) > r && scale * term / (1.0 - r / (m + 1)) <= 1e-17)
    {
      return m;
    }
  }
  return MaxSeriesTerms;
}

/// Radii per step of RealSeriesTerms' table (the bound at the step's upper end).
constexpr int RadiusSteps = 8;

int RealSeriesTerms(double r)
{
  if (r <= 1.0)
  {
    return SeriesTerms;
  }
  // The bound is increasing in r: a table of its terms at the upper ends of
  // steps of 1/8 up to r = 3.25 (the widest the series take: 3.2).
  static const std::array<int, 9 * RadiusSteps / 4 + 2> table = [] {
    std::array<int, 9 * RadiusSteps / 4 + 2> t{};
    for (int i = 0; i < static_cast<int>(t.size()); ++i)
    {
      t[i] = TermsForRadius(1.0 + static_cast<double>(i) / RadiusSteps);
    }
    return t;
  }();
  // Step i covers (1 + (i - 1) / 8, 1 + i / 8]; rounding only moves r up a step.
  const int step = static_cast<int>((r - 1.0) * RadiusSteps) + 1;
  return step < static_cast<int>(table.size()) ? table[step] : TermsForRadius(r);
}

/// The divided differences of exp on the subsets of one set of nodes,
/// memoised by bit mask.
template <class T>
class DividedDifferences
{
public:
  DividedDifferences(const T* z, int n)
    : Z(z)
    , N(n)
  {
  }

  T Of(unsigned mask)
  {
    if (this->Known[mask])
    {
      return this->Value[mask];
    }
    int nodes[MaxNodes], count = 0;
    for (int i = 0; i < this->N; ++i)
    {
      if (mask & (1u << i))
      {
        nodes[count++] = i;
      }
    }
    T value;
    if (count == 1)
    {
      value = std::exp(this->Z[nodes[0]]);
    }
    else
    {
      // The two most distant nodes of the subset.
      int a = nodes[0], b = nodes[1];
      double spread = -1.0;
      for (int p = 0; p < count; ++p)
      {
        for (int q = p + 1; q < count; ++q)
        {
          const double d = std::abs(this->Z[nodes[q]] - this->Z[nodes[p]]);
          if (d > spread)
          {
            spread = d;
            a = nodes[p];
            b = nodes[q];
          }
        }
      }
      value = spread <= 1.0
        ? Series(nodes, count)
        : (this->Of(mask & ~(1u << a)) - this->Of(mask & ~(1u << b))) / (this->Z[b] - this->Z[a]);
    }
    this->Known[mask] = true;
    this->Value[mask] = value;
    return value;
  }

private:
  /// exp[x] = e^c sum_m h_m(x - c) / (n + m)!, c the mean of the nodes
  /// (spread <= 1: SeriesTerms terms).
  T Series(const int* nodes, int count) const
  {
    T centre = 0.0;
    for (int p = 0; p < count; ++p)
    {
      centre += this->Z[nodes[p]];
    }
    centre /= static_cast<double>(count);
    std::array<T, MaxSeriesTerms> h;
    h.fill(T(0.0));
    h[0] = 1.0;
    for (int p = 0; p < count; ++p)
    {
      const T y = this->Z[nodes[p]] - centre;
      for (int m = 1; m < SeriesTerms; ++m)
      {
        h[m] += y * h[m - 1];
      }
    }
    const std::array<double, MaxFactorial>& inverse = InverseFactorials();
    T sum = 0.0;
    for (int m = 0; m < SeriesTerms; ++m)
    {
      sum += h[m] * inverse[count - 1 + m];
    }
    return std::exp(centre) * sum;
  }

  const T* Z;
  int N;
  T Value[1u << MaxNodes];
  bool Known[1u << MaxNodes] = {};
};

} // namespace

template <class T>
T ExponentialDividedDifference(const T* z, int n)
{
  if (n < 1 || n > MaxNodes)
  {
    throw Error("ExponentialDividedDifference: 1 to 5 nodes");
  }
  // exp[z] = e^s exp[z - s]: shifted by the largest real part, every
  // exponential evaluated is at most 1 (no overflow on a bright vertex).
  double shift = std::real(z[0]);
  for (int i = 1; i < n; ++i)
  {
    shift = std::max(shift, static_cast<double>(std::real(z[i])));
  }
  T shifted[MaxNodes];
  for (int i = 0; i < n; ++i)
  {
    shifted[i] = z[i] - shift;
  }
  DividedDifferences<T> table(shifted, n);
  return std::exp(shift) * table.Of((1u << n) - 1u);
}

/// The five divided differences of ExponentialMoments at once when the four
/// nodes lie close together: one series about their mean c for all five,
/// exp[z] = e^c sum_m h_m(z - c) / (n + m)!, the complete symmetric
/// polynomials h_m of the four nodes extended by the fifth node z_k
/// (h_m^+ = h_m + y_k h_{m-1}^+, the four extensions side by side). Complex
/// nodes within 1 of each other (spread <= 1: |z_k - c| <= 1 too, so the
/// series' bound, SeriesTerms, holds); real nodes up to RealSeriesSpread
/// apart, with the terms of RealSeriesTerms (Jensen bounds the real divided
/// differences from below; a complex one can be small by cancellation, so
/// the complex rule stays at 1). One exp per tet instead of 30 and more (the
/// recursion's table of each call): the relight of an extended-moments beam
/// spent most of its time in the recursion (Documentation/DiffuseOptics.md,
/// "What the default costs in a relight"). False: too wide.
template <class T>
bool SharedCentreMoments(const T z[4], double volume, T& total, T moment[4])
{
  double spread = 0.0;
  for (int p = 0; p < 4; ++p)
  {
    for (int q = p + 1; q < 4; ++q)
    {
      spread = std::max(spread, static_cast<double>(std::abs(z[q] - z[p])));
    }
  }
  constexpr bool real = std::is_same<T, double>::value;
  if (!(spread <= (real ? RealSeriesSpread : 1.0)))
  {
    return false;
  }
  const T centre = 0.25 * (z[0] + z[1] + z[2] + z[3]);
  T y[4];
  double radius = 0.0;
  for (int p = 0; p < 4; ++p)
  {
    y[p] = z[p] - centre;
    radius = std::max(radius, static_cast<double>(std::abs(y[p])));
  }
  const int terms = real ? RealSeriesTerms(radius) : SeriesTerms;
  const std::array<double, MaxFactorial>& inverse = InverseFactorials();
  // One pass over m: h_m of the nodes added one by one (h_m^+ = h_m +
  // y h_{m-1}^+ for y_0, y_1, y_2, y_3 in turn, each stage fed by the one
  // before at the same m), the four extensions by y_k and the five sums.
  // Every recurrence runs on its own value of the previous m, so the stages
  // overlap in the pipeline instead of running one after the other.
  T stage[4] = { T(1.0), T(1.0), T(1.0), T(1.0) }; // h_0 after each node
  T extended[4], sums[4];
  for (int k = 0; k < 4; ++k)
  {
    extended[k] = T(1.0);
    sums[k] = inverse[4];
  }
  T sum = inverse[3];
  for (int m = 1; m < terms; ++m)
  {
    stage[0] = y[0] * stage[0]; // h_m of {y_0} (h_m before any node is 0 for m > 0)
    stage[1] = stage[0] + y[1] * stage[1];
    stage[2] = stage[1] + y[2] * stage[2];
    stage[3] = stage[2] + y[3] * stage[3];
    const T h = stage[3];
    for (int k = 0; k < 4; ++k)
    {
      extended[k] = h + y[k] * extended[k];
      sums[k] += extended[k] * inverse[4 + m];
    }
    sum += h * inverse[3 + m];
  }
  const T scale = 6.0 * volume * std::exp(centre);
  total = scale * sum;
  for (int k = 0; k < 4; ++k)
  {
    moment[k] = scale * sums[k];
  }
  return true;
}

/// exp[x] over `count` real nodes (count <= 5) by the series about their
/// mean with RealSeriesTerms (the recursion's leaves; spread <= RealSeriesSpread).
double RealSeries(const double* x, int count)
{
  double centre = 0.0;
  for (int p = 0; p < count; ++p)
  {
    centre += x[p];
  }
  centre /= static_cast<double>(count);
  double radius = 0.0;
  for (int p = 0; p < count; ++p)
  {
    radius = std::max(radius, std::abs(x[p] - centre));
  }
  const int terms = RealSeriesTerms(radius);
  // h_m of the nodes added one by one, all stages in one pass over m (as
  // SharedCentreMoments: the recurrences overlap instead of waiting on
  // memory).
  double y[MaxNodes], stage[MaxNodes];
  for (int p = 0; p < count; ++p)
  {
    y[p] = x[p] - centre;
    stage[p] = 1.0;
  }
  const std::array<double, MaxFactorial>& inverse = InverseFactorials();
  double sum = inverse[count - 1];
  for (int m = 1; m < terms; ++m)
  {
    double previous = 0.0; // h_m before any node (m > 0)
    for (int p = 0; p < count; ++p)
    {
      stage[p] = previous + y[p] * stage[p];
      previous = stage[p];
    }
    sum += previous * inverse[count - 1 + m];
  }
  return std::exp(centre) * sum;
}

/**
 * The five divided differences of ExponentialMoments for real nodes more
 * than RealSeriesSpread apart: the recursion of ExponentialDividedDifference
 * specialised to real nodes. Sorted (x_0 >= x_1 >= x_2 >= x_3, shifted so
 * that x_0 = 0), the two most distant nodes of every set the recursion
 * meets are its first and last, and the sets are the runs x_i..x_j, alone
 * (D(i, j)) or with one node k of the run repeated (K(k, i, j)):
 *   D(i, j) = (D(i, j - 1) - D(i + 1, j)) / (x_i - x_j),
 *   K(k, i, j) = (K or D without one x_j - K or D without one x_i) / (x_i - x_j),
 * each a series (RealSeries) once its spread is at most RealSeriesSpread;
 * one table for all five (the moments share the total's runs).
 */
class RealRuns
{
public:
  explicit RealRuns(const double z[4])
  {
    for (int k = 0; k < 4; ++k)
    {
      this->Order[k] = k;
    }
    std::sort(this->Order, this->Order + 4, [z](int a, int b) { return z[a] > z[b]; });
    this->Shift = z[this->Order[0]];
    for (int k = 0; k < 4; ++k)
    {
      this->X[k] = z[this->Order[k]] - this->Shift;
    }
  }

  /// exp[z_0..z_3] and exp[z_0..z_3, z_k] (k in the caller's order), each / e^Shift.
  double Total() { return this->Run(0, 3); }
  double Moment(int k)
  {
    int sorted = 0;
    while (this->Order[sorted] != k)
    {
      ++sorted;
    }
    return this->Repeated(sorted, 0, 3);
  }
  double Shift = 0.0;

private:
  double Run(int i, int j)
  {
    double& value = this->RunValue[i][j];
    if (!this->RunKnown[i][j])
    {
      this->RunKnown[i][j] = true;
      const double spread = this->X[i] - this->X[j];
      value = i == j     ? std::exp(this->X[i])
        : spread <= RealSeriesSpread ? RealSeries(this->X + i, j - i + 1)
                         : (this->Run(i, j - 1) - this->Run(i + 1, j)) / spread;
    }
    return value;
  }

  double Repeated(int k, int i, int j)
  {
    double& value = this->RepeatedValue[k][i][j];
    if (!this->RepeatedKnown[k][i][j])
    {
      this->RepeatedKnown[k][i][j] = true;
      const double spread = this->X[i] - this->X[j];
      if (i == j)
      {
        value = std::exp(this->X[k]); // exp[x_k, x_k] = exp'(x_k)
      }
      else if (spread <= RealSeriesSpread)
      {
        double nodes[5];
        for (int p = i; p <= j; ++p)
        {
          nodes[p - i] = this->X[p];
        }
        nodes[j - i + 1] = this->X[k];
        value = RealSeries(nodes, j - i + 2);
      }
      else
      {
        const double withoutLast = k == j ? this->Run(i, j) : this->Repeated(k, i, j - 1);
        const double withoutFirst = k == i ? this->Run(i, j) : this->Repeated(k, i + 1, j);
        value = (withoutLast - withoutFirst) / spread;
      }
    }
    return value;
  }

  int Order[4];
  double X[4];
  double RunValue[4][4];
  bool RunKnown[4][4] = {};
  double RepeatedValue[4][4][4];
  bool RepeatedKnown[4][4][4] = {};
};

template <class T>
void WideMoments(const T z[4], double volume, T& total, T moment[4])
{
  // Hermite-Genocchi: int_T exp(z . lambda) dV = 6 V exp[z_0..z_3] and
  // int_T lambda_k exp(z . lambda) dV = 6 V exp[z_0..z_3, z_k].
  T nodes[5] = { z[0], z[1], z[2], z[3], T(0.0) };
  total = 6.0 * volume * ExponentialDividedDifference(nodes, 4);
  for (int k = 0; k < 4; ++k)
  {
    nodes[4] = z[k];
    moment[k] = 6.0 * volume * ExponentialDividedDifference(nodes, 5);
  }
}

template <>
void WideMoments<double>(const double z[4], double volume, double& total, double moment[4])
{
  RealRuns runs(z);
  const double scale = 6.0 * volume * std::exp(runs.Shift);
  total = scale * runs.Total();
  for (int k = 0; k < 4; ++k)
  {
    moment[k] = scale * runs.Moment(k);
  }
}

template <class T>
void ExponentialMoments(const T z[4], double volume, T& total, T moment[4])
{
  if (SharedCentreMoments(z, volume, total, moment))
  {
    return;
  }
  WideMoments(z, volume, total, moment);
}

template double ExponentialDividedDifference<double>(const double*, int);
template std::complex<double> ExponentialDividedDifference<std::complex<double>>(
  const std::complex<double>*, int);
template void ExponentialMoments<double>(const double[4], double, double&, double[4]);
template void ExponentialMoments<std::complex<double>>(
  const std::complex<double>[4], double, std::complex<double>&, std::complex<double>[4]);

} // namespace translucency
