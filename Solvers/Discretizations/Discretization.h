/**
 * @file Discretization.h
 * @brief Common interface: a discretisation turns (mesh, material, boundary
 * irradiance) into a linear system on its own unknowns and maps a solution
 * back to fluence at the mesh vertices.
 */
#pragma once

#include "DiffusionSystem.h"
#include "Fresnel.h"

#include <array>
#include <string>
#include <vector>

namespace translucency
{

class TetMesh;

class Discretization
{
public:
  virtual ~Discretization() = default;

  /// Short name used by scripts and the CLI ("divergence", ...).
  virtual std::string GetName() const = 0;

  /**
   * Build the three-channel system.
   * @param irradiance q, 3 values (R, G, B, W/mm^2) per mesh point; only
   *        boundary points are read.
   * Throws translucency::Error on inconsistent sizes or invalid values.
   */
  virtual void Assemble(const TetMesh& mesh, const OpticalProperties& material,
    const std::vector<double>& irradiance, DiffusionSystem& system) = 0;

  /// OpenMP threads of the assembly (0 = OpenMP's default); default: ignored.
  virtual void SetNumberOfThreads(int /*n*/) {}

  /**
   * Incremental update after the material of some tets changed (painting,
   * TransCut Sec. 5.2): rebuild only the rows of the vertices of
   * `changedTets` of a `system` assembled by Assemble() on the same mesh with
   * the same irradiance; `material` is the whole new material. Returns false
   * (and leaves `system` alone) if the discretisation has no incremental
   * update: then call Assemble(). Default: false.
   */
  virtual bool UpdateTets(const TetMesh& /*mesh*/, const OpticalProperties& /*material*/,
    const std::vector<double>& /*irradiance*/, const std::vector<int>& /*changedTets*/,
    DiffusionSystem& /*system*/) const
  {
    return false;
  }

  /**
   * Relighting: rebuild only the right-hand side of a `system` assembled by
   * Assemble() (or kept up to date by UpdateTets()) on the same mesh with the
   * same `material`, for the new `irradiance` (3 per point). The result
   * equals Assemble() with the new irradiance bit for bit; the matrices are
   * untouched. Returns false (and leaves `system` alone) if the
   * discretisation has no such update: then call Assemble(). Default: false.
   */
  virtual bool UpdateRightHandSide(const TetMesh& /*mesh*/, const OpticalProperties& /*material*/,
    const std::vector<double>& /*irradiance*/, DiffusionSystem& /*system*/) const
  {
    return false;
  }

  /**
   * Add, for every tet t and channel c, coefficient[3 t + c] (1/mm) times
   * this discretisation's (scaled) mass matrix of tet t to values[c], the
   * value arrays of a system assembled by Assemble() on `mesh`: the change
   * of the matrix when mu_a grows by `coefficient`, kappa held fixed. The
   * frequency-domain solve uses it for the imaginary absorption
   * 2 pi f eta / c. Returns false if the discretisation has none (default).
   */
  virtual bool AddMass(const TetMesh& /*mesh*/, const std::vector<double>& /*coefficient*/,
    std::array<std::vector<double>, NumberOfChannels>& /*values*/) const
  {
    return false;
  }

  /**
   * The coefficients A and Fdr of the Robin condition that Assemble() and
   * UpdateTets() use (Fresnel::BoundaryRule; default Fit, TransCut eq. 2).
   * Discretisations without the choice keep Fit and ignore it
   * (VertexDiffusionSolver sets it from DiffusionProblem::Collimated).
   */
  void SetBoundaryRule(Fresnel::BoundaryRule rule) { BoundaryRule_ = rule; }
  Fresnel::BoundaryRule GetBoundaryRule() const { return BoundaryRule_; }

  /// Map the per-channel solutions to fluence phi, 3 values per mesh point
  /// (W/mm^2).
  virtual void ToPointFluence(const TetMesh& mesh, const DiffusionSystem& system,
    const std::array<Eigen::VectorXd, NumberOfChannels>& solution,
    std::vector<double>& fluence) const = 0;

protected:
  Fresnel::BoundaryRule BoundaryRule_ = Fresnel::BoundaryRule::Fit;
};

} // namespace translucency
