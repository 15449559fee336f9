#include "CholmodSolver.h"

#include "Error.h"
#include "LinearSolverCommon.h"

#include <cholmod.h>

#include <cstring>
#include <sstream>

namespace translucency
{

struct CholmodSolver::Internals
{
  cholmod_common Common;
  std::array<cholmod_factor*, NumberOfChannels> Factor{};
  double FactorNonZeros = 0.0; ///< nnz(L) of the analysis (the same for every channel)

  Internals()
  {
    cholmod_start(&Common);
    Common.print = 0; // no messages on stdout/stderr: errors are thrown instead
  }
  ~Internals()
  {
    FreeFactors();
    cholmod_finish(&Common);
  }
  void FreeFactors()
  {
    for (auto& f : Factor)
    {
      if (f)
      {
        cholmod_free_factor(&f, &Common);
      }
    }
  }
};

namespace
{

/// Channel c of the system as a CHOLMOD matrix without copying: the matrix
/// is symmetric, so its CSR arrays are its CSC arrays; stype = 1 makes
/// CHOLMOD read the upper triangle only.
cholmod_sparse Wrap(const DiffusionSystem& system, int c)
{
  cholmod_sparse a;
  std::memset(&a, 0, sizeof(a));
  a.nrow = a.ncol = static_cast<size_t>(system.NumberOfUnknowns);
  a.nzmax = system.ColumnIndices.size();
  a.p = const_cast<int*>(system.RowOffsets.data());
  a.i = const_cast<int*>(system.ColumnIndices.data());
  a.x = const_cast<double*>(system.Values[c].data());
  a.stype = 1;
  a.itype = CHOLMOD_INT;
  a.xtype = CHOLMOD_REAL;
  a.dtype = CHOLMOD_DOUBLE;
  a.sorted = 1;
  a.packed = 1;
  return a;
}

cholmod_dense WrapVector(double* data, int n)
{
  cholmod_dense d;
  std::memset(&d, 0, sizeof(d));
  d.nrow = d.d = d.nzmax = static_cast<size_t>(n);
  d.ncol = 1;
  d.x = data;
  d.xtype = CHOLMOD_REAL;
  d.dtype = CHOLMOD_DOUBLE;
  return d;
}

} // namespace

CholmodSolver::CholmodSolver()
  : Internals_(std::make_unique<Internals>())
{
}

CholmodSolver::~CholmodSolver() = default;

void CholmodSolver::SetupStructure(const DiffusionSystem& system, const TetMesh*)
{
  Internals& in = *Internals_;
  {
    // Symbolic analysis once for the shared pattern, copied per channel.
    in.FreeFactors();
    cholmod_sparse a = Wrap(system, 0);
    in.Factor[0] = cholmod_analyze(&a, &in.Common);
    if (!in.Factor[0])
    {
      std::ostringstream os;
      os << "cholmod: symbolic analysis of the " << system.NumberOfUnknowns
         << "-unknown system failed (CHOLMOD status " << in.Common.status << ")";
      throw Error(os.str());
    }
    in.FactorNonZeros = in.Common.lnz;
    for (int c = 1; c < NumberOfChannels; ++c)
    {
      in.Factor[c] = cholmod_copy_factor(in.Factor[0], &in.Common);
    }
  }
}

void CholmodSolver::SetupValues(const DiffusionSystem& system, const TetMesh*)
{
  Internals& in = *Internals_;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    cholmod_sparse a = Wrap(system, c);
    const int ok = cholmod_factorize(&a, in.Factor[c], &in.Common);
    if (!ok || in.Common.status != CHOLMOD_OK)
    {
      std::ostringstream os;
      os << "cholmod: numeric factorisation of channel " << c << " failed";
      if (in.Common.status == CHOLMOD_NOT_POSDEF)
      {
        os << ": the matrix is not positive definite (pivot of column "
           << in.Factor[c]->minor << " in CHOLMOD's ordering)";
      }
      else
      {
        os << " (CHOLMOD status " << in.Common.status << ")";
      }
      in.FreeFactors();
      throw Error(os.str());
    }
  }
}

bool CholmodSolver::Solve(const DiffusionSystem& system,
  std::array<Eigen::VectorXd, NumberOfChannels>& x, bool,
  std::array<LinearSolveStats, NumberOfChannels>& stats)
{
  Internals& in = *Internals_;
  CheckLinearSystem(system, "cholmod");
  if (!IsSetUpFor(system) || !in.Factor[0])
  {
    throw Error("cholmod: Solve() called without a Setup() for this system");
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
    const double bNorm = b.norm();
    if (bNorm == 0.0)
    {
      x[c].setZero(n);
      stats[c].Converged = true;
      continue;
    }
    cholmod_dense bd = WrapVector(const_cast<double*>(b.data()), n);
    cholmod_dense* xd = cholmod_solve(CHOLMOD_A, in.Factor[c], &bd, &in.Common);
    if (!xd)
    {
      std::ostringstream os;
      os << "cholmod: solve of channel " << c << " failed (CHOLMOD status " << in.Common.status
         << ")";
      throw Error(os.str());
    }
    x[c] = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(xd->x), n);
    cholmod_free_dense(&xd, &in.Common);
    stats[c].RelativeResidual = (b - system.Matrix(c) * x[c]).norm() / bNorm;
    stats[c].Converged = stats[c].RelativeResidual <= RelTol_;
    // Forward and backward substitution use each of the factor's nonzeros
    // once, plus the residual check.
    stats[c].SpMVEquivalents = 1.0 + 2.0 * GetFactorNonZeros(c) / system.ColumnIndices.size();
  }
  ReportProgress(1.0);
  return true;
}

double CholmodSolver::GetFactorNonZeros(int c) const
{
  return Internals_->Factor[c] ? Internals_->FactorNonZeros : 0.0;
}

std::size_t CholmodSolver::GetMemoryBytes() const
{
  std::size_t bytes = 0;
  for (const cholmod_factor* f : Internals_->Factor)
  {
    if (f)
    {
      // Supernodal: xsize values; simplicial: nzmax values and row indices.
      bytes += f->is_super ? f->xsize * sizeof(double) + f->ssize * sizeof(int)
                           : f->nzmax * (sizeof(double) + sizeof(int));
    }
  }
  return bytes;
}

} // namespace translucency
