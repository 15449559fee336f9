/**
 * @file CholmodSolver.h
 * @brief The "cholmod" linear solver: a sparse direct Cholesky factorisation
 * (SuiteSparse CHOLMOD) per channel, the bench's direct reference.
 */
#pragma once

#include "LinearSolver.h"

#include <memory>

namespace translucency
{

/**
 * CHOLMOD supernodal Cholesky (its default fill-reducing ordering; BLAS does
 * the dense work, so use an optimised BLAS such as OpenBLAS). Setup() with a
 * changed pattern runs the symbolic analysis (ordering, elimination tree,
 * supernodes) once for the shared pattern and then the numeric factorisation
 * of each channel; with values only it reuses the analysis and refactorises.
 * Solve() is a forward and a backward substitution per channel (warm start is
 * meaningless for a direct solve and ignored); the statistics give the true
 * relative residual, computed with one SpMV.
 */
class CholmodSolver : public LinearSolver
{
public:
  CholmodSolver();
  ~CholmodSolver() override;

  std::string GetName() const override { return "cholmod"; }
  bool Solve(const DiffusionSystem& system, std::array<Eigen::VectorXd, NumberOfChannels>& x,
    bool warmStart, std::array<LinearSolveStats, NumberOfChannels>& stats) override;
  std::size_t GetMemoryBytes() const override;

  /// Nonzeros of the Cholesky factor of channel c (0 before Setup()).
  double GetFactorNonZeros(int c) const;

protected:
  /// Symbolic analysis (ordering, factor pattern) of the shared pattern.
  void SetupStructure(const DiffusionSystem& system, const TetMesh* mesh) override;
  /// Numeric factorisation of each channel.
  void SetupValues(const DiffusionSystem& system, const TetMesh* mesh) override;

private:
  struct Internals;
  std::unique_ptr<Internals> Internals_;
};

} // namespace translucency
