#include "HypreSolver.h"

#include "Error.h"
#include "HypreParCSR.h"
#include "LinearSolverCommon.h"

#include <HYPRE.h>
#include <HYPRE_parcsr_ls.h>
#include <_hypre_parcsr_ls.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <numeric>
#include <sstream>
#include <type_traits>
#include <vector>

namespace translucency
{

namespace
{

bool HypreInitialisedHere = false;
bool MPIInitialisedHere = false;

void FinaliseAtExit()
{
  if (HypreInitialisedHere)
  {
    HYPRE_Finalize();
  }
  int finalised = 0;
  MPI_Finalized(&finalised);
  if (MPIInitialisedHere && !finalised)
  {
    MPI_Finalize();
  }
}

void Check(HYPRE_Int code, const char* what)
{
  hypre::Check(code, "hypre-amg", what);
}

} // namespace

void EnsureHypreInitialized()
{
  static std::once_flag once;
  std::call_once(once, [] {
    int initialised = 0;
    MPI_Initialized(&initialised);
    if (!initialised)
    {
      // An Open MPI singleton normally starts a helper daemon (orted, through
      // the ssh/rsh launcher): not needed on MPI_COMM_SELF, and MPI_Init
      // aborts the whole process when that fails. Users may still override.
      setenv("OMPI_MCA_ess_singleton_isolated", "1", 0);
      int provided = 0;
      if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
      {
        throw Error("hypre-amg: MPI_Init failed (is Open MPI installed and usable?)");
      }
      MPIInitialisedHere = true;
    }
    HYPRE_Init();
    HypreInitialisedHere = true;
    std::atexit(FinaliseAtExit);
  });
}

const MPI_Comm* GetSelfCommunicator()
{
  static const MPI_Comm self = MPI_COMM_SELF;
  return &self;
}

const MPI_Comm* GetWorldCommunicator()
{
  static const MPI_Comm world = MPI_COMM_WORLD;
  return &world;
}

MPI_Comm GetMPIComm(const Communicator& comm)
{
  EnsureHypreInitialized();
  return comm.IsMPI() ? *static_cast<const MPI_Comm*>(comm.GetHandle()) : MPI_COMM_SELF;
}

Communicator MakeCommunicator(const MPI_Comm* comm)
{
  EnsureHypreInitialized();
  int rank = 0, size = 1;
  MPI_Comm_rank(*comm, &rank);
  MPI_Comm_size(*comm, &size);
  return Communicator(comm, rank, size);
}

SolverOptions BoomerAMGOptions::ToOptions() const
{
  return { { "amg-coarsening", static_cast<double>(CoarsenType) },
    { "amg-interpolation", static_cast<double>(InterpType) },
    { "amg-pmax", static_cast<double>(PMaxElmts) }, { "amg-strong-threshold", StrongThreshold },
    { "amg-relaxation", static_cast<double>(RelaxType) },
    { "amg-sweeps", static_cast<double>(NumSweeps) },
    { "amg-relaxation-down", static_cast<double>(RelaxDown) },
    { "amg-relaxation-up", static_cast<double>(RelaxUp) },
    { "amg-aggressive-levels", static_cast<double>(AggNumLevels) },
    { "amg-aggressive-interpolation", static_cast<double>(AggInterpType) },
    { "amg-keep-transpose", static_cast<double>(KeepTranspose) } };
}

void HypreBoomerAMGPCG::SetOptions(const SolverOptions& options)
{
  const std::string who = "cg/boomeramg";
  BoomerAMGOptions o = Options_;
  options.ReadInteger(who, "amg-coarsening", 0, "a BoomerAMG coarsening code (10 = HMIS)", o.CoarsenType);
  options.ReadInteger(who, "amg-interpolation", 0, "a BoomerAMG interpolation code (6 = ext+i)", o.InterpType);
  options.ReadInteger(who, "amg-pmax", 0, "interpolation entries per row, >= 0", o.PMaxElmts);
  options.ReadNumber(who, "amg-strong-threshold", 0.0, "the strength threshold, in [0, 1)", o.StrongThreshold);
  options.ReadInteger(who, "amg-relaxation", 0, "a BoomerAMG relaxation code", o.RelaxType);
  options.ReadInteger(who, "amg-sweeps", 1, "sweeps, >= 1", o.NumSweeps);
  options.ReadInteger(who, "amg-relaxation-down", -1,
    "a BoomerAMG relaxation code of the down cycle (-1: amg-relaxation)", o.RelaxDown);
  options.ReadInteger(who, "amg-relaxation-up", -1,
    "a BoomerAMG relaxation code of the up cycle (-1: amg-relaxation)", o.RelaxUp);
  options.ReadInteger(who, "amg-aggressive-levels", 0, "levels, >= 0", o.AggNumLevels);
  options.ReadInteger(who, "amg-aggressive-interpolation", 0, "a BoomerAMG interpolation code", o.AggInterpType);
  options.ReadInteger(who, "amg-keep-transpose", 0, "0 or 1", o.KeepTranspose);
  if (!(o.StrongThreshold < 1.0))
  {
    throw Error(who + ": option amg-strong-threshold = " + std::to_string(o.StrongThreshold) +
      " is invalid: the strength threshold, in [0, 1)");
  }
  Options_ = o;
}

namespace
{
/// The assembled ParCSR matrix of an IJ matrix.
hypre_ParCSRMatrix* ParCSROf(HYPRE_IJMatrix ij)
{
  HYPRE_ParCSRMatrix a = nullptr;
  HYPRE_IJMatrixGetObject(ij, reinterpret_cast<void**>(&a));
  return reinterpret_cast<hypre_ParCSRMatrix*>(a);
}

/**
 * A channel's own Galerkin levels on another channel's BoomerAMG coarsening
 * (HypreBoomerAMGPCG::SetupShared): the donor's interpolation P_l and
 * coarse/fine splitting, this channel's coarse operators
 * A_{l+1} = P_l^T A_l P_l from its own fine matrix, the l1 norms of its own
 * levels for the smoother, and its own coarsest matrix for the Gaussian
 * elimination. Applied by swapping them into the donor's BoomerAMG for the
 * duration of one V-cycle (GalerkinSolve): the cycle is then the one
 * BoomerAMG would run on a hierarchy of this channel's matrix with the
 * donor's P. What the serial path's aggregation multigrid does across its
 * channels (one aggregation, each channel's Galerkin values: Performance.md).
 */
struct GalerkinLevels
{
  HYPRE_Solver Donor = nullptr;
  std::vector<hypre_ParCSRMatrix*> A;  ///< [0] unused (the caller's fine matrix); own from 1
  std::vector<hypre_Vector*> L1;       ///< own l1 norms where the donor has them
  HYPRE_Real* CoarseDense = nullptr;   ///< own coarsest matrix for relaxation 9, if any
  GalerkinLevels() = default;
  GalerkinLevels(const GalerkinLevels&) = delete;
  GalerkinLevels& operator=(const GalerkinLevels&) = delete;
  ~GalerkinLevels()
  {
    for (std::size_t l = 1; l < A.size(); ++l)
      if (A[l])
        hypre_ParCSRMatrixDestroy(A[l]);
    for (hypre_Vector* v : L1)
      if (v)
        hypre_SeqVectorDestroy(v);
    hypre_TFree(CoarseDense, HYPRE_MEMORY_HOST);
  }

  /// Exchanges these levels with the donor's (twice: back as they were).
  void Swap()
  {
    auto* amg = reinterpret_cast<hypre_ParAMGData*>(Donor);
    hypre_ParCSRMatrix** levels = hypre_ParAMGDataAArray(amg);
    for (std::size_t l = 1; l < A.size(); ++l)
      std::swap(levels[l], A[l]);
    hypre_Vector** l1 = hypre_ParAMGDataL1Norms(amg);
    for (std::size_t l = 0; l1 && l < L1.size(); ++l)
      std::swap(l1[l], L1[l]);
    if (CoarseDense)
      std::swap(hypre_ParAMGDataAMat(amg), CoarseDense);
  }
};

/// Whether a sharer can have its own Galerkin levels on `donor`'s
/// coarsening: the relaxations whose set-up data GalerkinLevels rebuilds
/// (l1 Gauss-Seidel 8/13/14 in natural order, on the coarsest level also
/// Gaussian elimination 9), and no other per-level data.
bool GalerkinSharable(HYPRE_Solver donor)
{
  auto* amg = reinterpret_cast<hypre_ParAMGData*>(donor);
  if (!amg || hypre_ParAMGDataNumLevels(amg) < 1 || hypre_ParAMGDataBlockMode(amg) ||
    hypre_ParAMGDataRelaxOrder(amg) != 0 || hypre_ParAMGDataAdditive(amg) >= 0 ||
    hypre_ParAMGDataMultAdditive(amg) >= 0 || hypre_ParAMGDataSimple(amg) >= 0 ||
    hypre_ParAMGDataSmoothNumLevels(amg) > 0 || hypre_ParAMGDataSeqThreshold(amg) > 0 ||
    hypre_ParAMGDataADropTol(amg) > 0.0 || hypre_ParAMGDataNonGalerkinTol(amg) > 0.0)
    return false;
  const HYPRE_Int* relax = hypre_ParAMGDataGridRelaxType(amg);
  auto l1 = [](HYPRE_Int t) { return t == 8 || t == 13 || t == 14; };
  return relax && l1(relax[1]) && l1(relax[2]) && (l1(relax[3]) || relax[3] == 9);
}

/**
 * The fine level's l1 norms of the smoother (the channel's own BoomerAMG's,
 * or its own Galerkin levels'), or nullptr for a smoother without them or a
 * one-level hierarchy.
 */
hypre_Vector* FineNorms(HYPRE_Solver amg, GalerkinLevels* galerkin)
{
  if (galerkin)
    return galerkin->L1.empty() ? nullptr : galerkin->L1[0];
  if (!amg)
    return nullptr;
  hypre_Vector** l1 = hypre_ParAMGDataL1Norms(reinterpret_cast<hypre_ParAMGData*>(amg));
  return l1 ? l1[0] : nullptr;
}

/**
 * The fine level's l1 norms of rows `rows` (local numbers; all rows when
 * null) recomputed from the matrix's current values: BoomerAMG's option 4
 * (natural order; hypre_ParCSRComputeL1Norms), per row |a_ii| plus half the
 * absolute off-rank entries, truncated to |a_ii| when within 4/3 of it,
 * with the diagonal's sign. After a values-only update (a paint) the kept
 * hierarchy's l1 Gauss-Seidel sweeps would otherwise divide the new
 * residual by the old norm: where a paint raised a row's diagonal more
 * than twice (an absorber) the sweep over-corrects there and diverges, and
 * the V-cycle is no longer a convergent preconditioner. Also what every
 * set-up's fine norms are (BoomerAMG's overwritten, a sharer's own computed
 * here), so that a row's norm never depends on whether it was last set by
 * hypre or here. Throws translucency::Error on a zero diagonal.
 */
void RefreshFineNorms(hypre_ParCSRMatrix* m, hypre_Vector* fine, const int* rows, int count)
{
  if (!fine)
    return;
  const HYPRE_Int numRows = hypre_ParCSRMatrixNumRows(m);
  if (hypre_VectorSize(fine) != numRows)
  {
    throw Error("hypre-amg: the kept hierarchy's fine level has " +
      std::to_string(hypre_VectorSize(fine)) + " rows, the matrix " + std::to_string(numRows));
  }
  const hypre_CSRMatrix* diag = hypre_ParCSRMatrixDiag(m);
  const hypre_CSRMatrix* offd = hypre_ParCSRMatrixOffd(m);
  const HYPRE_Int* di = hypre_CSRMatrixI(diag);
  const HYPRE_Int* dj = hypre_CSRMatrixJ(diag);
  const HYPRE_Complex* dv = hypre_CSRMatrixData(diag);
  const HYPRE_Int* oi = hypre_CSRMatrixNumCols(offd) > 0 ? hypre_CSRMatrixI(offd) : nullptr;
  const HYPRE_Complex* ov = oi ? hypre_CSRMatrixData(offd) : nullptr;
  HYPRE_Real* l1 = hypre_VectorData(fine);
  const int n = rows ? count : numRows;
  for (int k = 0; k < n; ++k)
  {
    const HYPRE_Int i = rows ? rows[k] : k;
    if (i < 0 || i >= numRows)
      throw Error("hypre-amg: row " + std::to_string(i) + " outside the rank's " +
        std::to_string(numRows) + " rows");
    HYPRE_Real d = 0.0;
    for (HYPRE_Int e = di[i]; e < di[i + 1]; ++e)
    {
      if (dj[e] == i)
      {
        d = dv[e];
        break;
      }
    }
    const HYPRE_Real ad = std::abs(d);
    HYPRE_Real norm = ad;
    if (oi)
    {
      for (HYPRE_Int e = oi[i]; e < oi[i + 1]; ++e)
        norm += 0.5 * std::abs(ov[e]);
    }
    if (norm <= 4.0 / 3.0 * ad)
      norm = ad;
    if (norm == 0.0)
    {
      throw Error("hypre-amg: row " + std::to_string(hypre_ParCSRMatrixFirstRowIndex(m) + i) +
        " of the matrix has a zero diagonal and no off-rank entries (the smoother divides by it)");
    }
    l1[i] = d < 0.0 ? -norm : norm;
  }
}

/**
 * Collective: `fine`'s Galerkin levels on `donor`'s coarsening (every rank
 * calls it; GalerkinSharable(donor) true). Throws translucency::Error on a
 * hypre error.
 */
std::unique_ptr<GalerkinLevels> BuildGalerkinLevels(HYPRE_Solver donor, hypre_ParCSRMatrix* fine)
{
  auto* amg = reinterpret_cast<hypre_ParAMGData*>(donor);
  const int levels = hypre_ParAMGDataNumLevels(amg);
  auto g = std::make_unique<GalerkinLevels>();
  g->Donor = donor;
  g->A.assign(static_cast<std::size_t>(levels), nullptr);
  hypre_ParCSRMatrix** P = hypre_ParAMGDataPArray(amg);
  const HYPRE_Int keepTranspose = hypre_ParAMGDataKeepTranspose(amg);
  hypre_ParCSRMatrix* a = fine;
  for (int l = 0; l + 1 < levels; ++l)
  {
    // The coarse operator as BoomerAMG's set-up forms it (par_amg_setup.c):
    // P^T A P with the donor's P.
    hypre_ParCSRMatrix* coarse = nullptr;
    if (hypre_ParAMGDataModularizedMatMat(amg))
      coarse = hypre_ParCSRMatrixRAPKT(P[l], a, P[l], keepTranspose);
    else
      hypre_BoomerAMGBuildCoarseOperatorKT(P[l], a, P[l], keepTranspose, &coarse);
    if (!coarse)
      throw Error("hypre-amg: the shared hierarchy's coarse operator failed");
    if (!hypre_ParCSRMatrixCommPkg(coarse))
      hypre_MatvecCommPkgCreate(coarse);
    hypre_ParCSRMatrixSetNumNonzeros(coarse);
    hypre_ParCSRMatrixSetDNumNonzeros(coarse);
    g->A[static_cast<std::size_t>(l) + 1] = coarse;
    a = coarse;
  }
  // The smoother's l1 norms of this channel's levels (option 4, as the
  // set-up for relaxations 8, 13 and 14 in natural order).
  hypre_Vector** donorL1 = hypre_ParAMGDataL1Norms(amg);
  if (donorL1)
  {
    g->L1.assign(static_cast<std::size_t>(levels), nullptr);
    for (int l = 0; l < levels; ++l)
    {
      if (!donorL1[l])
        continue;
      hypre_ParCSRMatrix* m = l == 0 ? fine : g->A[static_cast<std::size_t>(l)];
      hypre_Vector* v = hypre_SeqVectorCreate(hypre_ParCSRMatrixNumRows(m));
      g->L1[static_cast<std::size_t>(l)] = v; // owned (destroyed) from here on
      if (l == 0)
      {
        // The fine level's as every update recomputes them.
        hypre_SeqVectorInitialize_v2(v, hypre_ParCSRMatrixMemoryLocation(m));
        RefreshFineNorms(m, v, nullptr, 0);
        continue;
      }
      HYPRE_Real* norms = nullptr;
      hypre_ParCSRComputeL1Norms(m, 4, nullptr, &norms);
      hypre_VectorData(v) = norms;
      hypre_SeqVectorInitialize_v2(v, hypre_ParCSRMatrixMemoryLocation(m));
    }
  }
  // The coarsest level's dense copy for Gaussian elimination, laid out as
  // hypre_GaussElimSetup lays out the donor's, on the donor's
  // sub-communicator of the ranks with coarsest rows (the same rows here).
  if (hypre_ParAMGDataGridRelaxType(amg)[3] == 9 && hypre_ParAMGDataAMat(amg))
  {
    hypre_ParCSRMatrix* c = levels > 1 ? g->A[static_cast<std::size_t>(levels) - 1] : fine;
    hypre_CSRMatrix* diag = hypre_ParCSRMatrixDiag(c);
    hypre_CSRMatrix* offd = hypre_ParCSRMatrixOffd(c);
    const HYPRE_Int rows = hypre_CSRMatrixNumRows(diag);
    const HYPRE_Int n = static_cast<HYPRE_Int>(hypre_ParCSRMatrixGlobalNumRows(c));
    MPI_Comm sub = hypre_ParAMGDataNewComm(amg);
    const HYPRE_Int* info = hypre_ParAMGDataCommInfo(amg);
    if (rows > 0 && sub != MPI_COMM_NULL && info)
    {
      int ranks = 1;
      MPI_Comm_size(sub, &ranks);
      std::vector<int> counts(static_cast<std::size_t>(ranks)), displs(ranks + 1, 0);
      for (int r = 0; r < ranks; ++r)
      {
        counts[r] = n * info[r];
        displs[r + 1] = displs[r] + counts[r];
      }
      std::vector<HYPRE_Real> local(static_cast<std::size_t>(n) * rows, 0.0);
      const HYPRE_BigInt first = hypre_ParCSRMatrixFirstRowIndex(c);
      const HYPRE_BigInt* colMap = hypre_ParCSRMatrixColMapOffd(c);
      for (HYPRE_Int i = 0; i < rows; ++i)
      {
        for (HYPRE_Int k = hypre_CSRMatrixI(diag)[i]; k < hypre_CSRMatrixI(diag)[i + 1]; ++k)
          local[static_cast<std::size_t>(i) * n + (hypre_CSRMatrixJ(diag)[k] + first)] =
            hypre_CSRMatrixData(diag)[k];
        for (HYPRE_Int k = hypre_CSRMatrixI(offd)[i]; k < hypre_CSRMatrixI(offd)[i + 1]; ++k)
          local[static_cast<std::size_t>(i) * n + colMap[hypre_CSRMatrixJ(offd)[k]]] =
            hypre_CSRMatrixData(offd)[k];
      }
      g->CoarseDense = hypre_CTAlloc(HYPRE_Real, static_cast<std::size_t>(n) * n, HYPRE_MEMORY_HOST);
      MPI_Allgatherv(local.data(), n * rows, MPI_DOUBLE, g->CoarseDense, counts.data(),
        displs.data(), MPI_DOUBLE, sub);
    }
  }
  return g;
}

/// The preconditioner of a channel with Galerkin levels: one V-cycle of the
/// donor's BoomerAMG on them (`self` is the GalerkinLevels).
HYPRE_Int GalerkinSolve(HYPRE_Solver self, HYPRE_ParCSRMatrix a, HYPRE_ParVector r, HYPRE_ParVector z)
{
  auto* g = reinterpret_cast<GalerkinLevels*>(self);
  auto* amg = reinterpret_cast<hypre_ParAMGData*>(g->Donor);
  hypre_ParCSRMatrix* donorFine = hypre_ParAMGDataAArray(amg)[0];
  g->Swap();
  const HYPRE_Int code = HYPRE_BoomerAMGSolve(g->Donor, a, r, z);
  g->Swap();
  hypre_ParAMGDataAArray(amg)[0] = donorFine; // the solve put this channel's there
  return code;
}
} // namespace

struct HypreBoomerAMGPCG::Handles
{
  HYPRE_IJMatrix A = nullptr;
  HYPRE_IJVector B = nullptr, X = nullptr;
  HYPRE_Solver PCG = nullptr, AMG = nullptr;
  /// Another solver's BoomerAMG whose coarsening this one shares (not owned).
  HYPRE_Solver SharedAMG = nullptr;
  /// This channel's own levels on SharedAMG's coarsening.
  std::unique_ptr<GalerkinLevels> Galerkin;
  std::vector<HYPRE_BigInt> Rows;
  /// SolveChannels' vectors r, z, p, q (made at its first call).
  hypre::ChannelWork Work;
};

namespace
{
/// The preconditioner set-up of a channel that shares another's hierarchy:
/// nothing (the hierarchy is the donor's, already set up).
HYPRE_Int NoSetup(HYPRE_Solver, HYPRE_Matrix, HYPRE_Vector, HYPRE_Vector)
{
  return 0;
}

}

HypreBoomerAMGPCG::HypreBoomerAMGPCG(MPI_Comm comm, const BoomerAMGOptions& options)
  : Comm_(comm)
  , Options_(options)
  , H_(std::make_unique<Handles>())
{
  EnsureHypreInitialized();
}

HypreBoomerAMGPCG::~HypreBoomerAMGPCG()
{
  Free();
}

void HypreBoomerAMGPCG::Free()
{
  // The PCG (which does not own its preconditioner) and the matrix and
  // vectors, then BoomerAMG (which does not own the level-0 matrix).
  hypre::DestroyPCG(H_->PCG, H_->A, H_->B, H_->X);
  if (H_->AMG)
    HYPRE_BoomerAMGDestroy(H_->AMG);
  H_->Work.Destroy();
  H_->AMG = nullptr;
  H_->SharedAMG = nullptr;
  H_->Galerkin.reset();
  H_->Rows.clear();
  Places_.clear();
  PlacePattern_ = 0;
}

void HypreBoomerAMGPCG::BuildMatrix(
  int rowBegin, int rowEnd, const int* rowOffsets, const int* columns, const double* values)
{
  RowBegin_ = rowBegin;
  RowEnd_ = rowEnd;
  H_->A = hypre::BuildMatrix(Comm_, rowBegin, rowEnd, rowOffsets, columns, values, H_->Rows, "hypre-amg");
}

void HypreBoomerAMGPCG::Setup(
  int rowBegin, int rowEnd, const int* rowOffsets, const int* columns, const double* values)
{
  Free();
  const double start = MPI_Wtime();
  BuildMatrix(rowBegin, rowEnd, rowOffsets, columns, values);
  const double assembled = MPI_Wtime();
  MatrixMilliseconds_ = 1000.0 * (assembled - start);
  BuildSolver();
  HierarchyMilliseconds_ = 1000.0 * (MPI_Wtime() - assembled);
}

bool HypreBoomerAMGPCG::SetupShared(int rowBegin, int rowEnd, const int* rowOffsets,
  const int* columns, const double* values, const DistributedLinearSolver& donor)
{
  const auto* other = dynamic_cast<const HypreBoomerAMGPCG*>(&donor);
  if (!other || other == this || !other->H_->AMG || !other->H_->PCG ||
    other->RowBegin_ != rowBegin || other->RowEnd_ != rowEnd || !GalerkinSharable(other->H_->AMG))
  {
    return false;
  }
  Free();
  const double start = MPI_Wtime();
  BuildMatrix(rowBegin, rowEnd, rowOffsets, columns, values);
  // hypre::BuildMatrix lays out the same rows and columns the same way: the
  // donor's entry places are this matrix's when its pattern is the donor's
  // (a fingerprint pass instead of a search of every entry).
  const int rows = rowEnd - rowBegin;
  if (!other->Places_.empty() &&
    other->Places_.size() == static_cast<std::size_t>(rows > 0 ? rowOffsets[rows] : 0) &&
    hypre::PatternFingerprint(rows, rowOffsets, columns) == other->PlacePattern_)
  {
    Places_ = other->Places_;
    PlacePattern_ = other->PlacePattern_;
  }
  const double assembled = MPI_Wtime();
  MatrixMilliseconds_ = 1000.0 * (assembled - start);
  BuildSolver(other);
  HierarchyMilliseconds_ = 1000.0 * (MPI_Wtime() - assembled);
  return true;
}

void HypreBoomerAMGPCG::UpdateValues(const int* rowOffsets, const int* columns, const double* values)
{
  Handles& h = *H_;
  if (!h.A || !h.PCG)
  {
    throw Error("hypre-amg: UpdateValues() called before Setup()");
  }
  const double start = MPI_Wtime();
  // The new values go straight into the assembled ParCSR matrix (the fine
  // level of the kept hierarchy): each entry's place in the diagonal or
  // off-diagonal block is found once per pattern, then every update is a
  // scatter. (Re-initialising a matrix made with SetDiagOffdSizes and
  // setting its values through the IJ interface does not give the new
  // matrix in hypre 2.26: TestDistributedFamily's (2A)^-1 = A^-1 / 2.)
  hypre::ScatterValues(h.A, RowBegin_, RowEnd_, rowOffsets, columns, values, Places_,
    PlacePattern_, "hypre-amg");
  RefreshFineNorms(ParCSROf(h.A), FineNorms(h.AMG, h.Galerkin.get()), nullptr, 0);
  MatrixMilliseconds_ = 1000.0 * (MPI_Wtime() - start);
  HierarchyMilliseconds_ = 0.0;
}

void HypreBoomerAMGPCG::UpdateRows(const int* rowOffsets, const int* columns,
  const double* values, const int* rows, int numRows)
{
  Handles& h = *H_;
  if (!h.A || !h.PCG)
  {
    throw Error("hypre-amg: UpdateRows() called before Setup()");
  }
  const double start = MPI_Wtime();
  hypre::ScatterRows(h.A, RowBegin_, RowEnd_, rowOffsets, columns, values, rows, numRows, Places_,
    PlacePattern_, "hypre-amg");
  RefreshFineNorms(ParCSROf(h.A), FineNorms(h.AMG, h.Galerkin.get()), rows, numRows);
  MatrixMilliseconds_ = 1000.0 * (MPI_Wtime() - start);
  HierarchyMilliseconds_ = 0.0;
}

std::vector<double> HypreBoomerAMGPCG::GetFineSmootherNorms() const
{
  const hypre_Vector* fine = FineNorms(H_->AMG, H_->Galerkin.get());
  if (!fine)
    return {};
  const HYPRE_Real* data = hypre_VectorData(fine);
  return std::vector<double>(data, data + hypre_VectorSize(fine));
}

void HypreBoomerAMGPCG::PrepareUpdates(const int* rowOffsets, const int* columns)
{
  if (!H_->A)
  {
    throw Error("hypre-amg: PrepareUpdates() called before Setup()");
  }
  // Places already of this pattern (a sharer's, from its donor): kept.
  const int rows = RowEnd_ - RowBegin_;
  if (!Places_.empty() && Places_.size() == static_cast<std::size_t>(rowOffsets[rows]) &&
    hypre::PatternFingerprint(rows, rowOffsets, columns) == PlacePattern_)
  {
    return;
  }
  hypre::FindPlaces(H_->A, RowBegin_, RowEnd_, rowOffsets, columns, Places_, PlacePattern_,
    "hypre-amg");
}

void HypreBoomerAMGPCG::BuildSolver(const HypreBoomerAMGPCG* shared)
{
  Handles& h = *H_;
  const int rowBegin = RowBegin_, rowEnd = RowEnd_;
  for (HYPRE_IJVector* v : { &h.B, &h.X })
  {
    Check(HYPRE_IJVectorCreate(Comm_, rowBegin, rowEnd - 1, v), "vector creation");
    Check(HYPRE_IJVectorSetObjectType(*v, HYPRE_PARCSR), "vector type");
    Check(HYPRE_IJVectorInitialize(*v), "vector initialisation");
    Check(HYPRE_IJVectorAssemble(*v), "vector assembly");
  }
  HYPRE_ParCSRMatrix a;
  HYPRE_ParVector b, x;
  HYPRE_IJMatrixGetObject(h.A, reinterpret_cast<void**>(&a));
  HYPRE_IJVectorGetObject(h.B, reinterpret_cast<void**>(&b));
  HYPRE_IJVectorGetObject(h.X, reinterpret_cast<void**>(&x));

  auto nonZeros = [](hypre_ParCSRMatrix* m) {
    return static_cast<double>(hypre_CSRMatrixNumNonzeros(hypre_ParCSRMatrixDiag(m)) +
      hypre_CSRMatrixNumNonzeros(hypre_ParCSRMatrixOffd(m)));
  };
  if (shared)
  {
    // The donor's coarsening with this matrix's own Galerkin levels (built
    // here, collectively), its set-up otherwise the donor's (NoSetup); PCG's
    // own vectors are set up on this matrix.
    h.SharedAMG = shared->H_->AMG;
    h.Galerkin = BuildGalerkinLevels(h.SharedAMG, reinterpret_cast<hypre_ParCSRMatrix*>(a));
    Check(HYPRE_ParCSRPCGCreate(Comm_, &h.PCG), "PCG creation");
    HYPRE_PCGSetTwoNorm(h.PCG, 1);
    HYPRE_PCGSetPrintLevel(h.PCG, 0);
    HYPRE_PCGSetLogging(h.PCG, 1);
    HYPRE_PCGSetPrecond(h.PCG, reinterpret_cast<HYPRE_PtrToSolverFcn>(GalerkinSolve),
      reinterpret_cast<HYPRE_PtrToSolverFcn>(NoSetup), reinterpret_cast<HYPRE_Solver>(h.Galerkin.get()));
    Check(HYPRE_ParCSRPCGSetup(h.PCG, a, b, x), "PCG set-up");
    double local[2] = { nonZeros(reinterpret_cast<hypre_ParCSRMatrix*>(a)), 0.0 };
    for (std::size_t l = 1; l < h.Galerkin->A.size(); ++l)
      local[1] += nonZeros(h.Galerkin->A[l]);
    double total[2] = { 0.0, 0.0 };
    MPI_Allreduce(local, total, 2, MPI_DOUBLE, MPI_SUM, Comm_);
    NonZeros_ = static_cast<long long>(total[0]);
    Levels_ = shared->Levels_;
    OperatorComplexity_ = total[0] > 0 ? (total[0] + total[1]) / total[0] : 0.0;
    IterationWork_ = shared->IterationWork_;
    MemoryBytes_ = static_cast<std::size_t>(local[1] * 12.0); // own levels; P is the donor's
    return;
  }
  Check(HYPRE_BoomerAMGCreate(&h.AMG), "BoomerAMG creation");
  HYPRE_BoomerAMGSetPrintLevel(h.AMG, 0);
  const BoomerAMGOptions& o = Options_; // defaults: hypre's 3-D diffusion recommendations
  HYPRE_BoomerAMGSetCoarsenType(h.AMG, o.CoarsenType);
  HYPRE_BoomerAMGSetInterpType(h.AMG, o.InterpType);
  HYPRE_BoomerAMGSetPMaxElmts(h.AMG, o.PMaxElmts);
  HYPRE_BoomerAMGSetStrongThreshold(h.AMG, o.StrongThreshold);
  HYPRE_BoomerAMGSetRelaxType(h.AMG, o.RelaxType);
  HYPRE_BoomerAMGSetNumSweeps(h.AMG, o.NumSweeps);
  if (o.RelaxDown >= 0)
    HYPRE_BoomerAMGSetCycleRelaxType(h.AMG, o.RelaxDown, 1);
  if (o.RelaxUp >= 0)
    HYPRE_BoomerAMGSetCycleRelaxType(h.AMG, o.RelaxUp, 2);
  if (o.AggNumLevels > 0)
  {
    HYPRE_BoomerAMGSetAggNumLevels(h.AMG, o.AggNumLevels);
    HYPRE_BoomerAMGSetAggInterpType(h.AMG, o.AggInterpType);
  }
  if (o.KeepTranspose)
  {
    HYPRE_BoomerAMGSetKeepTranspose(h.AMG, 1);
  }
  HYPRE_BoomerAMGSetTol(h.AMG, 0.0);
  HYPRE_BoomerAMGSetMaxIter(h.AMG, 1); // one V-cycle per application
  Check(HYPRE_ParCSRPCGCreate(Comm_, &h.PCG), "PCG creation");
  HYPRE_PCGSetTwoNorm(h.PCG, 1);
  HYPRE_PCGSetPrintLevel(h.PCG, 0);
  HYPRE_PCGSetLogging(h.PCG, 1);
  HYPRE_PCGSetPrecond(h.PCG, reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSolve),
    reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSetup), h.AMG);
  Check(HYPRE_ParCSRPCGSetup(h.PCG, a, b, x), "BoomerAMG set-up");

  // Work and memory of the hierarchy (summed over the ranks).
  auto* amg = reinterpret_cast<hypre_ParAMGData*>(h.AMG);
  Levels_ = hypre_ParAMGDataNumLevels(amg);
  double local[3] = { 0.0, 0.0, 0.0 }; // nnz(A_0), sum nnz(A_l), sum nnz(P_l)
  for (int l = 0; l < Levels_; ++l)
  {
    const double nz = nonZeros(hypre_ParAMGDataAArray(amg)[l]);
    if (l == 0)
      local[0] = nz;
    local[1] += nz;
    if (l + 1 < Levels_ && hypre_ParAMGDataPArray(amg)[l])
      local[2] += nonZeros(hypre_ParAMGDataPArray(amg)[l]);
  }
  double total[3];
  MPI_Allreduce(local, total, 3, MPI_DOUBLE, MPI_SUM, Comm_);
  OperatorComplexity_ = total[0] > 0 ? total[1] / total[0] : 0.0;
  NonZeros_ = static_cast<long long>(total[0]);
  IterationWork_ = total[0] > 0 ? 1.0 + (3.0 * total[1] + 2.0 * total[2]) / total[0] : 0.0;
  MemoryBytes_ = static_cast<std::size_t>((local[1] - local[0] + local[2]) * 12.0);
  RefreshFineNorms(
    reinterpret_cast<hypre_ParCSRMatrix*>(a), FineNorms(h.AMG, nullptr), nullptr, 0);
}

int HypreBoomerAMGPCG::Solve(
  const double* bLocal, double* xLocal, bool guess, double relTol, int maxIter, double& relRes)
{
  Handles& h = *H_;
  if (!h.PCG)
  {
    throw Error("hypre-amg: Solve() called before Setup()");
  }
  return hypre::SolvePCG(h.PCG, h.A, h.B, h.X, h.Rows, bLocal, xLocal, guess, relTol, maxIter,
    relRes, "hypre-amg");
}

void HypreBoomerAMGPCG::SumOverRanks(double* values, int count) const
{
  MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_DOUBLE, MPI_SUM, Comm_);
}

void HypreBoomerAMGPCG::SolveChannels(
  const std::array<DistributedLinearSolver*, NumberOfChannels>& solvers,
  const std::array<const double*, NumberOfChannels>& b, const std::array<double*, NumberOfChannels>& x,
  const std::array<bool, NumberOfChannels>& guess, const DistributedSolveControl& control,
  std::array<DistributedChannelStats, NumberOfChannels>& stats)
{
  // The same on every rank: the solvers' kinds, and whether they are set up.
  std::array<HypreBoomerAMGPCG*, NumberOfChannels> own{};
  std::array<HYPRE_IJMatrix, NumberOfChannels> matrices{};
  std::array<hypre::ChannelWork*, NumberOfChannels> work{};
  std::array<HYPRE_Solver, NumberOfChannels> amg{};
  std::array<GalerkinLevels*, NumberOfChannels> galerkin{};
  bool ours = true;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    if (!solvers[c])
      continue;
    own[c] = dynamic_cast<HypreBoomerAMGPCG*>(solvers[c]);
    if (!own[c] || !own[c]->H_->PCG)
    {
      ours = false;
      break;
    }
    if (own[c]->RowBegin_ != RowBegin_ || own[c]->RowEnd_ != RowEnd_)
    {
      throw Error("hypre-amg: SolveChannels() with channels on other rows");
    }
    matrices[c] = own[c]->H_->A;
    work[c] = &own[c]->H_->Work;
    amg[c] = own[c]->H_->AMG ? own[c]->H_->AMG : own[c]->H_->SharedAMG;
    galerkin[c] = own[c]->H_->AMG ? nullptr : own[c]->H_->Galerkin.get();
  }
  if (!ours)
  {
    SolveChannelsOneByOne(solvers, b, x, guess, control, stats);
    return;
  }
  hypre::SolveChannels(Comm_, matrices, work,
    [&amg, &galerkin](int c, HYPRE_ParCSRMatrix a, HYPRE_ParVector r, HYPRE_ParVector z) {
      return galerkin[c] ? GalerkinSolve(reinterpret_cast<HYPRE_Solver>(galerkin[c]), a, r, z)
                         : HYPRE_BoomerAMGSolve(amg[c], a, r, z);
    },
    b, x, guess, control, stats, "hypre-amg");
}

HypreSolver::HypreSolver() = default;
HypreSolver::~HypreSolver() = default;

void HypreSolver::SetupValues(const DiffusionSystem& system, const TetMesh*)
{
  const int n = system.NumberOfUnknowns;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    if (!Channels_[c])
      Channels_[c] = std::make_unique<HypreBoomerAMGPCG>(MPI_COMM_SELF);
    Channels_[c]->Setup(0, n, system.RowOffsets.data(), system.ColumnIndices.data(),
      system.Values[c].data());
  }
}

bool HypreSolver::Solve(const DiffusionSystem& system,
  std::array<Eigen::VectorXd, NumberOfChannels>& x, bool warmStart,
  std::array<LinearSolveStats, NumberOfChannels>& stats)
{
  CheckLinearSystem(system, "hypre-amg");
  if (!IsSetUpFor(system))
  {
    throw Error("hypre-amg: Solve() called without a Setup() for this system");
  }
  const int n = system.NumberOfUnknowns;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    stats[c] = LinearSolveStats();
    if (!ReportProgress(static_cast<double>(c) / NumberOfChannels))
    {
      return false;
    }
    const Eigen::VectorXd& b = system.RightHandSide[c];
    const bool guess = warmStart && x[c].size() == n;
    if (!guess)
      x[c].setZero(n);
    if (b.squaredNorm() == 0.0)
    {
      x[c].setZero(n);
      stats[c].Converged = true;
      continue;
    }
    double residual = 0.0;
    const int iterations =
      Channels_[c]->Solve(b.data(), x[c].data(), guess, RelTol_, MaxIter_, residual);
    stats[c].Iterations = iterations;
    stats[c].RelativeResidual = residual;
    stats[c].Converged = residual <= RelTol_;
    // The initial residual, then per iteration one SpMV and one V-cycle.
    stats[c].SpMVEquivalents = 1.0 + iterations * Channels_[c]->GetSpMVEquivalentsPerIteration();
  }
  ReportProgress(1.0);
  return true;
}

std::size_t HypreSolver::GetMemoryBytes() const
{
  std::size_t bytes = 0;
  for (const auto& ch : Channels_)
    if (ch)
      bytes += ch->GetMemoryBytes();
  return bytes;
}

} // namespace translucency
