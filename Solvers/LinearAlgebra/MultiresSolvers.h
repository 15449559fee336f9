/**
 * @file MultiresSolvers.h
 * @brief The two linear solvers built on the TransCut multiresolution
 * hierarchy (MultiresHierarchy.h), both selectable through
 * CreateLinearSolver():
 *
 * - "transcut-multires": the paper's scheme (TransCut Sec. 4.2): coarse
 *   operators by substituting eq. 16 into eq. 15 (eq. 17, non-symmetric),
 *   b^{l+1} = b^l on the retained vertices, BiCGSTAB on the coarsest level,
 *   interpolation (eq. 16) to the next finer level as its initial guess,
 *   BiCGSTAB there, ..., Jacobi-CG on level 0. A warm start skips the coarse
 *   levels (the previous solution is a better guess than any coarse one).
 * - "multigrid-cg": beyond the paper, the same hierarchy as a symmetric
 *   V-cycle preconditioner for CG on level 0: prolongation P = eq. 16,
 *   restriction P^T, Galerkin coarse operators P^T A P, Chebyshev smoothing
 *   (polynomial in D^-1 A, the same before and after the coarse correction,
 *   so the preconditioner is SPD), a sparse LDL^T solve on the coarsest level.
 *   The preconditioner holds single-precision matrix values; CG itself is
 *   double precision.
 *
 * Both solve the three channels together: one pass over the shared pattern
 * per matrix-vector product (vectors interleaved per vertex).
 */
#pragma once

#include "LinearSolver.h"
#include "MultiresHierarchy.h"

#include <Eigen/SparseCore>

#include <memory>

namespace translucency
{

/// Common part: hierarchy set-up and the shared options.
class MultiresLinearSolverBase : public LinearSolver
{
public:
  ///@{
  /// Hierarchy levels including level 0 (0 = automatic, default) and the
  /// automatic stop size (default 1000 vertices).
  void SetMaxLevels(int n) { Hierarchy_.SetMaxLevels(n); }
  void SetCoarsestSize(int n) { Hierarchy_.SetCoarsestSize(n); }
  ///@}
  /// OpenMP threads of the hierarchy build (0 = default, 1 = serial).
  void SetNumberOfThreads(int n) override
  {
    LinearSolver::SetNumberOfThreads(n);
    Threads_ = n;
    Hierarchy_.SetNumberOfThreads(n);
  }

  const MultiresHierarchy& GetHierarchy() const { return Hierarchy_; }
  /// Milliseconds of the last hierarchy build and of the last coarse-value
  /// computation (Setup).
  double GetHierarchyMilliseconds() const { return HierarchyMs_; }
  double GetCoarseValuesMilliseconds() const { return ValuesMs_; }
  /// How many times the hierarchy was (re)built (Setup with patternChanged).
  int GetNumberOfHierarchyBuilds() const { return Builds_; }
  /// How many times Setup ran (builds and values-only set-ups).
  int GetNumberOfSetups() const { return Setups_; }

  /// Non-zeros of the coarse operator of level l >= 1 divided by those of level 0.
  double GetOperatorComplexity() const;

protected:
  /// The system must live on `mesh` (its vertex graph and positions).
  void CheckSetup(const DiffusionSystem& system, const TetMesh* mesh) const override;
  /// Builds the hierarchy and the coarse operators' patterns.
  void SetupStructure(const DiffusionSystem& system, const TetMesh* mesh) override;
  /// Recomputes the coarse values.
  void SetupValues(const DiffusionSystem& system, const TetMesh* mesh) override;
  /// Build the coarse operators' patterns (after a hierarchy build).
  virtual void BuildOperators() = 0;
  /// Recompute coarse values from the system's current values.
  virtual void ComputeValues(const DiffusionSystem& system) = 0;
  /// Throws unless `system` matches the Setup one.
  void CheckSystem(const DiffusionSystem& system) const;

  MultiresHierarchy Hierarchy_;
  std::vector<CoarseOperator> Operators_; ///< level l -> l + 1
  int Threads_ = 0;
  double HierarchyMs_ = 0.0, ValuesMs_ = 0.0;
  int Builds_ = 0;
  int Setups_ = 0;
};

/// "multigrid-cg": CG preconditioned by a V-cycle on the TransCut hierarchy.
class MultigridConjugateGradient : public MultiresLinearSolverBase
{
public:
  MultigridConjugateGradient();
  ~MultigridConjugateGradient() override;
  std::string GetName() const override { return "multigrid-cg"; }
  bool Solve(const DiffusionSystem& system, std::array<Eigen::VectorXd, NumberOfChannels>& x,
    bool warmStart, std::array<LinearSolveStats, NumberOfChannels>& stats) override;
  std::size_t GetMemoryBytes() const override;

  /// Chebyshev polynomial degree of each pre-/post-smoothing (default 1:
  /// one damped-Jacobi step, weight 1 / theta; measured best in SpMV
  /// equivalents, see Documentation/Multiresolution.md).
  void SetSmootherDegree(int degree) { Degree_ = degree; }
  /// Lower end of the Chebyshev interval as a fraction of the largest
  /// eigenvalue estimate of D^-1 A (default 0.3).
  void SetSmootherFraction(double f) { Fraction_ = f; }
  /**
   * Coarse operators: the first n (levels 1..n) are the exact Galerkin
   * product P^T A P, the deeper ones P^T A P restricted to the hierarchy's
   * coarse graph with the dropped entries added to the diagonal as |a_ab|
   * (sparser, still SPD). Exact Galerkin grows denser with every level (a
   * 3-ring pattern of a 3-ring pattern...); see Multiresolution.md for the
   * measurements behind the default. n < 0 = all exact (default: fewer
   * V-cycles outweigh the denser coarse levels). Takes effect at the next
   * Setup with patternChanged.
   */
  void SetExactGalerkinLevels(int n) { ExactGalerkinLevels_ = n; }
  int GetExactGalerkinLevels() const { return ExactGalerkinLevels_; }
  /// Shorthand: true = SetExactGalerkinLevels(0), false = all exact.
  void SetSparseGalerkin(bool on) { ExactGalerkinLevels_ = on ? 0 : -1; }

  /// The Galerkin operator P^T A P of level l >= 1, channel c (double values).
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> GetCoarseMatrix(int l, int c) const;

  /// Apply one V-cycle z = B r to the three channels (r, z interleaved, 3
  /// values per vertex) — the preconditioner, exposed for tests.
  void ApplyPreconditioner(const Eigen::VectorXd& r, Eigen::VectorXd& z) const;

protected:
  void BuildOperators() override;
  void ComputeValues(const DiffusionSystem& system) override;

private:
  struct Internals;
  std::unique_ptr<Internals> Internal_;
  int Degree_ = 1;
  double Fraction_ = 0.3;
  int ExactGalerkinLevels_ = -1;
};

/// "transcut-multires": the paper's coarse-to-fine scheme (Sec. 4.2).
class TransCutMultiresSolver : public MultiresLinearSolverBase
{
public:
  TransCutMultiresSolver();
  ~TransCutMultiresSolver() override;
  std::string GetName() const override { return "transcut-multires"; }
  bool Solve(const DiffusionSystem& system, std::array<Eigen::VectorXd, NumberOfChannels>& x,
    bool warmStart, std::array<LinearSolveStats, NumberOfChannels>& stats) override;
  std::size_t GetMemoryBytes() const override;

  /// Relative residual of the coarse-level BiCGSTAB solves (default 1e-2)
  /// and their iteration limit (default 50).
  void SetCoarseRelTol(double tol) { CoarseTol_ = tol; }
  void SetCoarseMaxIter(int n) { CoarseMaxIter_ = n; }

  /// The eq. 17 operator of level l >= 1, channel c.
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> GetCoarseMatrix(int l, int c) const;

protected:
  void BuildOperators() override;
  void ComputeValues(const DiffusionSystem& system) override;

private:
  struct Internals;
  std::unique_ptr<Internals> Internal_;
  double CoarseTol_ = 1e-2;
  int CoarseMaxIter_ = 50;
};

} // namespace translucency
