#include "ToneMap.h"

#include <algorithm>
#include <cmath>

namespace translucency
{

double EncodeSRGB(double linear)
{
  const double v = std::min(1.0, std::max(0.0, linear));
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

double AutomaticExposure(const std::vector<double>& rgb)
{
  const std::size_t n = rgb.size() / 3;
  if (n == 0)
  {
    return 1.0;
  }
  std::vector<double> peaks(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    peaks[i] = std::max({ rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2] });
  }
  const std::size_t k = static_cast<std::size_t>(0.99 * static_cast<double>(n - 1));
  std::nth_element(peaks.begin(), peaks.begin() + static_cast<std::ptrdiff_t>(k), peaks.end());
  const double p99 = peaks[k];
  return p99 > 0.0 && std::isfinite(p99) ? 0.9 / p99 : 1.0;
}

std::vector<unsigned char> ToneMap(const std::vector<double>& rgb, double exposure)
{
  std::vector<unsigned char> bytes(rgb.size());
  for (std::size_t i = 0; i < rgb.size(); ++i)
  {
    bytes[i] = static_cast<unsigned char>(std::lround(255.0 * EncodeSRGB(exposure * rgb[i])));
  }
  return bytes;
}

} // namespace translucency
