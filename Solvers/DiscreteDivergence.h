/**
 * @file DiscreteDivergence.h
 * @brief The TransCut discrete-divergence discretisation (paper Sec. 3,
 * eq. 4-14): unknowns at the mesh vertices, cot-weight edge coefficients,
 * lumped absorption and lumped Robin boundary term.
 */
#pragma once

#include "Discretization.h"

namespace translucency
{

class DiscreteDivergence : public Discretization
{
public:
  std::string GetName() const override { return "divergence"; }

  /**
   * Assemble M (eq. 13-14) and b (eq. 12) for the three channels. Parallel
   * over tets with OpenMP. The result is bit-identical for any thread count
   * (tets are processed in vertex-disjoint colour classes, so every entry
   * sums its contributions in the same order).
   */
  void Assemble(const TetMesh& mesh, const OpticalProperties& material,
    const std::vector<double>& irradiance, DiffusionSystem& system) override;

  /// Unknowns are the vertex fluences: a copy.
  void ToPointFluence(const TetMesh& mesh, const DiffusionSystem& system,
    const std::array<Eigen::VectorXd, NumberOfChannels>& solution,
    std::vector<double>& fluence) const override;

  /// OpenMP threads for assembly (0 = OpenMP default). Default 0.
  void SetNumberOfThreads(int n) { NumberOfThreads_ = n; }
  int GetNumberOfThreads() const { return NumberOfThreads_; }

private:
  int NumberOfThreads_ = 0;
};

} // namespace translucency
