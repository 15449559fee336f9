#include "ExponentialMoments.h"

#include "Error.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace translucency
{

namespace
{

constexpr int MaxNodes = 5;
/// Terms of the series: |h_m(y)| <= C(n+m, m) for |y_i| <= 1, so the term m
/// is at most 1 / (n! m!) of e^c: m = 19 is below 1e-17.
constexpr int SeriesTerms = 20;

/// 1 / k! for k < 25 (the series' denominators (n + m)!, n <= 4, m < 20).
const std::array<double, 25>& InverseFactorials()
{
  static const std::array<double, 25> table = [] {
    std::array<double, 25> t{};
    double f = 1.0;
    for (int k = 0; k < 25; ++k)
    {
      f *= k > 0 ? static_cast<double>(k) : 1.0;
      t[k] = 1.0 / f;
    }
    return t;
  }();
  return table;
}

/// The complete symmetric polynomials h_m of the nodes so far, extended by
/// the node y (h_m^+ = h_m + y h_{m-1}^+); h = {1, 0, ...} for no node.
template <class T>
void AddNode(std::array<T, SeriesTerms>& h, T y)
{
  for (int m = 1; m < SeriesTerms; ++m)
  {
    h[m] += y * h[m - 1];
  }
}

/// sum_m h_m / (n + m)!: exp[x_0..x_n] / e^c for nodes x = c + y.
template <class T>
T SeriesSum(const std::array<T, SeriesTerms>& h, int n)
{
  const std::array<double, 25>& inverse = InverseFactorials();
  T sum = 0.0;
  for (int m = 0; m < SeriesTerms; ++m)
  {
    sum += h[m] * inverse[n + m];
  }
  return sum;
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
    for (int i = 0; i < n; ++i)
    {
      this->Leaf[i] = std::exp(z[i]);
    }
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
      value = this->Leaf[nodes[0]];
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
  /// exp[x] = e^c sum_m h_m(x - c) / (n + m)!, c the mean of the nodes.
  T Series(const int* nodes, int count) const
  {
    T centre = 0.0;
    for (int p = 0; p < count; ++p)
    {
      centre += this->Z[nodes[p]];
    }
    centre /= static_cast<double>(count);
    std::array<T, SeriesTerms> h;
    h.fill(T(0.0));
    h[0] = 1.0;
    for (int p = 0; p < count; ++p)
    {
      AddNode(h, this->Z[nodes[p]] - centre);
    }
    return std::exp(centre) * SeriesSum(h, count - 1);
  }

  const T* Z;
  int N;
  T Leaf[MaxNodes];
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
/// nodes lie within 1 of each other (a tet at most one optical depth across:
/// the usual case): one series about their mean c for all five, exp[z] =
/// e^c sum_m h_m(z - c) / (n + m)!, the complete symmetric polynomials h_m of
/// the four nodes extended by the fifth node z_k (h_m^+ = h_m + y_k h_{m-1}^+).
/// |z_k - c| <= 1 too, so the series' bound (SeriesTerms) holds. One exp per
/// tet instead of 30 (the table of each call, eagerly): the relight of an
/// extended-moments beam spent 63 % of its time here. False: spread > 1.
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
  if (!(spread <= 1.0))
  {
    return false;
  }
  const T centre = 0.25 * (z[0] + z[1] + z[2] + z[3]);
  std::array<T, SeriesTerms> h;
  h.fill(T(0.0));
  h[0] = 1.0;
  for (int p = 0; p < 4; ++p)
  {
    AddNode(h, z[p] - centre);
  }
  const T scale = 6.0 * volume * std::exp(centre);
  total = scale * SeriesSum(h, 3);
  for (int k = 0; k < 4; ++k)
  {
    std::array<T, SeriesTerms> extended = h;
    AddNode(extended, z[k] - centre);
    moment[k] = scale * SeriesSum(extended, 4);
  }
  return true;
}

template <class T>
void ExponentialMoments(const T z[4], double volume, T& total, T moment[4])
{
  if (SharedCentreMoments(z, volume, total, moment))
  {
    return;
  }
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

template double ExponentialDividedDifference<double>(const double*, int);
template std::complex<double> ExponentialDividedDifference<std::complex<double>>(
  const std::complex<double>*, int);
template void ExponentialMoments<double>(const double[4], double, double&, double[4]);
template void ExponentialMoments<std::complex<double>>(
  const std::complex<double>[4], double, std::complex<double>&, std::complex<double>[4]);

} // namespace translucency
