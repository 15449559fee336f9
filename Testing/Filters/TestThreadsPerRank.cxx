// OpenMP threads per rank (Solvers/Common/Threads.h, the rule of the filters'
// dispatcher and the distributed solver): the
// team each rank runs is cores / ranks on the node, never more than the rank
// may use, never zero, and an explicit OMP_NUM_THREADS is left alone.
#include "Threads.h"

#include <gtest/gtest.h>

using translucency::ThreadsPerRank;

TEST(ThreadsPerRank, SplitsTheCoresOverTheRanksOnTheNode)
{
  EXPECT_EQ(ThreadsPerRank(2, 2, 2, false), 1);
  EXPECT_EQ(ThreadsPerRank(64, 64, 4, false), 16);
  EXPECT_EQ(ThreadsPerRank(64, 64, 3, false), 21); // the remainder idles: no rank runs more
}

TEST(ThreadsPerRank, NeverZeroWhenRanksOutnumberTheCores)
{
  // 3 ranks on 2 cores (mpiexec --oversubscribe): one thread each, not 0.
  EXPECT_EQ(ThreadsPerRank(2, 2, 3, false), 1);
}

TEST(ThreadsPerRank, NeverMoreThanTheRankIsBoundTo)
{
  // mpiexec bound the rank to one core of 8 with 2 ranks on the node.
  EXPECT_EQ(ThreadsPerRank(8, 1, 2, false), 1);
  EXPECT_EQ(ThreadsPerRank(16, 4, 2, false), 4);
}

TEST(ThreadsPerRank, LeavesOpenMPAloneForOneRankOrAnExplicitSetting)
{
  EXPECT_EQ(ThreadsPerRank(8, 8, 1, false), 0);
  EXPECT_EQ(ThreadsPerRank(8, 8, 4, true), 0);
}
