/**
 * @file VertexDiffusionSolver.h
 * @brief A DiffusionSolver for discretisations whose unknowns are the mesh
 * vertices and whose matrix is SPD (discrete divergence, FEM): assemble, then
 * Jacobi-preconditioned conjugate gradient per channel, with warm start.
 */
#pragma once

#include "ConjugateGradient.h"
#include "DiffusionSolver.h"
#include "Discretization.h"

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

private:
  std::unique_ptr<Discretization> Discretization_;
  DiffusionSystem System_;
  ConjugateGradient Solver_;
  std::array<Eigen::VectorXd, NumberOfChannels> Solution_;
  const TetMesh* LastMesh_ = nullptr;
  int LastPoints_ = -1;
};

} // namespace translucency
