#include "SpatialOrder.h"

#include <algorithm>
#include <numeric>
#include <utility>

namespace translucency
{

MortonEncoder::MortonEncoder(const double* xyz, std::size_t count)
{
  if (count == 0)
  {
    return;
  }
  double lo[3] = { xyz[0], xyz[1], xyz[2] };
  double hi[3] = { xyz[0], xyz[1], xyz[2] };
  for (std::size_t i = 1; i < count; ++i)
  {
    for (int d = 0; d < 3; ++d)
    {
      lo[d] = std::min(lo[d], xyz[3 * i + d]);
      hi[d] = std::max(hi[d], xyz[3 * i + d]);
    }
  }
  const double extent = std::max({ hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2] });
  for (int d = 0; d < 3; ++d)
  {
    Origin_[d] = lo[d];
  }
  Scale_ = extent > 0.0 ? MaxCell / extent : 0.0;
}

std::vector<int> SortByCode(const std::vector<std::uint64_t>& codes)
{
  const int n = static_cast<int>(codes.size());
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  if (std::is_sorted(codes.begin(), codes.end()))
  {
    return order;
  }
  std::vector<std::pair<std::uint64_t, int>> keyed(n);
#pragma omp parallel for schedule(static)
  for (int k = 0; k < n; ++k)
  {
    keyed[k] = { codes[k], k };
  }
  std::sort(keyed.begin(), keyed.end());
#pragma omp parallel for schedule(static)
  for (int k = 0; k < n; ++k)
  {
    order[k] = keyed[k].second;
  }
  return order;
}

std::vector<int> MortonOrder(const double* xyz, std::size_t count)
{
  const MortonEncoder encode(xyz, count);
  std::vector<std::uint64_t> codes(count);
  for (std::size_t i = 0; i < count; ++i)
  {
    codes[i] = encode(xyz + 3 * i);
  }
  return SortByCode(codes);
}

} // namespace translucency
