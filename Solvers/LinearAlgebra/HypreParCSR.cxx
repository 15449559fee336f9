#include "HypreParCSR.h"

#include "Error.h"

#include <_hypre_parcsr_ls.h>

#include <limits>
#include <sstream>

namespace translucency
{
namespace hypre
{

void Check(HYPRE_Int code, const std::string& who, const char* what)
{
  if (code != 0)
  {
    char message[256] = { 0 };
    HYPRE_DescribeError(code, message);
    HYPRE_ClearAllErrors();
    std::ostringstream os;
    os << who << ": " << what << " failed (hypre error " << code << ": " << message << ")";
    throw Error(os.str());
  }
}

HYPRE_IJMatrix BuildMatrix(MPI_Comm comm, int rowBegin, int rowEnd, const int* rowOffsets,
  const int* columns, const double* values, std::vector<HYPRE_BigInt>& rowIds,
  const std::string& who)
{
  const int rows = rowEnd - rowBegin;
  HYPRE_IJMatrix a = nullptr;
  // hypre's ranges are inclusive; an empty local block is [begin, begin - 1].
  Check(HYPRE_IJMatrixCreate(comm, rowBegin, rowEnd - 1, rowBegin, rowEnd - 1, &a), who,
    "matrix creation");
  try
  {
    Check(HYPRE_IJMatrixSetObjectType(a, HYPRE_PARCSR), who, "matrix type");
    std::vector<HYPRE_Int> diag(rows, 0), offd(rows, 0), sizes(rows);
    rowIds.resize(rows);
    for (int i = 0; i < rows; ++i)
    {
      rowIds[i] = rowBegin + i;
      sizes[i] = rowOffsets[i + 1] - rowOffsets[i];
      for (int k = rowOffsets[i]; k < rowOffsets[i + 1]; ++k)
      {
        (columns[k] >= rowBegin && columns[k] < rowEnd ? diag[i] : offd[i])++;
      }
    }
    Check(HYPRE_IJMatrixSetDiagOffdSizes(a, diag.data(), offd.data()), who, "matrix sizes");
    Check(HYPRE_IJMatrixInitialize(a), who, "matrix initialisation");
    const std::size_t nnz = rows > 0 ? static_cast<std::size_t>(rowOffsets[rows]) : 0;
    if (rows > 0)
    {
      std::vector<HYPRE_BigInt> cols(columns, columns + nnz);
      Check(HYPRE_IJMatrixSetValues(a, rows, sizes.data(), rowIds.data(), cols.data(), values),
        who, "setting the matrix values");
    }
    Check(HYPRE_IJMatrixAssemble(a), who, "matrix assembly");
  }
  catch (...)
  {
    HYPRE_IJMatrixDestroy(a);
    throw;
  }
  return a;
}

std::uint64_t PatternFingerprint(int rows, const int* rowOffsets, const int* columns)
{
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](int v) { h = (h ^ static_cast<std::uint32_t>(v)) * 1099511628211ull; };
  for (int r = 0; r <= rows; ++r)
    mix(rowOffsets[r]);
  for (int k = 0; k < rowOffsets[rows]; ++k)
    mix(columns[k]);
  return h;
}

/// Entry value into the ParCSR data at `place` (FindPlaces: >= 0 the diag
/// block's index, else -1 - the offd block's).
inline void WriteAtPlace(int place, double value, HYPRE_Complex* diagData, HYPRE_Complex* offdData)
{
  if (place >= 0)
    diagData[place] = value;
  else
    offdData[-1 - place] = value;
}

void FindPlaces(HYPRE_IJMatrix matrix, int rowBegin, int rowEnd, const int* rowOffsets,
  const int* columns, std::vector<int>& places, std::uint64_t& pattern, const std::string& who)
{
  const int rows = rowEnd - rowBegin;
  hypre_ParCSRMatrix* a = nullptr;
  HYPRE_IJMatrixGetObject(matrix, reinterpret_cast<void**>(&a));
  hypre_CSRMatrix* diag = hypre_ParCSRMatrixDiag(a);
  hypre_CSRMatrix* offd = hypre_ParCSRMatrixOffd(a);
  const std::size_t nnz = static_cast<std::size_t>(rowOffsets[rows]);
  const std::uint64_t fingerprint = PatternFingerprint(rows, rowOffsets, columns);
  places.clear();
  const HYPRE_Int* di = hypre_CSRMatrixI(diag);
  const HYPRE_Int* dj = hypre_CSRMatrixJ(diag);
  const HYPRE_Int* oi = hypre_CSRMatrixI(offd);
  const HYPRE_Int* oj = hypre_CSRMatrixJ(offd);
  const HYPRE_BigInt* colMap = hypre_ParCSRMatrixColMapOffd(a);
  const HYPRE_BigInt firstColumn = hypre_ParCSRMatrixFirstColDiag(a);
  const HYPRE_BigInt lastColumn = firstColumn + hypre_CSRMatrixNumCols(diag) - 1;
  std::vector<int> found(nnz);
  for (int r = 0; r < rows; ++r)
  {
    // hypre keeps a row's entries in the order they were set, the
    // diagonal moved first: with sorted columns each entry is where the
    // previous one's successor is (the diagonal at the row's start), so
    // a hint is tried before the row's search (issue 32: the search of
    // every entry was quadratic in the row length).
    HYPRE_Int diagHint = di[r] + 1, offdHint = oi ? oi[r] : 0;
    for (int k = rowOffsets[r]; k < rowOffsets[r + 1]; ++k)
    {
      const HYPRE_BigInt column = columns[k];
      int place = std::numeric_limits<int>::min();
      if (column >= firstColumn && column <= lastColumn)
      {
        const HYPRE_Int local = static_cast<HYPRE_Int>(column - firstColumn);
        if (di[r] < di[r + 1] && dj[di[r]] == local)
          place = di[r];
        else if (diagHint < di[r + 1] && dj[diagHint] == local)
          place = diagHint++;
        else
        {
          for (HYPRE_Int q = di[r]; q < di[r + 1]; ++q)
            if (dj[q] == local)
            {
              place = q;
              diagHint = q + 1;
              break;
            }
        }
      }
      else if (oi && colMap)
      {
        if (offdHint < oi[r + 1] && colMap[oj[offdHint]] == column)
          place = -1 - static_cast<int>(offdHint++);
        else
        {
          for (HYPRE_Int q = oi[r]; q < oi[r + 1]; ++q)
            if (colMap[oj[q]] == column)
            {
              place = -1 - static_cast<int>(q);
              offdHint = q + 1;
              break;
            }
        }
      }
      if (place == std::numeric_limits<int>::min())
      {
        throw Error(who + ": UpdateValues(): entry (" + std::to_string(rowBegin + r) + ", " +
          std::to_string(column) + ") is not in the matrix of the last Setup() (a changed pattern)");
      }
      found[k] = place;
    }
  }
  places = std::move(found);
  pattern = fingerprint;
}

void ScatterValues(HYPRE_IJMatrix matrix, int rowBegin, int rowEnd, const int* rowOffsets,
  const int* columns, const double* values, std::vector<int>& places, std::uint64_t& pattern,
  const std::string& who)
{
  const int rows = rowEnd - rowBegin;
  hypre_ParCSRMatrix* a = nullptr;
  HYPRE_IJMatrixGetObject(matrix, reinterpret_cast<void**>(&a));
  hypre_CSRMatrix* diag = hypre_ParCSRMatrixDiag(a);
  hypre_CSRMatrix* offd = hypre_ParCSRMatrixOffd(a);
  const std::size_t nnz = static_cast<std::size_t>(rowOffsets[rows]);
  // A changed pattern finds its places again (or is refused), without a copy.
  if (places.size() != nnz || PatternFingerprint(rows, rowOffsets, columns) != pattern)
    FindPlaces(matrix, rowBegin, rowEnd, rowOffsets, columns, places, pattern, who);
  HYPRE_Complex* diagData = hypre_CSRMatrixData(diag);
  HYPRE_Complex* offdData = hypre_CSRMatrixData(offd);
  for (std::size_t k = 0; k < nnz; ++k)
    WriteAtPlace(places[k], values[k], diagData, offdData);
}

void ScatterRows(HYPRE_IJMatrix matrix, int rowBegin, int rowEnd, const int* rowOffsets,
  const int* columns, const double* values, const int* rows, int numRows,
  std::vector<int>& places, std::uint64_t& pattern, const std::string& who)
{
  const int numLocal = rowEnd - rowBegin;
  if (places.size() != static_cast<std::size_t>(rowOffsets[numLocal]))
  {
    // No places yet (the first update after a Setup): found for every row.
    ScatterValues(matrix, rowBegin, rowEnd, rowOffsets, columns, values, places, pattern, who);
    return;
  }
  hypre_ParCSRMatrix* a = nullptr;
  HYPRE_IJMatrixGetObject(matrix, reinterpret_cast<void**>(&a));
  HYPRE_Complex* diagData = hypre_CSRMatrixData(hypre_ParCSRMatrixDiag(a));
  HYPRE_Complex* offdData = hypre_CSRMatrixData(hypre_ParCSRMatrixOffd(a));
  for (int n = 0; n < numRows; ++n)
  {
    const int r = rows[n];
    if (r < 0 || r >= numLocal)
    {
      throw Error(who + ": UpdateRows(): row " + std::to_string(r) + " is not one of this rank's " +
        std::to_string(numLocal) + " rows");
    }
    for (int k = rowOffsets[r]; k < rowOffsets[r + 1]; ++k)
      WriteAtPlace(places[static_cast<std::size_t>(k)], values[k], diagData, offdData);
  }
}

int SolvePCG(HYPRE_Solver pcg, HYPRE_IJMatrix matrix, HYPRE_IJVector bVector,
  HYPRE_IJVector xVector, const std::vector<HYPRE_BigInt>& rowIds, const double* bLocal,
  double* xLocal, bool guess, double relTol, int maxIter, double& relRes, const std::string& who)
{
  const int rows = static_cast<int>(rowIds.size());
  std::vector<double> zero;
  if (!guess)
    zero.assign(rows, 0.0);
  Check(HYPRE_IJVectorSetValues(bVector, rows, rowIds.data(), bLocal), who,
    "setting the right-hand side");
  Check(HYPRE_IJVectorSetValues(xVector, rows, rowIds.data(), guess ? xLocal : zero.data()), who,
    "setting the initial guess");
  HYPRE_ParCSRMatrix a;
  HYPRE_ParVector b, x;
  HYPRE_IJMatrixGetObject(matrix, reinterpret_cast<void**>(&a));
  HYPRE_IJVectorGetObject(bVector, reinterpret_cast<void**>(&b));
  HYPRE_IJVectorGetObject(xVector, reinterpret_cast<void**>(&x));
  HYPRE_PCGSetTol(pcg, relTol);
  HYPRE_PCGSetMaxIter(pcg, maxIter);
  const HYPRE_Int code = HYPRE_ParCSRPCGSolve(pcg, a, b, x);
  // Not converging within maxIter is reported as an error code by hypre: it
  // is not an error here (the caller reads the residual).
  if (code != 0 && !HYPRE_CheckError(code, HYPRE_ERROR_CONV))
  {
    Check(code, who, "PCG solve");
  }
  HYPRE_ClearAllErrors();
  HYPRE_Int iterations = 0;
  HYPRE_Real residual = 0.0;
  HYPRE_ParCSRPCGGetNumIterations(pcg, &iterations);
  HYPRE_ParCSRPCGGetFinalRelativeResidualNorm(pcg, &residual);
  Check(HYPRE_IJVectorGetValues(xVector, rows, rowIds.data(), xLocal), who, "reading the solution");
  relRes = residual;
  return iterations;
}

void ChannelWork::Destroy()
{
  for (HYPRE_ParVector& v : V)
  {
    if (v)
      hypre_ParVectorDestroy(reinterpret_cast<hypre_ParVector*>(v));
    v = nullptr;
  }
}

void SolveChannels(MPI_Comm comm, const std::array<HYPRE_IJMatrix, 3>& matrices,
  const std::array<ChannelWork*, 3>& work, const ChannelPreconditioner& precondition,
  const std::array<const double*, 3>& b, const std::array<double*, 3>& x,
  const std::array<bool, 3>& guess, const DistributedSolveControl& control,
  std::array<DistributedChannelStats, 3>& stats, const std::string& who)
{
  // A hypre error left by an earlier call would be returned by every later
  // one (hypre's error flag is sticky).
  HYPRE_ClearAllErrors();
  std::array<DistributedPCGChannel, 3> channels;
  std::array<DistributedPCGChannel*, 3> solved{};
  int rows = 0;
  for (int c = 0; c < 3; ++c)
  {
    if (!matrices[c])
      continue;
    hypre_ParCSRMatrix* a = nullptr;
    HYPRE_IJMatrixGetObject(matrices[c], reinterpret_cast<void**>(&a));
    rows = hypre_CSRMatrixNumRows(hypre_ParCSRMatrixDiag(a));
    ChannelWork& w = *work[c];
    if (!w.V[0] || hypre_VectorSize(hypre_ParVectorLocalVector(
                     reinterpret_cast<hypre_ParVector*>(w.V[0]))) != rows)
    {
      w.Destroy();
      for (HYPRE_ParVector& v : w.V)
      {
        hypre_ParVector* pv = hypre_ParVectorCreate(hypre_ParCSRMatrixComm(a),
          hypre_ParCSRMatrixGlobalNumRows(a), hypre_ParCSRMatrixRowStarts(a));
        hypre_ParVectorInitialize(pv);
        v = reinterpret_cast<HYPRE_ParVector>(pv);
      }
    }
    auto data = [&w](int k) {
      return hypre_VectorData(hypre_ParVectorLocalVector(reinterpret_cast<hypre_ParVector*>(w.V[k])));
    };
    DistributedPCGChannel& ch = channels[c];
    ch.R = data(0);
    ch.Z = data(1);
    ch.P = data(2);
    ch.Q = data(3);
    auto* r = reinterpret_cast<hypre_ParVector*>(w.V[0]);
    auto* z = reinterpret_cast<hypre_ParVector*>(w.V[1]);
    auto* p = reinterpret_cast<hypre_ParVector*>(w.V[2]);
    auto* q = reinterpret_cast<hypre_ParVector*>(w.V[3]);
    ch.Multiply = [a, p, q, &who]() {
      Check(hypre_ParCSRMatrixMatvec(1.0, a, p, 0.0, q), who, "the matrix product");
    };
    ch.Precondition = [c, a, r, z, &precondition, &who]() {
      // As hypre's PCG: z cleared, then one application (a V-cycle).
      hypre_ParVectorSetConstantValues(z, 0.0);
      const HYPRE_Int code = precondition(c, reinterpret_cast<HYPRE_ParCSRMatrix>(a),
        reinterpret_cast<HYPRE_ParVector>(r), reinterpret_cast<HYPRE_ParVector>(z));
      // hypre's PCG ignores the preconditioner's code; a convergence flag
      // (a V-cycle is not iterated to a tolerance) is no error here either.
      if (code != 0 && !HYPRE_CheckError(code, HYPRE_ERROR_CONV))
        Check(code, who, "the preconditioner");
      HYPRE_ClearAllErrors();
    };
    solved[c] = &ch;
  }
  SolveChannelsPCG(comm, rows, solved, b, x, guess, control, stats);
}

void DestroyPCG(HYPRE_Solver& pcg, HYPRE_IJMatrix& matrix, HYPRE_IJVector& b, HYPRE_IJVector& x)
{
  if (pcg)
    HYPRE_ParCSRPCGDestroy(pcg);
  if (matrix)
    HYPRE_IJMatrixDestroy(matrix);
  if (b)
    HYPRE_IJVectorDestroy(b);
  if (x)
    HYPRE_IJVectorDestroy(x);
  pcg = nullptr;
  matrix = nullptr;
  b = nullptr;
  x = nullptr;
}

} // namespace hypre
} // namespace translucency
