/**
 * @file SubsurfaceOperator.h
 * @brief The subsurface scattering operator S of translucent radiosity
 * (TranslucentRadiosity, eq. 7-9 and 14) for one translucent object, and
 * its matrix-free version by a diffusion solve (ours: Documentation/Radiosity.md,
 * "S by a diffusion solve").
 */
#pragma once

#include "DiffusionSystem.h"
#include "DiscreteDivergence.h"
#include "LinearSolver.h"

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace translucency
{

class RadiosityScene;
class TetMesh;

/**
 * S restricted to one translucent object of a scene: maps the irradiance
 * transmitted into the object at each of its patches, q (W/mm^2; Fresnel
 * already applied), to the radiosity (exitance, W/mm^2) leaving each of its
 * patches: B_j = sum_i S_ji q_i (paper eq. 9). Vectors hold 3 values per
 * patch of the object (R, G, B) in the object's local patch order.
 */
class SubsurfaceOperator
{
public:
  virtual ~SubsurfaceOperator() = default;
  /// "diffusion" or "profile".
  virtual std::string GetName() const = 0;
  /**
   * Prepare for translucent object `object` of the built scene (the scene
   * must outlive this operator). Call again after the object's material
   * changed (translucency change).
   */
  virtual void Setup(const RadiosityScene& scene, int object) = 0;
  /// radiosity = S q (see the class comment). Sizes: 3 per patch.
  virtual void Apply(const std::vector<double>& q, std::vector<double>& radiosity) = 0;
  /// Bytes the operator holds (matrices, caches).
  virtual std::size_t GetMemoryBytes() const = 0;
};

/**
 * S applied by the discrete-divergence diffusion solve (TransCut eq. 10-14)
 * on the object's tet mesh:
 *  1. patch q -> vertex q: q_v = sum_{t ni v} A_t q_t / S_v (area-weighted
 *     mean of the patches around boundary vertex v; S_v = their area), so
 *     that sum_v (S_v / 3) q_v = sum_t A_t q_t (same power);
 *  2. right-hand side b = beta .* q_v, beta obtained once from an assembly
 *     with q = 1 (the matrix does not depend on q);
 *  3. a LinearSolver (the seam of the vertex discretisations; default
 *     "cg-jacobi", SetLinearSolver), warm-started from the previous apply
 *     (relative tolerance SetRelTol, default 1e-6); Setup() of the linear
 *     solver runs once per material (a direct solver factors once and then
 *     only substitutes per apply);
 *  4. vertex exitance from the discrete energy balance of the lumped
 *     boundary term (Documentation/Radiosity.md):
 *     M_v = phi_v / (2 A_v) - q_v (1 - Fdr_v) / (1 + Fdr_v),
 *     which makes sum_v (S_v/3) M_v = power in - power absorbed exactly for
 *     the discrete system (it equals the hemispherical integral of eq. 3 with
 *     the n^2 law up to the polynomial fit of Fdr);
 *  5. patch radiosity B_t = mean of M_v over the 3 vertices of t.
 * The operator is linear (no clamping: M_v can be slightly negative next to
 * a sharp light edge).
 */
class DiffusionSubsurface : public SubsurfaceOperator
{
public:
  std::string GetName() const override { return "diffusion"; }
  void Setup(const RadiosityScene& scene, int object) override;
  void Apply(const std::vector<double>& q, std::vector<double>& radiosity) override;
  std::size_t GetMemoryBytes() const override;

  /// Linear solver by name (CreateLinearSolver; default "cg-jacobi"). Takes
  /// effect at the next Setup(). Throws translucency::Error for an unknown name.
  void SetLinearSolver(const std::string& name);
  const std::string& GetLinearSolver() const { return LinearSolverName_; }
  /// Relative residual of the linear solves (default 1e-6).
  void SetRelTol(double tol);
  /// Warm start from the previous apply (default on).
  void SetWarmStart(bool on) { WarmStart_ = on; }
  /// Iterations of the last apply (channel R, G, B) and in total.
  int GetLastIterations(int c) const { return Stats_[c].Iterations; }
  long long GetTotalIterations() const { return TotalIterations_; }

private:
  const TetMesh* Mesh_ = nullptr;
  DiscreteDivergence Discretization_;
  DiffusionSystem System_;
  std::string LinearSolverName_ = "cg-jacobi";
  std::unique_ptr<LinearSolver> Solver_;
  double RelTol_ = 1e-6;
  std::array<LinearSolveStats, NumberOfChannels> Stats_{};
  std::array<Eigen::VectorXd, NumberOfChannels> Solution_;
  std::array<Eigen::VectorXd, NumberOfChannels> Beta_;
  std::vector<double> HalfOverA_;  ///< 1 / (2 A_v) per point (0 inside)
  std::vector<double> QFactor_;    ///< (1 - Fdr_v) / (1 + Fdr_v) per point
  bool WarmStart_ = true;
  long long TotalIterations_ = 0;
};

/**
 * Total diffuse reflectance of a half-space (Jensen et al. 2001, eq. for
 * R_d: (alpha'/2) (1 + exp(-4/3 A sqrt(3 (1 - alpha')))) exp(-sqrt(3 (1 - alpha')))),
 * alpha' = sigma_s' / (sigma_s' + mu_a). Used as the diffuse colour of a
 * translucent patch (times the Fresnel transmittance in, T_u) where a
 * diffuse stand-in is needed: the "direct" panel and the Sec. 6.3 heuristics.
 */
double DipoleTotalReflectance(double muA, double sigmaS, double eta);

} // namespace translucency
