/**
 * @file HypreMPI.h
 * @brief The file formats between `translucency bench --linear-solvers` and
 * translucency-hypre-mpi, the small MPI program that times hypre BoomerAMG-PCG
 * on several ranks (`mpiexec -n 2 translucency-hypre-mpi IN OUT`).
 *
 * IN (native byte order): "TRHYIN01", int32 n, int64 nnz, int32 runs,
 * int32 maxIter, double coldTol, double warmTol, int32 rowOffsets[n + 1],
 * int32 columns[nnz], double values[3][nnz], double coldRhs[3][n],
 * double warmRhs[3][n].
 *
 * OUT: "TRHYOUT1", int32 n, int32 ranks, double setupMs, coldMs, warmMs
 * (medians over the runs of the 3-channel set-up, cold solve from zero and
 * warm solve from the cold solution; each the slowest rank's time), then per
 * channel int32 coldIterations, int32 warmIterations, double coldResidual,
 * double warmResidual, double spmvEquivalentsPerIteration, then
 * double coldSolution[3][n], double warmSolution[3][n].
 */
#pragma once

namespace translucency_app
{
constexpr char HypreInputMagic[9] = "TRHYIN01";
constexpr char HypreOutputMagic[9] = "TRHYOUT1";
}
