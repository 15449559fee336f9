/**
 * @file SparseFactorization.h
 * @brief Direct factorisations of one sparse symmetric positive definite
 * matrix, solved for many right-hand sides at once (the inverse problem's
 * forward model: one factor per parameter set, then blocks of adjoint and
 * forward solves). A family with its own registry beside the linear
 * solvers': the interface differs (one matrix, a dense block of right-hand
 * sides, no iterations), the optional library is the same CHOLMOD.
 */
#pragma once

#include "Registry.h"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>
#include <string>

namespace translucency
{

class SparseFactorization
{
public:
  virtual ~SparseFactorization() = default;

  /// The name of the entry, e.g. "cholmod-supernodal".
  virtual std::string GetName() const = 0;

  /// Symbolic analysis (fill-reducing ordering, factor pattern) of the
  /// pattern of `matrix` (its lower part is read); once per pattern.
  virtual void AnalyzePattern(const Eigen::SparseMatrix<double>& matrix) = 0;

  /// Numeric factorisation of `matrix` (the analysed pattern). False if the
  /// matrix is not positive definite (then Solve must not be called).
  virtual bool Factorize(const Eigen::SparseMatrix<double>& matrix) = 0;

  ///@{
  /// x = M^-1 rhs, for one vector or a block of columns (one blocked
  /// back-substitution: much faster than column by column with CHOLMOD).
  virtual void Solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const = 0;
  virtual void Solve(const Eigen::MatrixXd& rhs, Eigen::MatrixXd& x) const = 0;
  ///@}
};

/// What the registry says about a factorisation.
struct SparseFactorizationTraits
{
  /// The optional library it needs ("" = always built), e.g. "CHOLMOD".
  std::string Library;
  /// Whether this build has it.
  bool Built = true;
  /// How to get the library when it is not built (for the error message).
  std::string Remedy;
};

using SparseFactorizationRegistry = Registry<SparseFactorization, SparseFactorizationTraits>;

/// Every factorisation this code knows, built or not, the fastest first
/// ("cholmod-supernodal", then "eigen-simplicial-ldlt").
const SparseFactorizationRegistry& GetSparseFactorizationRegistry();

/// The first built entry of the registry: the default factorisation.
std::string GetDefaultSparseFactorizationName();

/// The factorisation called `name` (case-insensitive; "" = the default).
/// Throws translucency::Error if it is unknown or not in this build.
std::unique_ptr<SparseFactorization> CreateSparseFactorization(const std::string& name = "");

} // namespace translucency
