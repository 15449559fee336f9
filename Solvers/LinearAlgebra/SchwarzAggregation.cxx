#include "SchwarzAggregation.h"

#include "AggregationMultigrid.h"
#include "DiffusionSystem.h"
#include "Error.h"
#include "HypreParCSR.h"
#include "HypreSolver.h"

#include <HYPRE.h>
#include <HYPRE_parcsr_ls.h>
#include <_hypre_parcsr_ls.h>

#include <Eigen/SparseCholesky>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace translucency
{

namespace
{

using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
using ColMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

/// Loops shorter than this run on one thread (as AggregationMultigrid's).
constexpr long long SchwarzThreshold = 8192;

const char* const Who = "cg/aggregation";

void SchwarzCheck(HYPRE_Int code, const char* what)
{
  hypre::Check(code, Who, what);
}

} // namespace

struct SchwarzAggregationPCG::Handles
{
  HYPRE_IJMatrix A = nullptr;
  HYPRE_IJVector B = nullptr, X = nullptr;
  HYPRE_Solver PCG = nullptr;
  std::vector<HYPRE_BigInt> Rows;
  std::uint64_t Pattern = 0; ///< fingerprint of the rows given to Setup
  /// SolveChannels' vectors r, z, p, q (made at its first call).
  hypre::ChannelWork Work;
};

/// The values of the owned block's hierarchy (the structure is
/// Structure_'s) and the single-channel cycle: AggregationMultigrid's cycle
/// (smoother degree 1, i.e. l1-Jacobi with weight 1 / theta, theta = 0.6)
/// on one channel, single-precision values and vectors, double sums.
struct SchwarzAggregationPCG::Block
{
  struct Level
  {
    const CsrPattern* Pattern = nullptr;
    const int* Aggregate = nullptr;
    const int* MemberOffsets = nullptr;
    const int* Members = nullptr;
    std::vector<double> Values; ///< double values (level 0: the block's)
    std::vector<float> Single;  ///< single-precision values
    std::vector<float> InverseL1;
    mutable std::vector<float> B, X, Y, R, Saved, Sum;
  };
  std::vector<Level> Levels;
  Eigen::SimplicialLDLT<ColMatrix> Coarsest;
  std::size_t CoarsestNonZeros = 0;
  int Threads = 1;
  double Theta = 0.6; ///< centre of the Chebyshev interval [0.2, 1] (serial default)
  double Scale = 1.4;
  int CycleIndex = 2;

  /// out = b - A x (b == nullptr: A x), single-precision values.
  template <typename TB>
  void Residual(const Level& lev, const TB* b, const float* x, float* out) const
  {
    const int n = lev.Pattern->Size;
    const int* ro = lev.Pattern->Offsets.data();
    const int* ci = lev.Pattern->Columns.data();
    const float* v = lev.Single.data();
#pragma omp parallel for num_threads(Threads) schedule(static) if(n > SchwarzThreshold)
    for (int i = 0; i < n; ++i)
    {
      double ax = 0.0;
      for (int k = ro[i]; k < ro[i + 1]; ++k)
        ax += static_cast<double>(v[k]) * x[ci[k]];
      out[i] = static_cast<float>(b ? static_cast<double>(b[i]) - ax : ax);
    }
  }

  /// out ~ A_l^-1 b: one cycle (AggregationMultigridSolver::Internals::Visit).
  template <typename TB, typename TO>
  void Visit(int l, const TB* b, TO* out) const
  {
    const int L = static_cast<int>(Levels.size());
    const Level& lev = Levels[l];
    const int n = lev.Pattern->Size;
    if (l == L - 1)
    {
      Eigen::VectorXd rhs(n);
      for (int i = 0; i < n; ++i)
        rhs[i] = static_cast<double>(b[i]);
      const Eigen::VectorXd x = Coarsest.solve(rhs);
      for (int i = 0; i < n; ++i)
        out[i] = static_cast<TO>(x[i]);
      return;
    }
    const double w = 1.0 / Theta;
    const float* inv = lev.InverseL1.data();
    float* X = lev.X.data();
    // Pre-smoothing from zero: x = D^-1 b / theta.
#pragma omp parallel for num_threads(Threads) schedule(static) if(n > SchwarzThreshold)
    for (int i = 0; i < n; ++i)
      X[i] = static_cast<float>(w * inv[i] * static_cast<double>(b[i]));
    Residual(lev, b, static_cast<const float*>(X), lev.R.data());
    // Restriction b_c = P^T r (sums over the aggregates).
    const Level& coarse = Levels[l + 1];
    {
      const int nc = coarse.Pattern->Size;
      const float* R = lev.R.data();
      float* cb = coarse.B.data();
#pragma omp parallel for num_threads(Threads) schedule(static) if(nc > SchwarzThreshold)
      for (int a = 0; a < nc; ++a)
      {
        double s = 0.0;
        for (int m = lev.MemberOffsets[a]; m < lev.MemberOffsets[a + 1]; ++m)
          s += R[lev.Members[m]];
        cb[a] = static_cast<float>(s);
      }
    }
    // gamma cycles on the coarse level below level 0 (W-cycle), as a
    // stationary iteration from zero.
    const int gamma = l + 1 < L - 1 ? std::max(1, CycleIndex) : 1;
    for (int g = 0; g < gamma; ++g)
    {
      if (g > 0)
      {
        Residual(coarse, static_cast<const float*>(coarse.Saved.data()),
          static_cast<const float*>(coarse.Sum.data()), coarse.B.data());
      }
      Visit(l + 1, static_cast<const float*>(coarse.B.data()), coarse.Y.data());
      coarse.X.swap(coarse.Y);
      if (g > 0)
      {
        float* xc = coarse.X.data();
        const float* sum = coarse.Sum.data();
        const long long mc = static_cast<long long>(coarse.X.size());
#pragma omp parallel for num_threads(Threads) schedule(static) if(mc > SchwarzThreshold)
        for (long long k = 0; k < mc; ++k)
          xc[k] += sum[k];
      }
      if (g == 0 && gamma > 1)
        coarse.Saved.swap(coarse.B);
      if (g + 1 < gamma)
        coarse.Sum.swap(coarse.X);
    }
    // Coarse correction x += s P x_c, then post-smoothing into out.
    {
      const float* xc = coarse.X.data();
      const int* agg = lev.Aggregate;
#pragma omp parallel for num_threads(Threads) schedule(static) if(n > SchwarzThreshold)
      for (int i = 0; i < n; ++i)
        X[i] = static_cast<float>(X[i] + Scale * xc[agg[i]]);
    }
    const int* ro = lev.Pattern->Offsets.data();
    const int* ci = lev.Pattern->Columns.data();
    const float* v = lev.Single.data();
#pragma omp parallel for num_threads(Threads) schedule(static) if(n > SchwarzThreshold)
    for (int i = 0; i < n; ++i)
    {
      double ax = 0.0;
      for (int k = ro[i]; k < ro[i + 1]; ++k)
        ax += static_cast<double>(v[k]) * X[ci[k]];
      out[i] =
        static_cast<TO>(static_cast<double>(X[i]) + w * inv[i] * (static_cast<double>(b[i]) - ax));
    }
  }
};

namespace
{

/// hypre's preconditioner set-up: nothing (Setup built the block cycle).
HYPRE_Int SchwarzNoSetup(HYPRE_Solver, HYPRE_Matrix, HYPRE_Vector, HYPRE_Vector)
{
  return 0;
}

/// hypre's preconditioner: z = B r on this rank's rows.
HYPRE_Int ApplySchwarz(HYPRE_Solver data, HYPRE_Matrix, HYPRE_Vector r, HYPRE_Vector z)
{
  const auto* self = reinterpret_cast<const SchwarzAggregationPCG*>(data);
  const double* rl = hypre_VectorData(hypre_ParVectorLocalVector(reinterpret_cast<hypre_ParVector*>(r)));
  double* zl = hypre_VectorData(hypre_ParVectorLocalVector(reinterpret_cast<hypre_ParVector*>(z)));
  try
  {
    self->ApplyPreconditioner(rl, zl);
  }
  catch (...)
  {
    return 1; // cannot happen after a successful Setup; hypre reports it
  }
  return 0;
}

} // namespace

SchwarzAggregationPCG::SchwarzAggregationPCG(MPI_Comm comm)
  : Comm_(comm)
  , H_(std::make_unique<Handles>())
  , B_(std::make_unique<Block>())
{
  EnsureHypreInitialized();
}

SchwarzAggregationPCG::~SchwarzAggregationPCG()
{
  Free();
}

void SchwarzAggregationPCG::Free()
{
  hypre::DestroyPCG(H_->PCG, H_->A, H_->B, H_->X);
  H_->Work.Destroy();
  H_->Rows.clear();
  H_->Pattern = 0;
  B_ = std::make_unique<Block>();
  Structure_.reset();
  OwnsStructure_ = false;
  Places_.clear();
  PlacePattern_ = 0;
}

void SchwarzAggregationPCG::SetOptions(const SolverOptions& options)
{
  double scale = CoarseScale_;
  int gamma = CycleIndex_, coarsest = CoarsestSize_, threads = Threads_;
  options.ReadNumber(Who, "agg-coarse-scale", 0.0, "the coarse-correction factor, in (0, 2)", scale);
  options.ReadInteger(Who, "agg-cycle-index", 1, "1 (V-cycle) or 2 (W-cycle)", gamma);
  options.ReadInteger(Who, "agg-coarsest-size", 1, "vertices of the coarsest level, >= 1", coarsest);
  options.ReadInteger(Who, "agg-threads", 0, "OpenMP threads, >= 0 (0: OpenMP's default)", threads);
  if (!(scale > 0.0 && scale < 2.0))
  {
    throw Error(std::string(Who) + ": option agg-coarse-scale = " + std::to_string(scale) +
      " is invalid: the coarse-correction factor, in (0, 2)");
  }
  if (gamma > 2)
  {
    throw Error(std::string(Who) + ": option agg-cycle-index = " + std::to_string(gamma) +
      " is invalid: 1 (V-cycle) or 2 (W-cycle)");
  }
  CoarseScale_ = scale;
  CycleIndex_ = gamma;
  CoarsestSize_ = coarsest;
  Threads_ = threads;
}

void SchwarzAggregationPCG::SetCoordinates(const double* xyz, int rows)
{
  if (rows < 0 || (rows > 0 && !xyz))
  {
    throw Error(std::string(Who) + ": SetCoordinates() needs 3 coordinates for each of >= 0 rows");
  }
  Coordinates_.assign(xyz, xyz + 3 * static_cast<std::size_t>(rows));
}

void SchwarzAggregationPCG::BuildMatrix(
  int rowBegin, int rowEnd, const int* rowOffsets, const int* columns, const double* values)
{
  RowBegin_ = rowBegin;
  RowEnd_ = rowEnd;
  const int rows = rowEnd - rowBegin;
  Handles& h = *H_;
  h.A = hypre::BuildMatrix(Comm_, rowBegin, rowEnd, rowOffsets, columns, values, h.Rows, Who);
  h.Pattern = hypre::PatternFingerprint(rows, rowOffsets, columns);
  hypre_ParCSRMatrix* a = nullptr;
  HYPRE_IJMatrixGetObject(h.A, reinterpret_cast<void**>(&a));
  const double local = static_cast<double>(hypre_CSRMatrixNumNonzeros(hypre_ParCSRMatrixDiag(a)) +
    hypre_CSRMatrixNumNonzeros(hypre_ParCSRMatrixOffd(a)));
  double total = 0.0;
  MPI_Allreduce(&local, &total, 1, MPI_DOUBLE, MPI_SUM, Comm_);
  NonZeros_ = static_cast<long long>(total);
}

void SchwarzAggregationPCG::ExtractBlock(const int* rowOffsets, const int* columns)
{
  const int rows = RowEnd_ - RowBegin_;
  BlockOffsets_.assign(static_cast<std::size_t>(rows) + 1, 0);
  BlockColumns_.clear();
  BlockEntries_.clear();
  BlockColumns_.reserve(static_cast<std::size_t>(rowOffsets[rows]));
  BlockEntries_.reserve(static_cast<std::size_t>(rowOffsets[rows]));
  for (int i = 0; i < rows; ++i)
  {
    for (int k = rowOffsets[i]; k < rowOffsets[i + 1]; ++k)
    {
      if (columns[k] >= RowBegin_ && columns[k] < RowEnd_)
      {
        BlockColumns_.push_back(columns[k] - RowBegin_);
        BlockEntries_.push_back(k);
      }
    }
    BlockOffsets_[i + 1] = static_cast<int>(BlockColumns_.size());
  }
  BlockPattern_ = hypre::PatternFingerprint(rows, BlockOffsets_.data(), BlockColumns_.data());
}

void SchwarzAggregationPCG::SetBlockValues(const double* values)
{
  Block& blk = *B_;
  const int nt = Threads_ > 0 ? Threads_ : omp_get_max_threads();
  blk.Threads = std::max(1, nt);
  blk.Scale = CoarseScale_;
  blk.CycleIndex = CycleIndex_;
  const int rows = RowEnd_ - RowBegin_;
  if (rows == 0 || !Structure_)
  {
    blk.Levels.clear();
    return;
  }
  const AggregationMultigridSolver& s = *Structure_;
  const int L = s.GetNumberOfLevels();
  blk.Levels.resize(L);
  for (int l = 0; l < L; ++l)
  {
    Block::Level& lev = blk.Levels[l];
    lev.Pattern = &s.GetPattern(l);
    const bool last = l == L - 1;
    lev.Aggregate = last ? nullptr : s.GetAggregates(l).data();
    lev.MemberOffsets = last ? nullptr : s.GetMemberOffsets(l).data();
    lev.Members = last ? nullptr : s.GetMembers(l).data();
    const int n = lev.Pattern->Size;
    const std::size_t nnz = lev.Pattern->Columns.size();
    lev.Values.assign(nnz, 0.0);
    if (l == 0)
    {
      for (std::size_t k = 0; k < nnz; ++k)
        lev.Values[k] = values[BlockEntries_[k]];
    }
    else
    {
      // Galerkin P^T A P with piecewise-constant P: coarse (a, b) = the sum
      // of the fine a_ij with i in aggregate a and j in aggregate b; each
      // coarse row summed by one thread in a fixed order.
      const Block::Level& fine = blk.Levels[l - 1];
      const CsrPattern& fp = *fine.Pattern;
      const int* slots = s.GetCoarseSlots(l - 1).data();
      const double* f = fine.Values.data();
      double* cv = lev.Values.data();
#pragma omp parallel for num_threads(blk.Threads) schedule(dynamic, 256) if(n > SchwarzThreshold)
      for (int a = 0; a < n; ++a)
      {
        for (int m = fine.MemberOffsets[a]; m < fine.MemberOffsets[a + 1]; ++m)
        {
          const int i = fine.Members[m];
          for (int k = fp.Offsets[i]; k < fp.Offsets[i + 1]; ++k)
            cv[slots[k]] += f[k];
        }
      }
    }
    for (auto* v : { &lev.B, &lev.X, &lev.Y, &lev.R, &lev.Saved, &lev.Sum })
      v->assign(static_cast<std::size_t>(n), 0.0f);
    if (last)
    {
      for (std::size_t k = 0; k < nnz; ++k)
      {
        if (!std::isfinite(lev.Values[k]))
        {
          throw Error(std::string(Who) + ": the block of rows " + std::to_string(RowBegin_) +
            ".." + std::to_string(RowEnd_ - 1) + " has a non-finite entry (level " +
            std::to_string(l) + ")");
        }
      }
      const ColMatrix a(Eigen::Map<const RowMatrix>(n, n, static_cast<int>(nnz),
        lev.Pattern->Offsets.data(), lev.Pattern->Columns.data(), lev.Values.data()));
      blk.Coarsest.compute(a);
      if (blk.Coarsest.info() != Eigen::Success || !(blk.Coarsest.vectorD().minCoeff() > 0.0))
      {
        std::ostringstream os;
        os << Who << ": the coarsest-level matrix of the block of rows " << RowBegin_ << ".."
           << RowEnd_ - 1 << " (level " << l << ", " << n
           << " vertices) is not positive definite: the matrix is not SPD";
        throw Error(os.str());
      }
      blk.CoarsestNonZeros =
        static_cast<std::size_t>(blk.Coarsest.matrixL().nestedExpression().nonZeros());
      continue;
    }
    // Single-precision values and the l1 diagonal 1 / sum_j |a_ij|; every
    // diagonal entry positive, every entry finite.
    lev.Single.resize(nnz);
    lev.InverseL1.resize(static_cast<std::size_t>(n));
    const CsrPattern& p = *lev.Pattern;
    long long bad = -1;
#pragma omp parallel for num_threads(blk.Threads) schedule(static) reduction(max : bad) if(n > SchwarzThreshold)
    for (int i = 0; i < n; ++i)
    {
      double sum = 0.0;
      bool ok = false;
      for (int k = p.Offsets[i]; k < p.Offsets[i + 1]; ++k)
      {
        const double a = lev.Values[k];
        lev.Single[k] = static_cast<float>(a);
        sum += std::abs(a);
        if (p.Columns[k] == i)
          ok = a > 0.0;
      }
      ok = ok && std::isfinite(sum);
      lev.InverseL1[i] = sum > 0.0 ? static_cast<float>(1.0 / sum) : 0.0f;
      if (!ok)
        bad = std::max<long long>(bad, i);
    }
    if (bad >= 0)
    {
      std::ostringstream os;
      os << Who << ": row " << (l == 0 ? RowBegin_ + bad : bad) << " (level " << l
         << ") has a non-finite entry or a diagonal entry that is not positive: the matrix is "
            "not SPD";
      throw Error(os.str());
    }
  }
}

void SchwarzAggregationPCG::BuildSolver()
{
  Handles& h = *H_;
  for (HYPRE_IJVector* v : { &h.B, &h.X })
  {
    SchwarzCheck(HYPRE_IJVectorCreate(Comm_, RowBegin_, RowEnd_ - 1, v), "vector creation");
    SchwarzCheck(HYPRE_IJVectorSetObjectType(*v, HYPRE_PARCSR), "vector type");
    SchwarzCheck(HYPRE_IJVectorInitialize(*v), "vector initialisation");
    SchwarzCheck(HYPRE_IJVectorAssemble(*v), "vector assembly");
  }
  HYPRE_ParCSRMatrix a;
  HYPRE_ParVector b, x;
  HYPRE_IJMatrixGetObject(h.A, reinterpret_cast<void**>(&a));
  HYPRE_IJVectorGetObject(h.B, reinterpret_cast<void**>(&b));
  HYPRE_IJVectorGetObject(h.X, reinterpret_cast<void**>(&x));
  SchwarzCheck(HYPRE_ParCSRPCGCreate(Comm_, &h.PCG), "PCG creation");
  HYPRE_PCGSetTwoNorm(h.PCG, 1);
  HYPRE_PCGSetPrintLevel(h.PCG, 0);
  HYPRE_PCGSetLogging(h.PCG, 1);
  HYPRE_PCGSetPrecond(h.PCG, reinterpret_cast<HYPRE_PtrToSolverFcn>(ApplySchwarz),
    reinterpret_cast<HYPRE_PtrToSolverFcn>(SchwarzNoSetup), reinterpret_cast<HYPRE_Solver>(this));
  SchwarzCheck(HYPRE_ParCSRPCGSetup(h.PCG, a, b, x), "PCG set-up");
}

void SchwarzAggregationPCG::Setup(
  int rowBegin, int rowEnd, const int* rowOffsets, const int* columns, const double* values)
{
  if (rowEnd < rowBegin)
  {
    throw Error(std::string(Who) + ": Setup() with rowEnd < rowBegin");
  }
  Free();
  const double start = MPI_Wtime();
  BuildMatrix(rowBegin, rowEnd, rowOffsets, columns, values);
  const double assembled = MPI_Wtime();
  ExtractBlock(rowOffsets, columns);
  const int rows = rowEnd - rowBegin;
  if (rows > 0)
  {
    // The aggregation of the block at the rows' positions (zeros without
    // SetCoordinates: every neighbour equally near, ties to the smaller id).
    std::vector<double> points = Coordinates_;
    if (points.size() != 3 * static_cast<std::size_t>(rows))
      points.assign(3 * static_cast<std::size_t>(rows), 0.0);
    DiffusionSystem pattern;
    pattern.NumberOfUnknowns = rows;
    pattern.RowOffsets = BlockOffsets_;
    pattern.ColumnIndices = BlockColumns_;
    auto structure = std::make_shared<AggregationMultigridSolver>();
    structure->SetCoarsestSize(CoarsestSize_);
    structure->SetNumberOfThreads(Threads_);
    structure->BuildStructure(pattern, points);
    Structure_ = std::move(structure);
    OwnsStructure_ = true;
  }
  SetBlockValues(values);
  BuildSolver();
  MatrixMilliseconds_ = 1000.0 * (assembled - start);
  HierarchyMilliseconds_ = 1000.0 * (MPI_Wtime() - assembled);
}

bool SchwarzAggregationPCG::SetupShared(int rowBegin, int rowEnd, const int* rowOffsets,
  const int* columns, const double* values, const DistributedLinearSolver& donor)
{
  const auto* other = dynamic_cast<const SchwarzAggregationPCG*>(&donor);
  if (!other || other == this || !other->H_->PCG || other->RowBegin_ != rowBegin ||
    other->RowEnd_ != rowEnd || (rowEnd > rowBegin && !other->Structure_))
  {
    return false;
  }
  // The same block pattern as the donor's (its structure is of that pattern).
  RowBegin_ = rowBegin;
  RowEnd_ = rowEnd;
  ExtractBlock(rowOffsets, columns);
  if (BlockPattern_ != other->BlockPattern_ || BlockColumns_ != other->BlockColumns_ ||
    BlockOffsets_ != other->BlockOffsets_)
  {
    return false;
  }
  std::shared_ptr<const AggregationMultigridSolver> structure = other->Structure_;
  std::vector<int> offsets = BlockOffsets_, blockColumns = BlockColumns_, entries = BlockEntries_;
  Free();
  BlockOffsets_.swap(offsets);
  BlockColumns_.swap(blockColumns);
  BlockEntries_.swap(entries);
  const double start = MPI_Wtime();
  BuildMatrix(rowBegin, rowEnd, rowOffsets, columns, values);
  const double assembled = MPI_Wtime();
  Structure_ = std::move(structure);
  SetBlockValues(values);
  BuildSolver();
  MatrixMilliseconds_ = 1000.0 * (assembled - start);
  HierarchyMilliseconds_ = 1000.0 * (MPI_Wtime() - assembled);
  return true;
}

void SchwarzAggregationPCG::UpdateValues(
  const int* rowOffsets, const int* columns, const double* values)
{
  Handles& h = *H_;
  if (!h.A || !h.PCG)
  {
    throw Error(std::string(Who) + ": UpdateValues() called before Setup()");
  }
  const double start = MPI_Wtime();
  const int rows = RowEnd_ - RowBegin_;
  if (hypre::PatternFingerprint(rows, rowOffsets, columns) != h.Pattern)
  {
    throw Error(std::string(Who) +
      ": UpdateValues(): the rows' pattern is not the last Setup()'s (a changed pattern)");
  }
  // Into the assembled ParCSR matrix, each entry's place found once.
  hypre::ScatterValues(h.A, RowBegin_, RowEnd_, rowOffsets, columns, values, Places_,
    PlacePattern_, Who);
  const double assembled = MPI_Wtime();
  SetBlockValues(values); // the kept aggregation, the new matrix's values
  MatrixMilliseconds_ = 1000.0 * (assembled - start);
  HierarchyMilliseconds_ = 1000.0 * (MPI_Wtime() - assembled);
}

void SchwarzAggregationPCG::UpdateRows(const int* rowOffsets, const int* columns,
  const double* values, const int* rows, int numRows)
{
  Handles& h = *H_;
  if (!h.A || !h.PCG)
  {
    throw Error(std::string(Who) + ": UpdateRows() called before Setup()");
  }
  const double start = MPI_Wtime();
  hypre::ScatterRows(h.A, RowBegin_, RowEnd_, rowOffsets, columns, values, rows, numRows, Places_,
    PlacePattern_, Who);
  const double assembled = MPI_Wtime();
  SetBlockValues(values); // the kept aggregation, the new matrix's values
  MatrixMilliseconds_ = 1000.0 * (assembled - start);
  HierarchyMilliseconds_ = 1000.0 * (MPI_Wtime() - assembled);
}

void SchwarzAggregationPCG::PrepareUpdates(const int* rowOffsets, const int* columns)
{
  if (!H_->A)
  {
    throw Error(std::string(Who) + ": PrepareUpdates() called before Setup()");
  }
  hypre::FindPlaces(H_->A, RowBegin_, RowEnd_, rowOffsets, columns, Places_, PlacePattern_, Who);
}

void SchwarzAggregationPCG::ApplyPreconditioner(const double* r, double* z) const
{
  if (!H_->PCG)
  {
    throw Error(std::string(Who) + ": ApplyPreconditioner() before Setup()");
  }
  if (B_->Levels.empty())
    return; // no rows on this rank
  B_->Visit(0, r, z);
}

int SchwarzAggregationPCG::Solve(
  const double* bLocal, double* xLocal, bool guess, double relTol, int maxIter, double& relRes)
{
  Handles& h = *H_;
  if (!h.PCG)
  {
    throw Error(std::string(Who) + ": Solve() called before Setup()");
  }
  return hypre::SolvePCG(
    h.PCG, h.A, h.B, h.X, h.Rows, bLocal, xLocal, guess, relTol, maxIter, relRes, Who);
}

void SchwarzAggregationPCG::SumOverRanks(double* values, int count) const
{
  MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_DOUBLE, MPI_SUM, Comm_);
}

void SchwarzAggregationPCG::SolveChannels(
  const std::array<DistributedLinearSolver*, NumberOfChannels>& solvers,
  const std::array<const double*, NumberOfChannels>& b, const std::array<double*, NumberOfChannels>& x,
  const std::array<bool, NumberOfChannels>& guess, const DistributedSolveControl& control,
  std::array<DistributedChannelStats, NumberOfChannels>& stats)
{
  std::array<const SchwarzAggregationPCG*, NumberOfChannels> own{};
  std::array<HYPRE_IJMatrix, NumberOfChannels> matrices{};
  std::array<hypre::ChannelWork*, NumberOfChannels> work{};
  bool ours = true;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    if (!solvers[c])
      continue;
    auto* other = dynamic_cast<SchwarzAggregationPCG*>(solvers[c]);
    if (!other || !other->H_->PCG)
    {
      ours = false;
      break;
    }
    if (other->RowBegin_ != RowBegin_ || other->RowEnd_ != RowEnd_)
    {
      throw Error(std::string(Who) + ": SolveChannels() with channels on other rows");
    }
    own[c] = other;
    matrices[c] = other->H_->A;
    work[c] = &other->H_->Work;
  }
  if (!ours)
  {
    SolveChannelsOneByOne(solvers, b, x, guess, control, stats);
    return;
  }
  hypre::SolveChannels(Comm_, matrices, work,
    [&own](int c, HYPRE_ParCSRMatrix, HYPRE_ParVector r, HYPRE_ParVector z) -> HYPRE_Int {
      const double* rl =
        hypre_VectorData(hypre_ParVectorLocalVector(reinterpret_cast<hypre_ParVector*>(r)));
      double* zl = hypre_VectorData(hypre_ParVectorLocalVector(reinterpret_cast<hypre_ParVector*>(z)));
      own[c]->ApplyPreconditioner(rl, zl); // throws translucency::Error (caught per rank)
      return 0;
    },
    b, x, guess, control, stats, Who);
}

int SchwarzAggregationPCG::GetNumberOfLevels() const
{
  return std::max<int>(1, static_cast<int>(B_->Levels.size()));
}

double SchwarzAggregationPCG::GetOperatorComplexity() const
{
  return Structure_ ? Structure_->GetOperatorComplexity() : 1.0;
}

std::size_t SchwarzAggregationPCG::GetMemoryBytes() const
{
  std::size_t bytes = 0;
  for (const auto& lev : B_->Levels)
  {
    bytes += lev.Values.size() * sizeof(double) +
      (lev.Single.size() + lev.InverseL1.size() + lev.B.size() + lev.X.size() + lev.Y.size() +
        lev.R.size() + lev.Saved.size() + lev.Sum.size()) *
        sizeof(float);
  }
  bytes += B_->CoarsestNonZeros * (sizeof(double) + sizeof(int));
  bytes += (BlockOffsets_.size() + BlockColumns_.size() + BlockEntries_.size() + Places_.size()) *
      sizeof(int) +
    Coordinates_.size() * sizeof(double);
  // The aggregation counted once, by the solver that built it.
  if (Structure_ && OwnsStructure_)
    bytes += Structure_->GetMemoryBytes();
  return bytes;
}

} // namespace translucency
