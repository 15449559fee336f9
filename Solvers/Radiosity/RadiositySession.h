/**
 * @file RadiositySession.h
 * @brief The scene, form factors and solver of successive radiosity runs,
 * kept while they stay valid: a new scene with the same patches only updates
 * albedos and materials (no new form factors, TranslucentRadiosity Sec. 5's
 * F reused), and a solver is set up again only when its settings change.
 */
#pragma once

#include "FormFactors.h"
#include "RadiosityScene.h"
#include "TranslucentRadiosity.h"

#include <functional>
#include <memory>
#include <string>

namespace translucency
{

/// The settings that need a new subsurface set-up when they change.
struct SubsurfaceSettings
{
  std::string Method = "diffusion";       ///< "diffusion" or "profile"
  double VoxelSize = 0.0;                 ///< profile only: mm, 0 = automatic
  double MaxDistance = 0.0;               ///< profile only: mm, 0 = no limit
  std::string LinearSolver = "cg-jacobi"; ///< diffusion only: a linear solver name

  bool operator==(const SubsurfaceSettings& o) const
  {
    return Method == o.Method && VoxelSize == o.VoxelSize && MaxDistance == o.MaxDistance &&
      LinearSolver == o.LinearSolver;
  }
};

class RadiositySession
{
public:
  ///@{
  /// Form-factor settings (FormFactorComputer): rays per patch (default 256)
  /// and the threshold below which entries are dropped (default 0).
  void SetRaysPerPatch(int rays) { Rays_ = rays; }
  void SetFormFactorThreshold(double threshold) { Threshold_ = threshold; }
  ///@}

  /// Called with the fraction of the form factors done; return false to stop.
  void SetProgressCallback(std::function<bool(double)> callback) { Progress_ = std::move(callback); }

  /// True when a scene and its form factors are kept and were computed with
  /// the current rays and threshold.
  bool HasValidFormFactors() const;

  /**
   * Take a newly gathered scene (after RadiosityScene::Build(false)). With
   * the same patches (points, triangles, objects) and form-factor settings as
   * the kept scene, only changed albedos and materials are copied into the
   * kept scene (the solver updates those objects); otherwise the ray caster is
   * built, the form factors computed and the solver dropped. Returns false
   * (nothing kept) when the progress callback stopped it.
   */
  bool UpdateScene(std::unique_ptr<RadiosityScene> scene);

  /**
   * The solver for the kept scene with these settings: the kept one, or a new
   * one set up (timed in GetSetupMilliseconds()). Throws translucency::Error
   * without a scene.
   */
  TranslucentRadiosity& GetSolver(const SubsurfaceSettings& settings);

  /// The kept scene (nullptr before UpdateScene()) and its form factors.
  const RadiosityScene* GetScene() const { return Scene_.get(); }
  const FormFactorMatrix& GetFormFactors() const { return F_; }
  /// The kept solver, or nullptr.
  const TranslucentRadiosity* GetKeptSolver() const { return Solver_.get(); }

  /// Set the times below to 0 (at the start of a run).
  void ResetTimes() { FormFactorMilliseconds_ = SetupMilliseconds_ = 0.0; }
  /// Time of the form factors since ResetTimes() (0 when they were reused), ms.
  double GetFormFactorMilliseconds() const { return FormFactorMilliseconds_; }
  /// Time of the subsurface set-up and material updates since ResetTimes(), ms.
  double GetSetupMilliseconds() const { return SetupMilliseconds_; }

private:
  bool SamePatches(const RadiosityScene& scene) const;

  int Rays_ = 256;
  double Threshold_ = 0.0;
  std::function<bool(double)> Progress_;
  std::unique_ptr<RadiosityScene> Scene_;
  FormFactorMatrix F_;
  int FormFactorRays_ = -1;          ///< settings of F_
  double FormFactorThreshold_ = -1.0;
  std::unique_ptr<TranslucentRadiosity> Solver_;
  SubsurfaceSettings SolverSettings_;
  double FormFactorMilliseconds_ = 0.0, SetupMilliseconds_ = 0.0;
};

} // namespace translucency
