#include "ConjugateGradient.h"

#include "Error.h"

#include <Eigen/IterativeLinearSolvers>

#include <cmath>
#include <sstream>

namespace translucency
{

namespace
{

/// The pattern arrays must describe an n x n CSR matrix with nnz entries.
void CheckSystem(const DiffusionSystem& system)
{
  const int n = system.NumberOfUnknowns;
  const size_t nnz = system.ColumnIndices.size();
  bool ok = n >= 0 && system.RowOffsets.size() == static_cast<size_t>(n) + 1 &&
    system.RowOffsets.front() == 0 && static_cast<size_t>(system.RowOffsets.back()) == nnz;
  for (int c = 0; ok && c < NumberOfChannels; ++c)
  {
    ok = system.Values[c].size() == nnz && system.RightHandSide[c].size() == n;
  }
  if (!ok)
  {
    std::ostringstream os;
    os << "ConjugateGradient: inconsistent system (" << n << " unknowns, "
       << system.RowOffsets.size() << " row offsets, " << nnz << " column indices, values "
       << system.Values[0].size() << "/" << system.Values[1].size() << "/"
       << system.Values[2].size() << ", right-hand sides " << system.RightHandSide[0].size() << "/"
       << system.RightHandSide[1].size() << "/" << system.RightHandSide[2].size() << ")";
    throw Error(os.str());
  }
}

} // namespace

bool ConjugateGradient::Solve(const DiffusionSystem& system,
  std::array<Eigen::VectorXd, NumberOfChannels>& x,
  bool warmStart)
{
  CheckSystem(system);
  Iterations_.fill(0);
  FinalNorm_.fill(0.0);
  Converged_.fill(false);
  const int n = system.NumberOfUnknowns;

  // Eigen binds the Map to a Ref<const SparseMatrix> without copying;
  // Lower|Upper makes it use the full row-major product, which Eigen runs on
  // OpenMP threads.
  using Matrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
  Eigen::
    ConjugateGradient<Matrix, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>>
      solver;
  solver.setTolerance(RelTol_);
  solver.setMaxIterations(MaxIter_);

  for (int c = 0; c < NumberOfChannels; ++c)
  {
    if (Progress_ && !Progress_(static_cast<double>(c) / NumberOfChannels))
    {
      return false;
    }
    const Eigen::VectorXd& b = system.RightHandSide[c];
    const bool guess = warmStart && x[c].size() == n;
    if (!guess)
    {
      x[c].setZero(n);
    }
    if (b.squaredNorm() == 0.0)
    {
      // M is SPD: the solution is exactly zero.
      x[c].setZero(n);
      Converged_[c] = true;
      continue;
    }
    solver.compute(system.Matrix(c));
    if (solver.info() != Eigen::Success)
    {
      std::ostringstream os;
      os << "ConjugateGradient: the preconditioner of channel " << c
         << " could not be built (zero or non-finite diagonal?)";
      throw Error(os.str());
    }
    if (guess)
    {
      const Eigen::VectorXd x0 = x[c];
      x[c] = solver.solveWithGuess(b, x0);
    }
    else
    {
      x[c] = solver.solve(b);
    }
    Iterations_[c] = static_cast<int>(solver.iterations());
    FinalNorm_[c] = solver.error();
    Converged_[c] = solver.info() == Eigen::Success && std::isfinite(FinalNorm_[c]) &&
      x[c].allFinite(); // never converged on a NaN/inf residual
  }
  if (Progress_)
  {
    Progress_(1.0);
  }
  return true;
}

} // namespace translucency
