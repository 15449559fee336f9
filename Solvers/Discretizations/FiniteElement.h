/**
 * @file FiniteElement.h
 * @brief The consistent linear (P1) Galerkin discretisation of the diffusion
 * equation with the Robin (diffusive source) boundary condition: the finite
 * element reference the TransCut paper compares against (Arbree et al. 2011;
 * TransCut Sec. 3.2.4 and 6.2). Same unknowns as DiscreteDivergence (the mesh
 * vertices), different matrix: consistent instead of lumped mass, boundary
 * mass and load.
 */
#pragma once

#include "Discretization.h"
#include "TetGeometry.h"

namespace translucency
{

/**
 * Weak form (derivation): multiply div(kappa grad phi) - mu_a phi = 0
 * (TransCut eq. 1) by a test function v and integrate by parts over the
 * object Omega:
 *
 *   -int_Omega kappa grad phi . grad v + int_dOmega kappa (dphi/dn) v
 *     - int_Omega mu_a phi v = 0.
 *
 * The Robin condition phi + 2 A kappa dphi/dn = 4 q / (1 - Fdr) (TransCut
 * eq. 2, n outward) gives kappa dphi/dn = (4 q / (1 - Fdr) - phi) / (2 A) on
 * the boundary, hence
 *
 *   int kappa grad phi . grad v + int mu_a phi v + (1 / (2A)) int_dOmega phi v
 *     = (2 / (A (1 - Fdr))) int_dOmega q v.
 *
 * With phi and v in the P1 space of the tet mesh and q interpolated linearly
 * on each boundary triangle from its vertex values, every integral is exact:
 *  - stiffness kappa_t V_t grad(beta_a).grad(beta_b) on each tet t (the same
 *    numbers as TransCut eq. 10, which is this identity written with cot
 *    weights);
 *  - consistent mass (V_t / 20) (1 + delta_ab) mu_t on each tet;
 *  - consistent boundary mass (S_f / 12) (1 + delta_ab) / (2 A_f) on each
 *    boundary triangle f (area S_f);
 *  - consistent load (2 / (A_f (1 - Fdr_f))) (S_f / 12) sum_b (1 + delta_ab) q_b.
 *
 * The matrix and right-hand side are multiplied by 4, like DiscreteDivergence
 * (its M is 4 x the P1 stiffness + lumped terms), which does not change the
 * solution: lumping this matrix (adding each row onto its diagonal) gives the
 * divergence matrix exactly in exact arithmetic (for a uniform refractive
 * index; see below), and the two right-hand sides have the same sum.
 *
 * Refractive index: eta is a per-tet property, so A and Fdr are taken per
 * boundary triangle from the tet that owns it (piecewise constant on the
 * boundary, as the Galerkin integrals then are exact). DiscreteDivergence
 * uses the area-weighted mean index per boundary vertex
 * (BoundaryPointRefractiveIndex); the two agree whenever all triangles around
 * a vertex have the same eta.
 */
class FiniteElement : public Discretization
{
public:
  std::string GetName() const override { return "fem"; }

  /**
   * Assemble 4 x (stiffness + consistent mass + consistent boundary mass)
   * and 4 x the consistent load for the three channels. Parallel over tets
   * with OpenMP using the mesh's scatter schedule; each boundary triangle is
   * added with the tet that owns it, so the result is bit-identical for any
   * thread count. Throws translucency::Error on invalid material or
   * irradiance (naming the array, element and value) or an empty mesh.
   */
  void Assemble(const TetMesh& mesh, const OpticalProperties& material,
    const std::vector<double>& irradiance, DiffusionSystem& system) override;

  /// 4 x the consistent mass (V_t / 20)(1 + delta_ab).
  bool AddMass(const TetMesh& mesh, const std::vector<double>& coefficient,
    std::array<std::vector<double>, NumberOfChannels>& values) const override;

  /// Unknowns are the vertex fluences: a copy.
  void ToPointFluence(const TetMesh& mesh, const DiffusionSystem& system,
    const std::array<Eigen::VectorXd, NumberOfChannels>& solution,
    std::vector<double>& fluence) const override;

  /// OpenMP threads for assembly (0 = OpenMP default). Default 0.
  void SetNumberOfThreads(int n) override { NumberOfThreads_ = n; }
  int GetNumberOfThreads() const { return NumberOfThreads_; }

private:
  int NumberOfThreads_ = 0;
  /// Scratch of Assemble: the boundary triangles of each tet as linked lists
  /// (first triangle per tet or -1; next triangle of the same tet or -1).
  std::vector<int> TriangleHead_;
  std::vector<int> TriangleNext_;
  /// V_t and g_ab per tet, reused while the mesh geometry is the same.
  TetGeometryCache GeometryCache_;
};

} // namespace translucency
