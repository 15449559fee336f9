#include "IncompleteCholeskySolver.h"

#include "Error.h"
#include "LinearSolverCommon.h"

#include <Eigen/IterativeLinearSolvers>

#include <cmath>
#include <sstream>

namespace translucency
{

using ICholPreconditioner = Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>;

struct IncompleteCholeskySolver::Internals
{
  std::array<ICholPreconditioner, NumberOfChannels> Factor;
};

IncompleteCholeskySolver::IncompleteCholeskySolver()
  : Internals_(std::make_unique<Internals>())
{
}

IncompleteCholeskySolver::~IncompleteCholeskySolver() = default;

namespace
{
/// The matrix is symmetric, so its CSR arrays are also its CSC arrays: a
/// column-major map of them is the same matrix, which is what
/// IncompleteCholesky reads.
Eigen::Map<const Eigen::SparseMatrix<double, Eigen::ColMajor, int>> ColumnMajor(
  const DiffusionSystem& system, int c)
{
  return Eigen::Map<const Eigen::SparseMatrix<double, Eigen::ColMajor, int>>(
    system.NumberOfUnknowns, system.NumberOfUnknowns,
    static_cast<int>(system.ColumnIndices.size()), system.RowOffsets.data(),
    system.ColumnIndices.data(), system.Values[c].data());
}
} // namespace

void IncompleteCholeskySolver::SetupStructure(const DiffusionSystem& system, const TetMesh*)
{
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    Internals_->Factor[c].analyzePattern(ColumnMajor(system, c));
  }
}

void IncompleteCholeskySolver::SetupValues(const DiffusionSystem& system, const TetMesh*)
{
  Internals& in = *Internals_;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    in.Factor[c].factorize(ColumnMajor(system, c));
    if (in.Factor[c].info() != Eigen::Success)
    {
      std::ostringstream os;
      os << "cg-ichol: the incomplete Cholesky factorisation of channel " << c
         << " failed (matrix not positive definite or not finite?)";
      throw Error(os.str());
    }
  }
}

bool IncompleteCholeskySolver::Solve(const DiffusionSystem& system,
  std::array<Eigen::VectorXd, NumberOfChannels>& x, bool warmStart,
  std::array<LinearSolveStats, NumberOfChannels>& stats)
{
  Internals& in = *Internals_;
  CheckLinearSystem(system, "cg-ichol");
  if (!IsSetUpFor(system))
  {
    throw Error("cg-ichol: Solve() called without a Setup() for this system");
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
    if (!(warmStart && x[c].size() == n))
    {
      x[c].setZero(n);
    }
    if (b.squaredNorm() == 0.0)
    {
      x[c].setZero(n); // M is SPD: the solution is exactly zero
      stats[c].Converged = true;
      continue;
    }
    // Preconditioned CG (as Eigen's internal::conjugate_gradient, but
    // counting every iteration done, including the one that converges).
    const SparseMatrixMap m = system.Matrix(c);
    const ICholPreconditioner& ic = in.Factor[c];
    const double threshold = RelTol_ * RelTol_ * b.squaredNorm();
    Eigen::VectorXd r = b - m * x[c]; // full row-major product: OpenMP threads
    double r2 = r.squaredNorm();
    int iterations = 0;
    if (r2 > threshold)
    {
      Eigen::VectorXd z = ic.solve(r), p = z, q(n);
      double rz = r.dot(z);
      while (iterations < MaxIter_)
      {
        q.noalias() = m * p;
        const double alpha = rz / p.dot(q);
        x[c] += alpha * p;
        r -= alpha * q;
        r2 = r.squaredNorm();
        ++iterations;
        if (r2 <= threshold)
          break;
        z = ic.solve(r);
        const double rzOld = rz;
        rz = r.dot(z);
        p = z + (rz / rzOld) * p;
      }
    }
    stats[c].Iterations = iterations;
    stats[c].RelativeResidual = std::sqrt(r2 / b.squaredNorm());
    // Never converged on a NaN/inf residual (inf <= inf for an overflowed b).
    stats[c].Converged =
      r2 <= threshold && std::isfinite(r2) && std::isfinite(threshold) && x[c].allFinite();
    // The initial residual, then per iteration one SpMV and one solve with
    // L and L^T (the first before the loop, none after the last), which use
    // each of the nnz(L) entries once: 2 nnz(L) / nnz(M) SpMV-equivalents.
    const double factorRatio =
      2.0 * static_cast<double>(ic.matrixL().nonZeros()) / system.ColumnIndices.size();
    stats[c].SpMVEquivalents = 1.0 + iterations * (1.0 + factorRatio);
  }
  ReportProgress(1.0);
  return true;
}

std::size_t IncompleteCholeskySolver::GetMemoryBytes() const
{
  std::size_t bytes = 0;
  if (Ready_)
  {
    for (const auto& f : Internals_->Factor)
    {
      bytes += f.matrixL().nonZeros() * (sizeof(double) + sizeof(int)) +
        2 * f.permutationP().size() * sizeof(int) + f.scalingS().size() * sizeof(double);
    }
  }
  return bytes;
}

} // namespace translucency
