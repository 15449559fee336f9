#include "RadiositySession.h"

#include "Error.h"
#include "Timer.h"

namespace translucency
{

namespace
{
bool SameMaterial(const OpticalProperties& a, const OpticalProperties& b)
{
  return a.AbsorptionCoefficient == b.AbsorptionCoefficient &&
    a.ReducedScatteringCoefficient == b.ReducedScatteringCoefficient &&
    a.RefractiveIndex == b.RefractiveIndex;
}
} // namespace

//------------------------------------------------------------------------------
bool RadiositySession::HasValidFormFactors() const
{
  return Scene_ && FormFactorRays_ == Rays_ && FormFactorThreshold_ == Threshold_;
}

//------------------------------------------------------------------------------
bool RadiositySession::SamePatches(const RadiosityScene& scene) const
{
  if (scene.GetNumberOfObjects() != Scene_->GetNumberOfObjects() ||
    scene.GetPoints() != Scene_->GetPoints() || scene.GetTriangles() != Scene_->GetTriangles())
  {
    return false;
  }
  for (int k = 0; k < scene.GetNumberOfObjects(); ++k)
  {
    if (scene.GetObject(k).Translucent != Scene_->GetObject(k).Translucent)
    {
      return false;
    }
  }
  return true;
}

//------------------------------------------------------------------------------
bool RadiositySession::UpdateScene(std::unique_ptr<RadiosityScene> scene)
{
  if (HasValidFormFactors() && SamePatches(*scene))
  {
    // Same geometry: update albedos and materials in the kept scene.
    for (int k = 0; k < Scene_->GetNumberOfObjects(); ++k)
    {
      const RadiosityObject& kept = Scene_->GetObject(k);
      const RadiosityObject& fresh = scene->GetObject(k);
      if (!kept.Translucent && kept.Albedo != fresh.Albedo)
      {
        Scene_->SetAlbedo(k, fresh.Albedo);
      }
      else if (kept.Translucent && !SameMaterial(kept.Material, fresh.Material))
      {
        Scene_->SetMaterial(k, fresh.Material);
        if (Solver_)
        {
          const Timer timer;
          Solver_->UpdateMaterial(k);
          SetupMilliseconds_ += timer.GetMilliseconds();
        }
      }
    }
    return true;
  }
  scene->BuildRayCaster();
  FormFactorComputer computer;
  computer.SetRaysPerPatch(Rays_);
  computer.SetThreshold(Threshold_);
  computer.SetProgressCallback(Progress_);
  const Timer timer;
  if (!computer.Compute(*scene, F_))
  {
    Scene_.reset();
    Solver_.reset();
    return false; // stopped
  }
  FormFactorMilliseconds_ = timer.GetMilliseconds();
  FormFactorRays_ = Rays_;
  FormFactorThreshold_ = Threshold_;
  Scene_ = std::move(scene);
  Solver_.reset();
  return true;
}

//------------------------------------------------------------------------------
TranslucentRadiosity& RadiositySession::GetSolver(const SubsurfaceSettings& settings)
{
  if (!Scene_)
  {
    throw Error("RadiositySession::GetSolver: no scene (call UpdateScene first)");
  }
  if (!Solver_ || !(SolverSettings_ == settings))
  {
    Solver_ = std::make_unique<TranslucentRadiosity>();
    Solver_->SetScene(Scene_.get());
    Solver_->SetFormFactors(&F_);
    Solver_->SetSubsurfaceMethod(settings.Method);
    Solver_->SetVoxelSize(settings.VoxelSize);
    Solver_->SetLinearSolver(settings.LinearSolver);
    Solver_->SetMaxDistance(settings.MaxDistance);
    const Timer timer;
    try
    {
      Solver_->Setup();
    }
    catch (...)
    {
      Solver_.reset(); // not set up: never reused
      throw;
    }
    SetupMilliseconds_ += timer.GetMilliseconds();
    SolverSettings_ = settings;
  }
  return *Solver_;
}

} // namespace translucency
