/**
 * @file IncompleteCholeskySolver.h
 * @brief The "cg-ichol" linear solver: Eigen's conjugate gradient with
 * Eigen's IncompleteCholesky preconditioner (AMD ordering, one factor per
 * channel), a peer the bench compares against.
 */
#pragma once

#include "LinearSolver.h"

#include <memory>

namespace translucency
{

/**
 * Eigen CG + IncompleteCholesky<double, Lower, AMDOrdering>. Setup() with a
 * changed pattern recomputes the ordering and the factors; with values only
 * it keeps the ordering (Eigen's analyzePattern) and refactorises. The
 * triangular solves of the preconditioner are serial (Eigen); the SpMV runs
 * on OpenMP threads.
 */
class IncompleteCholeskySolver : public LinearSolver
{
public:
  IncompleteCholeskySolver();
  ~IncompleteCholeskySolver() override;

  std::string GetName() const override { return "cg-ichol"; }
  bool Solve(const DiffusionSystem& system, std::array<Eigen::VectorXd, NumberOfChannels>& x,
    bool warmStart, std::array<LinearSolveStats, NumberOfChannels>& stats) override;
  std::size_t GetMemoryBytes() const override;

protected:
  /// The AMD ordering and pattern of the factor (analyzePattern).
  void SetupStructure(const DiffusionSystem& system, const TetMesh* mesh) override;
  /// The numeric factorisation of each channel.
  void SetupValues(const DiffusionSystem& system, const TetMesh* mesh) override;

private:
  struct Internals;
  std::unique_ptr<Internals> Internals_;
};

} // namespace translucency
