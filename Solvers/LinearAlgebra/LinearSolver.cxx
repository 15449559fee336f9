#include "LinearSolver.h"

#include <cmath>
#include <string>

#include "Error.h"
#include "LinearSolverCommon.h"

namespace translucency
{

// ---- LinearSolver ----

void LinearSolver::CheckSetup(const DiffusionSystem& system, const TetMesh*) const
{
  CheckLinearSystem(system, GetName());
}

void LinearSolver::ApplyPreconditioner(const double*, double*) const
{
  throw Error(GetName() + ": has no preconditioner to apply (HasPreconditioner() is false)");
}

void LinearSolver::Setup(const DiffusionSystem& system, const TetMesh* mesh, bool patternChanged)
{
  CheckSetup(system, mesh);
  // Rebuild unless the caller promises the same pattern and the last Setup
  // succeeded for a system of this size (model: PETSc's PCSetUp).
  const bool rebuild = patternChanged || !IsSetUpFor(system);
  Ready_ = false; // a Setup that throws leaves the solver not ready
  if (rebuild)
  {
    SetupStructure(system, mesh);
  }
  SetupValues(system, mesh);
  Unknowns_ = system.NumberOfUnknowns;
  NonZeros_ = system.ColumnIndices.size();
  Ready_ = true;
}

void LinearSolver::SetupChangedRows(
  const DiffusionSystem& system, const TetMesh* mesh, const std::vector<int>& rows)
{
  if (!IsSetUpFor(system))
  {
    Setup(system, mesh, true);
    return;
  }
  CheckSetup(system, mesh);
  for (const int i : rows)
  {
    if (i < 0 || i >= system.NumberOfUnknowns)
    {
      throw Error(GetName() + ": changed row " + std::to_string(i) + " is out of range (the system has " +
        std::to_string(system.NumberOfUnknowns) + " unknowns)");
    }
  }
  Ready_ = false; // a set-up that throws leaves the solver not ready
  SetupRows(system, mesh, rows);
  Ready_ = true;
}

// ---- ChannelLinearSolver ----

bool ChannelLinearSolver::Solve(const DiffusionSystem& system,
  std::array<Eigen::VectorXd, NumberOfChannels>& x,
  bool warmStart,
  std::array<LinearSolveStats, NumberOfChannels>& stats)
{
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    const double base = static_cast<double>(c) / NumberOfChannels;
    if (!ReportProgress(base) ||
      !SolveChannel(system, c, x[c], warmStart, stats[c], base, 1.0 / NumberOfChannels))
    {
      return false;
    }
  }
  return true;
}

bool ChannelLinearSolver::SolveChannel(const DiffusionSystem& system,
  int c,
  Eigen::VectorXd& x,
  bool warmStart,
  LinearSolveStats& stats,
  double progressBase,
  double progressSpan)
{
  const int n = system.NumberOfUnknowns;
  stats = LinearSolveStats();
  if (!warmStart || x.size() != n)
  {
    x.setZero(n);
  }
  const double bNorm = system.RightHandSide[c].norm();
  if (bNorm == 0.0)
  {
    x.setZero(n); // the matrix is regular: x = 0
    stats.Converged = true;
    return true;
  }
  const auto progress = [&](int iterations)
  { return ReportProgress(progressBase + progressSpan * iterations / MaxIter_); };
  const bool completed = Iterate(system, c, x, bNorm, stats, progress);
  if (!std::isfinite(bNorm) || !std::isfinite(stats.RelativeResidual) || !x.allFinite())
  {
    stats.Converged = false; // never report convergence on a NaN/inf residual or solution
  }
  return completed;
}

} // namespace translucency
