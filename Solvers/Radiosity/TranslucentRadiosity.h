/**
 * @file TranslucentRadiosity.h
 * @brief B = (I - S F)^-1 S E (TranslucentRadiosity, eq. 14) for a
 * scene of translucent and opaque diffuse objects, by Jacobi or block
 * Gauss-Seidel iteration, with the two heuristics of the paper's Sec. 6.3.
 */
#pragma once

#include "FormFactors.h"
#include "LightSources.h"
#include "SubsurfaceOperator.h"

#include <memory>
#include <string>
#include <vector>

namespace translucency
{

class RadiosityScene;

/// Everything a solve returns; vectors hold 3 values per patch (R, G, B).
struct RadiosityResult
{
  std::vector<double> DirectIrradiance; ///< E: light arriving from the lights (W/mm^2)
  std::vector<double> Direct;           ///< P E: E reflected by the diffuse stand-in albedo
  std::vector<double> FirstBounce;      ///< S E: subsurface scattering only (paper eq. 7)
  std::vector<double> InterReflection;  ///< B - S E: every later bounce
  std::vector<double> Combined;         ///< B (eq. 14)
  /// Relative change ||B_k+1 - B_k|| / ||B_k+1|| (area-weighted 2-norm) per iteration.
  std::vector<double> ResidualHistory;
  int Iterations = 0;
  bool Converged = false;
  double DirectMilliseconds = 0.0;  ///< E and S E
  double SolveMilliseconds = 0.0;   ///< the iteration
};

class TranslucentRadiosity
{
public:
  enum class Iteration
  {
    Jacobi,     ///< B <- S E + S F B, all patches at once
    GaussSeidel ///< object by object (opaque objects patch by patch), newest B
  };

  /// The scene (built; borrowed, must outlive this object) and its form factors (borrowed).
  void SetScene(RadiosityScene* scene) { Scene_ = scene; Ready_ = false; }
  void SetFormFactors(const FormFactorMatrix* F) { F_ = F; }

  /// "diffusion" (default, ours) or "profile" (the paper's dipole over optical paths).
  void SetSubsurfaceMethod(const std::string& name);
  const std::string& GetSubsurfaceMethod() const { return Method_; }

  /// Diffusion S only: linear solver of the diffusion systems (a name of
  /// GetLinearSolverNames(); default "cg-jacobi"). Takes effect at Setup().
  void SetLinearSolver(const std::string& name);

  ///@{
  /// Profile S only: voxel size (mm, 0 = automatic: 1/40 of the object's
  /// largest side) and cut-off distance max_d (mm, 0 = automatic: where the
  /// dipole profile has fallen to 1e-4 of its value at one voxel).
  void SetVoxelSize(double h) { VoxelSize_ = h; }
  void SetMaxDistance(double d) { MaxDistance_ = d; }
  ///@}

  /// Relative change at which the iteration stops (default 0.005, the paper's
  /// 0.5 %). The diffusion S solves use min(1e-4, RelTol / 100) (set at Setup()).
  void SetRelTol(double tol) { RelTol_ = tol; }
  double GetRelTol() const { return RelTol_; }
  /// Iteration limit (default 200).
  void SetMaxIter(int n) { MaxIter_ = n; }
  void SetIteration(Iteration it) { Iteration_ = it; }
  /// Shadows of the direct light (default on).
  void SetShadows(bool on) { Shadows_ = on; }

  /**
   * Build one S operator per translucent object (diffusion: assembly;
   * profile: voxel graph, optical distances, matrix). Called by Solve() when
   * needed. Throws translucency::Error on a missing scene or form factors.
   */
  void Setup();
  /**
   * The material of translucent object k changed (RadiosityScene::SetMaterial):
   * rebuild its operator only (diffusion: re-assembly; profile: new profile
   * over the cached distances).
   */
  void UpdateMaterial(int object);

  /**
   * Solve for the lights (checked with RadiosityScene::CheckLights()).
   * Throws translucency::Error on invalid input. Not converging within
   * MaxIter is not an error (see result.Converged).
   */
  void Solve(const std::vector<LightSource>& lights, RadiosityResult& result);

  /**
   * Paper Sec. 6.3 heuristics, on the direct light of the last Solve():
   * h1 = (I - P F)^-1 S E and h2 = S E + (I - P F)^-1 P F P E, P the diffuse
   * albedo per patch (GetDiffuseAlbedo()). Solved by Jacobi to the same RelTol.
   */
  void SolveHeuristics(std::vector<double>& h1, std::vector<double>& h2);

  /**
   * y = S x for incident irradiance x (W/mm^2, per patch) arriving
   * diffusely: translucent patches transmit T_u(eta) x (Fresnel for uniform
   * incident radiance), opaque ones reflect albedo * x.
   */
  void ApplyS(const std::vector<double>& x, std::vector<double>& y);

  /**
   * Spectral radius of S F per channel by power iteration from a positive
   * vector (`iterations` steps; the ratio of area-weighted norms of the last step).
   */
  std::array<double, 3> EstimateSpectralRadius(int iterations);

  /**
   * Diffuse stand-in albedo per patch: the albedo of opaque patches; for
   * translucent patches T_u(eta) * DipoleTotalReflectance() of the tet that
   * owns the patch.
   */
  std::vector<double> GetDiffuseAlbedo();

  /// Bytes of the S operators (per object, summed).
  std::size_t GetSubsurfaceMemoryBytes() const;
  /// Milliseconds of the last Setup() / UpdateMaterial().
  double GetSetupMilliseconds() const { return SetupMilliseconds_; }
  /// The operator of object k (nullptr for opaque objects).
  SubsurfaceOperator* GetOperator(int k) { return Operators_[k].get(); }

private:
  /// y = S x where x is already transmitted into translucent objects.
  void ApplySTransmitted(const std::vector<double>& x, std::vector<double>& y);
  void ApplyObject(int k, const std::vector<double>& x, std::vector<double>& y);
  std::unique_ptr<SubsurfaceOperator> MakeOperator() const;
  double Norm(const std::vector<double>& v) const;
  void CheckReady();
  void ComputeTranslucentAlbedo(int k);

  RadiosityScene* Scene_ = nullptr;
  const FormFactorMatrix* F_ = nullptr;
  std::string Method_ = "diffusion";
  std::string LinearSolver_ = "cg-jacobi";
  double VoxelSize_ = 0.0;
  double MaxDistance_ = 0.0;
  double RelTol_ = 0.005;
  int MaxIter_ = 200;
  Iteration Iteration_ = Iteration::GaussSeidel;
  bool Shadows_ = true;
  bool Ready_ = false;
  std::vector<std::unique_ptr<SubsurfaceOperator>> Operators_;
  std::vector<double> Transmittance_; ///< T_u(eta) per patch (1 for opaque)
  std::vector<double> TranslucentAlbedo_; ///< stand-in albedo of translucent patches (3 each)
  std::vector<double> SE_;            ///< S E of the last Solve()
  std::vector<double> E_;             ///< incident E of the last Solve()
  double SetupMilliseconds_ = 0.0;
};

} // namespace translucency
