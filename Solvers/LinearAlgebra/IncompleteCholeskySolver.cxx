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
  bool Analysed = false;
  int NumberOfUnknowns = -1;
  std::size_t NonZeros = 0;
};

IncompleteCholeskySolver::IncompleteCholeskySolver()
  : Internals_(std::make_unique<Internals>())
{
}

IncompleteCholeskySolver::~IncompleteCholeskySolver() = default;

void IncompleteCholeskySolver::Setup(const DiffusionSystem& system, const TetMesh*, bool patternChanged)
{
  CheckLinearSystem(system, "cg-ichol");
  Internals& in = *Internals_;
  const bool analyse = patternChanged || !in.Analysed ||
    in.NumberOfUnknowns != system.NumberOfUnknowns || in.NonZeros != system.ColumnIndices.size();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    // The matrix is symmetric, so its CSR arrays are also its CSC arrays:
    // a column-major map of them is the same matrix, which is what
    // IncompleteCholesky reads.
    const Eigen::Map<const Eigen::SparseMatrix<double, Eigen::ColMajor, int>> a(
      system.NumberOfUnknowns, system.NumberOfUnknowns,
      static_cast<int>(system.ColumnIndices.size()), system.RowOffsets.data(),
      system.ColumnIndices.data(), system.Values[c].data());
    if (analyse)
    {
      in.Factor[c].analyzePattern(a);
    }
    in.Factor[c].factorize(a);
    if (in.Factor[c].info() != Eigen::Success)
    {
      std::ostringstream os;
      os << "cg-ichol: the incomplete Cholesky factorisation of channel " << c
         << " failed (matrix not positive definite or not finite?)";
      throw Error(os.str());
    }
  }
  in.Analysed = true;
  in.NumberOfUnknowns = system.NumberOfUnknowns;
  in.NonZeros = system.ColumnIndices.size();
}

bool IncompleteCholeskySolver::Solve(const DiffusionSystem& system,
  std::array<Eigen::VectorXd, NumberOfChannels>& x, bool warmStart,
  std::array<LinearSolveStats, NumberOfChannels>& stats)
{
  Internals& in = *Internals_;
  CheckLinearSystem(system, "cg-ichol");
  if (!in.Analysed || in.NumberOfUnknowns != system.NumberOfUnknowns ||
    in.NonZeros != system.ColumnIndices.size())
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
    stats[c].Converged = r2 <= threshold;
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
  if (Internals_->Analysed)
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
