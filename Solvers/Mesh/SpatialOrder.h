/**
 * @file SpatialOrder.h
 * @brief Morton (Z-order) codes and orders: the one spatial ordering of the
 * project (cache-friendly point and tet orders of TetMesh, the assembly's
 * fallback schedule, QuadGraph's coarse groups).
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace translucency
{

/// Bits per axis of the Morton codes (3 x 21 = 63 bits).
constexpr int MortonBits = 21;

/// The low 21 bits of v spread so that two zero bits separate each bit.
inline std::uint64_t SpreadBits(std::uint64_t v)
{
  std::uint64_t x = v & 0x1fffffULL;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

/**
 * Quantises coordinates in the bounding cube of a point set to 21-bit Morton
 * codes. One cube (the largest extent) for the three axes keeps the curve
 * isotropic; points outside the cube are clamped to it.
 */
class MortonEncoder
{
public:
  /// The cube of the first `count` points of `xyz` (3 doubles each, mm).
  MortonEncoder(const double* xyz, std::size_t count);
  /// The cube of every point of `xyz` (3 doubles each, mm).
  explicit MortonEncoder(const std::vector<double>& xyz)
    : MortonEncoder(xyz.data(), xyz.size() / 3)
  {
  }

  /// The code of the point x (3 doubles).
  std::uint64_t operator()(const double* x) const
  {
    std::uint64_t code = 0;
    for (int d = 0; d < 3; ++d)
    {
      double q = (x[d] - Origin_[d]) * Scale_;
      q = q < 0.0 ? 0.0 : (q > MaxCell ? MaxCell : q);
      code |= SpreadBits(static_cast<std::uint64_t>(q)) << d;
    }
    return code;
  }

private:
  static constexpr double MaxCell = static_cast<double>((1u << MortonBits) - 1);
  double Origin_[3] = { 0.0, 0.0, 0.0 };
  double Scale_ = 0.0;
};

/// Indices 0..n-1 sorted by code, ties by index (a deterministic total order).
std::vector<int> SortByCode(const std::vector<std::uint64_t>& codes);

/// The first `count` points of `xyz` (3 doubles each) in Morton order of
/// their own bounding cube (ties by index).
std::vector<int> MortonOrder(const double* xyz, std::size_t count);

} // namespace translucency
