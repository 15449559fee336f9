/**
 * @file Threads.h
 * @brief OpenMP threads per rank: the one rule for how many threads each of
 * the ranks sharing a node runs (Documentation/Parallel.md, "Threads per
 * rank"). Pure arithmetic: the MPI side (counting the ranks on a node,
 * agreeing on the user's choice) is Solvers/Parallel/RankThreads.h, which
 * the filters' dispatcher uses too.
 *
 * N ranks on a node that each start OpenMP's default team (one thread per
 * core) run N x cores threads on the cores; OpenMP's spin-wait then burns
 * the CPU the other ranks need (5.7x the CPU time of one thread was
 * measured with 3 ranks x 2 threads on 2 cores).
 */
#pragma once

#include <algorithm>

namespace translucency
{

/**
 * The OpenMP team size for one of `ranksOnNode` ranks sharing the node's
 * `cores`, of which `available` are in this rank's affinity mask (mpiexec
 * may bind a rank to one core): max(1, min(available, cores / ranksOnNode)).
 * 0 (leave OpenMP's own setting) when the user set OMP_NUM_THREADS
 * (`userSet`: an explicit choice wins) or there is one rank on the node.
 */
inline int ThreadsPerRank(int cores, int available, int ranksOnNode, bool userSet)
{
  if (userSet || ranksOnNode <= 1)
  {
    return 0;
  }
  return std::max(1, std::min(available, cores / ranksOnNode));
}

} // namespace translucency
