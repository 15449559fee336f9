/**
 * @file BlockSums.h
 * @brief Sums over rows in fixed blocks whose partial sums are added in
 * block order, so that the result does not depend on the number of threads
 * (internal to the ChannelLinearSolver implementations).
 */
#pragma once

#include <algorithm>
#include <array>
#include <vector>

namespace translucency
{
namespace blocksums
{

/**
 * For each fixed block of `Block` rows of [0, n), f(begin, end) returns K
 * partial sums; the blocks run in parallel on `threads` threads, their sums
 * are added in block order.
 */
template <int K, int Block, typename F>
std::array<double, K> BlockLoop(int n, int threads, F f)
{
  const int numBlocks = (n + Block - 1) / Block;
  std::vector<std::array<double, K>> partial(static_cast<size_t>(numBlocks));
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
  for (int block = 0; block < numBlocks; ++block)
  {
    partial[block] = f(block * Block, std::min(n, (block + 1) * Block));
  }
  std::array<double, K> total{};
  for (const std::array<double, K>& p : partial)
  {
    for (int k = 0; k < K; ++k)
    {
      total[k] += p[k];
    }
  }
  return total;
}

/// Sum of f(i) over [0, n) in fixed blocks of `Block` rows.
template <int Block, typename F>
double BlockedSum(int n, int threads, F f)
{
  return BlockLoop<1, Block>(n, threads,
    [&](int begin, int end)
    {
      double sum = 0.0;
      for (int i = begin; i < end; ++i)
      {
        sum += f(i);
      }
      return std::array<double, 1>{ sum };
    })[0];
}

} // namespace blocksums
} // namespace translucency
