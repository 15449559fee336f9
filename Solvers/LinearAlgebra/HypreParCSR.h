/**
 * @file HypreParCSR.h
 * @brief What the two distributed linear solvers on hypre's ParCSR matrices
 * share (HypreBoomerAMGPCG, "cg/boomeramg"; SchwarzAggregationPCG,
 * "cg/aggregation"): one rank's whole rows handed to hypre once, new values
 * scattered into the assembled matrix, and hypre's PCG run on them. Internal
 * to the LinearAlgebra layer (hypre's headers stay out of HypreSolver.h).
 */
#pragma once

#include "DistributedPCG.h"

#include <HYPRE.h>
#include <HYPRE_parcsr_ls.h>

#include <mpi.h>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace translucency
{
namespace hypre
{

/// Throws translucency::Error "<who>: <what> failed (hypre error <code>:
/// <hypre's description>)" if `code` is not 0 (and clears hypre's errors).
void Check(HYPRE_Int code, const std::string& who, const char* what);

/**
 * Collective: the IJ matrix (ParCSR) of this rank's rows [rowBegin, rowEnd)
 * as CSR (rowOffsets from 0, global columns, every row whole), with exact
 * diagonal/off-diagonal sizes and one HYPRE_IJMatrixSetValues, assembled.
 * `rows` gets the global row ids. The caller destroys the matrix.
 */
HYPRE_IJMatrix BuildMatrix(MPI_Comm comm, int rowBegin, int rowEnd, const int* rowOffsets,
  const int* columns, const double* values, std::vector<HYPRE_BigInt>& rows,
  const std::string& who);

/**
 * Each entry's place in the assembled ParCSR blocks of `matrix` (rows
 * [rowBegin, rowEnd), CSR as given to BuildMatrix): >= 0 in the diagonal
 * block, -1 - k in the off-diagonal one, into `places`, and the pattern's
 * fingerprint into `pattern`. Throws translucency::Error if an entry is not
 * in the matrix (a changed pattern). ScatterValues calls it when the pattern
 * changed; a solver may call it once after its set-up, so that the first
 * update after the set-up (a paint) does not search.
 */
void FindPlaces(HYPRE_IJMatrix matrix, int rowBegin, int rowEnd, const int* rowOffsets,
  const int* columns, std::vector<int>& places, std::uint64_t& pattern, const std::string& who);

/**
 * New values of the same rows written straight into the assembled ParCSR
 * blocks of `matrix` (rows [rowBegin, rowEnd)): each entry's place (>= 0 in
 * the diagonal block, -1 - k in the off-diagonal one) found once per
 * pattern (`places`, and `pattern` the fingerprint of the pattern they are
 * of), then a scatter. Throws translucency::Error if an entry is not in the
 * matrix (a changed pattern).
 */
void ScatterValues(HYPRE_IJMatrix matrix, int rowBegin, int rowEnd, const int* rowOffsets,
  const int* columns, const double* values, std::vector<int>& places, std::uint64_t& pattern,
  const std::string& who);

/**
 * ScatterValues of the rows `rows` only (numRows row numbers local to this
 * rank, 0 .. rowEnd - rowBegin - 1): their entries of `values` written to
 * the places a ScatterValues of this matrix found (`places`; the pattern is
 * the one they were found for, not fingerprinted again: the caller's
 * contract). Without places (none found yet, or of another size) it is
 * ScatterValues of every row. Throws translucency::Error for a row out of
 * range.
 */
void ScatterRows(HYPRE_IJMatrix matrix, int rowBegin, int rowEnd, const int* rowOffsets,
  const int* columns, const double* values, const int* rows, int numRows,
  std::vector<int>& places, std::uint64_t& pattern, const std::string& who);

/// FNV-1a fingerprint of a CSR pattern (rows + 1 offsets, then the columns).
std::uint64_t PatternFingerprint(int rows, const int* rowOffsets, const int* columns);

/**
 * Collective: hypre's ParCSR PCG `pcg` (set up on `matrix`, `bVector`,
 * `xVector`) from x (`guess`) or zero until ||b - A x|| <= relTol ||b||
 * or maxIter iterations; b and x are this rank's values (rows.size()).
 * Returns the iterations; relRes the final relative residual. Not
 * converging is not an error (the caller reads relRes); any other hypre
 * error throws.
 */
int SolvePCG(HYPRE_Solver pcg, HYPRE_IJMatrix matrix, HYPRE_IJVector bVector,
  HYPRE_IJVector xVector, const std::vector<HYPRE_BigInt>& rows, const double* b, double* x,
  bool guess, double relTol, int maxIter, double& relRes, const std::string& who);

/// One channel's work vectors of SolveChannels (r, z, p, q on the rows of
/// its matrix), kept by the solver between solves; created at the first.
struct ChannelWork
{
  std::array<HYPRE_ParVector, 4> V{ { nullptr, nullptr, nullptr, nullptr } };
  ChannelWork() = default;
  ChannelWork(const ChannelWork&) = delete;
  ChannelWork& operator=(const ChannelWork&) = delete;
  ~ChannelWork() { Destroy(); }
  void Destroy();
};

/// Channel c's preconditioner z = M r on the ParCSR matrix `a` (returns
/// hypre's error code; z need not be cleared by the caller).
using ChannelPreconditioner =
  std::function<HYPRE_Int(int c, HYPRE_ParCSRMatrix a, HYPRE_ParVector r, HYPRE_ParVector z)>;

/**
 * Collective: SolveChannelsPCG (DistributedPCG.h) on the channels with a
 * non-null matrices[c] (each channel's rows the same; work[c] its vectors,
 * made here on first use), the product hypre's (hypre_ParCSRMatrixMatvec)
 * and the preconditioner `precondition`. A hypre error throws
 * translucency::Error naming `who`.
 */
void SolveChannels(MPI_Comm comm, const std::array<HYPRE_IJMatrix, 3>& matrices,
  const std::array<ChannelWork*, 3>& work, const ChannelPreconditioner& precondition,
  const std::array<const double*, 3>& b, const std::array<double*, 3>& x,
  const std::array<bool, 3>& guess, const DistributedSolveControl& control,
  std::array<DistributedChannelStats, 3>& stats, const std::string& who);

/// Destroys whichever of the PCG solver, the matrix and the two vectors
/// exist and sets them to null (the distributed solvers' Free()).
void DestroyPCG(HYPRE_Solver& pcg, HYPRE_IJMatrix& matrix, HYPRE_IJVector& b, HYPRE_IJVector& x);

} // namespace hypre
} // namespace translucency
