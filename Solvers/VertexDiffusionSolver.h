/**
 * @file VertexDiffusionSolver.h
 * @brief A DiffusionSolver for discretisations whose unknowns are the mesh
 * vertices and whose matrix is SPD (discrete divergence, FEM): assemble, then
 * solve the three channels with the LinearSolver named by SetLinearSolver()
 * ("" = GetDefaultLinearSolverName()), with warm start.
 *
 * The LinearSolver object (and its hierarchy or factor) is kept across
 * solves: Setup(patternChanged = true) after a mesh change (another mesh
 * object, or its size or pattern changed), Setup(false) when only matrix
 * values changed (paint, material, deformation), no Setup at all when only
 * the right-hand side changed (relight). Changing the name creates a new
 * solver object.
 */
#pragma once

#include "DiffusionSolver.h"
#include "Discretization.h"
#include "LinearSolver.h"

namespace translucency
{

class VertexDiffusionSolver : public DiffusionSolver
{
public:
  /// Takes ownership of the discretisation.
  explicit VertexDiffusionSolver(std::unique_ptr<Discretization> discretization);

  std::string GetName() const override { return Discretization_->GetName(); }
  bool Solve(const DiffusionProblem& problem, std::vector<double>& fluence,
    SolverReport& report) override;
  void Reset() override;

  /// The discretisation (e.g. to set its number of threads).
  Discretization& GetDiscretization() { return *Discretization_; }
  /// The system of the last Solve (valid until the next one).
  const DiffusionSystem& GetSystem() const { return System_; }

  /// The linear solver of the last Solve (null before the first one).
  LinearSolver* GetLinearSolverObject() { return Linear_.get(); }
  /// The linear solver used when SetLinearSolver("") (the default).
  static std::string GetDefaultLinearSolverName();

private:
  std::unique_ptr<Discretization> Discretization_;
  DiffusionSystem System_;
  std::unique_ptr<LinearSolver> Linear_;
  std::string LinearName_; ///< lower-case name Linear_ was created for
  bool LinearReady_ = false;
  /// The values of the previous assembly, to detect value-only changes.
  std::array<std::vector<double>, NumberOfChannels> PreviousValues_;
  std::array<Eigen::VectorXd, NumberOfChannels> Solution_;
  const TetMesh* LastMesh_ = nullptr;
  int LastPoints_ = -1;
  int LastTets_ = -1;
  std::size_t LastNonZeros_ = 0;
};

} // namespace translucency
