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

using Matrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
using JacobiCG =
  Eigen::ConjugateGradient<Matrix, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>>;

/// Builds the diagonal preconditioner of channel c into `solver`.
void ComputePreconditioner(JacobiCG& solver, const DiffusionSystem& system, int c)
{
  solver.compute(system.Matrix(c));
  if (solver.info() != Eigen::Success)
  {
    std::ostringstream os;
    os << "ConjugateGradient: the preconditioner of channel " << c
       << " could not be built (zero or non-finite diagonal?)";
    throw Error(os.str());
  }
}

} // namespace

/// The preconditioners of Prepare and the value arrays they belong to.
struct ConjugateGradient::Prepared
{
  std::array<JacobiCG, NumberOfChannels> Solvers;
  std::array<const double*, NumberOfChannels> Values{};
  const int* RowOffsets = nullptr;
  const int* ColumnIndices = nullptr;
  int Unknowns = -1;
  std::size_t NonZeros = 0;

  bool Matches(const DiffusionSystem& system, int c) const
  {
    return Unknowns == system.NumberOfUnknowns && NonZeros == system.ColumnIndices.size() &&
      Values[c] == system.Values[c].data() && RowOffsets == system.RowOffsets.data() &&
      ColumnIndices == system.ColumnIndices.data();
  }
};

ConjugateGradient::ConjugateGradient() = default;
ConjugateGradient::~ConjugateGradient() = default;
ConjugateGradient::ConjugateGradient(ConjugateGradient&&) noexcept = default;
ConjugateGradient& ConjugateGradient::operator=(ConjugateGradient&&) noexcept = default;

void ConjugateGradient::Prepare(const DiffusionSystem& system)
{
  CheckSystem(system);
  Prepared_.reset();
  auto prepared = std::make_unique<Prepared>();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    ComputePreconditioner(prepared->Solvers[c], system, c);
    prepared->Values[c] = system.Values[c].data();
  }
  prepared->RowOffsets = system.RowOffsets.data();
  prepared->ColumnIndices = system.ColumnIndices.data();
  prepared->Unknowns = system.NumberOfUnknowns;
  prepared->NonZeros = system.ColumnIndices.size();
  Prepared_ = std::move(prepared);
}

std::size_t ConjugateGradient::GetMemoryBytes() const
{
  return Prepared_ ? NumberOfChannels * static_cast<std::size_t>(Prepared_->Unknowns) *
      sizeof(double)
                   : 0;
}

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
  JacobiCG own;

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
    const bool prepared = Prepared_ && Prepared_->Matches(system, c);
    JacobiCG& solver = prepared ? Prepared_->Solvers[c] : own;
    if (!prepared)
    {
      ComputePreconditioner(solver, system, c);
    }
    solver.setTolerance(RelTol_);
    solver.setMaxIterations(MaxIter_);
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
    bool success = solver.info() == Eigen::Success;
    if (Iterations_[c] < MinIter_ && FinalNorm_[c] > 0.0 && solver.info() == Eigen::Success)
    {
      // Within RelTol before MinIter iterations (a warm start): the
      // remaining iterations with no tolerance, from where it stopped.
      solver.setTolerance(0.0);
      solver.setMaxIterations(MinIter_ - Iterations_[c]);
      const Eigen::VectorXd x0 = x[c];
      x[c] = solver.solveWithGuess(b, x0);
      Iterations_[c] += static_cast<int>(solver.iterations());
      FinalNorm_[c] = solver.error();
      success = FinalNorm_[c] <= RelTol_; // no tolerance: judged against RelTol
    }
    Converged_[c] = success && std::isfinite(FinalNorm_[c]) &&
      x[c].allFinite(); // never converged on a NaN/inf residual
  }
  if (Progress_)
  {
    Progress_(1.0);
  }
  return true;
}

} // namespace translucency
