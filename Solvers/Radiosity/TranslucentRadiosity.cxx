#include "TranslucentRadiosity.h"
#include "ResourceLimits.h"

#include "Error.h"
#include "Fresnel.h"
#include "ProfileSubsurface.h"
#include "RadiosityScene.h"
#include "Strings.h"
#include "TetMesh.h"
#include "Timer.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace translucency
{

void TranslucentRadiosity::SetSubsurfaceMethod(const std::string& name)
{
  std::string lower = name;
  lower = ToLower(lower);
  if (lower != "diffusion" && lower != "profile")
  {
    throw Error("unknown S operator '" + name + "' (diffusion or profile)");
  }
  if (lower != Method_)
  {
    Ready_ = false;
  }
  Method_ = lower;
}

void TranslucentRadiosity::SetLinearSolver(const std::string& name)
{
  DiffusionSubsurface probe;
  probe.SetLinearSolver(name); // throws for an unknown name
  if (probe.GetLinearSolver() != LinearSolver_)
  {
    Ready_ = false;
  }
  LinearSolver_ = probe.GetLinearSolver();
}

std::unique_ptr<SubsurfaceOperator> TranslucentRadiosity::MakeOperator() const
{
  if (Method_ == "profile")
  {
    auto op = std::make_unique<ProfileSubsurface>();
    op->SetVoxelSize(VoxelSize_);
    op->SetMaxDistance(MaxDistance_);
    return op;
  }
  auto op = std::make_unique<DiffusionSubsurface>();
  op->SetLinearSolver(LinearSolver_);
  op->SetRelTol(std::min(1e-4, 0.01 * RelTol_));
  return op;
}

void TranslucentRadiosity::Setup()
{
  if (!Scene_ || Scene_->GetNumberOfPatches() == 0)
  {
    throw Error("translucent radiosity: no scene (or a scene without patches; call Build())");
  }
  if (!F_ || F_->NumberOfPatches != Scene_->GetNumberOfPatches())
  {
    throw Error("translucent radiosity: the form factors do not match the scene (compute them "
                "after RadiosityScene::Build())");
  }
  const auto start = Clock::now();
  Operators_.clear();
  Operators_.resize(Scene_->GetNumberOfObjects());
  for (int k = 0; k < Scene_->GetNumberOfObjects(); ++k)
  {
    if (Scene_->GetObject(k).Translucent)
    {
      Operators_[k] = MakeOperator();
      Operators_[k]->Setup(*Scene_, k);
    }
  }
  const int numPatches = Scene_->GetNumberOfPatches();
  TranslucentAlbedo_.assign(3 * static_cast<size_t>(numPatches), 0.0);
  for (int k = 0; k < Scene_->GetNumberOfObjects(); ++k)
  {
    if (Scene_->GetObject(k).Translucent)
    {
      ComputeTranslucentAlbedo(k);
    }
  }
  Transmittance_.assign(numPatches, 1.0);
  for (int p = 0; p < numPatches; ++p)
  {
    if (Scene_->GetObject(Scene_->GetPatchObject()[p]).Translucent)
    {
      // Diffuse light from other patches: cosine-weighted Fresnel transmittance.
      Transmittance_[p] = Fresnel::UniformTransmittance(Scene_->GetPatchEta()[p]);
    }
  }
  Ready_ = true;
  SetupMilliseconds_ = MillisecondsSince(start);
}

void TranslucentRadiosity::UpdateMaterial(int object)
{
  if (!Ready_)
  {
    Setup();
    return;
  }
  const auto start = Clock::now();
  if (object < 0 || object >= static_cast<int>(Operators_.size()) || !Operators_[object])
  {
    throw Error("UpdateMaterial: object " + std::to_string(object) + " is not translucent");
  }
  Operators_[object]->Setup(*Scene_, object);
  ComputeTranslucentAlbedo(object);
  for (int p = Scene_->GetPatchOffset(object); p < Scene_->GetPatchOffset(object + 1); ++p)
  {
    Transmittance_[p] = Fresnel::UniformTransmittance(Scene_->GetPatchEta()[p]);
  }
  SetupMilliseconds_ = MillisecondsSince(start);
}

void TranslucentRadiosity::CheckReady()
{
  if (!Ready_ || !Scene_ || !F_ || F_->NumberOfPatches != Scene_->GetNumberOfPatches())
  {
    Setup();
  }
}

double TranslucentRadiosity::Norm(const std::vector<double>& v) const
{
  const std::vector<double>& areas = Scene_->GetAreas();
  double s = 0.0;
  for (size_t p = 0; p < areas.size(); ++p)
  {
    s += areas[p] * (v[3 * p] * v[3 * p] + v[3 * p + 1] * v[3 * p + 1] + v[3 * p + 2] * v[3 * p + 2]);
  }
  return std::sqrt(s);
}

void TranslucentRadiosity::ApplyObject(int k, const std::vector<double>& x, std::vector<double>& y)
{
  const int begin = Scene_->GetPatchOffset(k), end = Scene_->GetPatchOffset(k + 1);
  const RadiosityObject& object = Scene_->GetObject(k);
  if (!object.Translucent)
  {
    // Opaque: S = diag(albedo) (paper Sec. 3.3: S = P for an opaque scene).
    for (int p = begin; p < end; ++p)
    {
      for (int c = 0; c < 3; ++c)
      {
        y[3 * p + c] = object.Albedo[3 * (p - begin) + c] * x[3 * p + c];
      }
    }
    return;
  }
  std::vector<double> local(x.begin() + 3 * begin, x.begin() + 3 * end), out;
  Operators_[k]->Apply(local, out);
  std::copy(out.begin(), out.end(), y.begin() + 3 * begin);
}

void TranslucentRadiosity::ApplySTransmitted(const std::vector<double>& x, std::vector<double>& y)
{
  y.assign(x.size(), 0.0);
  for (int k = 0; k < Scene_->GetNumberOfObjects(); ++k)
  {
    ApplyObject(k, x, y);
  }
}

void TranslucentRadiosity::ApplyS(const std::vector<double>& x, std::vector<double>& y)
{
  CheckReady();
  if (x.size() != 3 * static_cast<size_t>(Scene_->GetNumberOfPatches()))
  {
    throw Error("ApplyS: need 3 values per patch");
  }
  std::vector<double> q(x.size());
  for (size_t p = 0; p < Transmittance_.size(); ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      q[3 * p + c] = Transmittance_[p] * x[3 * p + c];
    }
  }
  ApplySTransmitted(q, y);
}

void TranslucentRadiosity::Solve(const std::vector<LightSource>& lights, RadiosityResult& result)
{
  CheckReady();
  result = RadiosityResult();
  for (auto& op : Operators_)
  {
    if (auto* diffusion = dynamic_cast<DiffusionSubsurface*>(op.get()))
    {
      // The diffusion solves need not be much more accurate than the
      // radiosity iteration: 1 % of its tolerance (5e-5 by default).
      diffusion->SetRelTol(std::min(1e-4, 0.01 * RelTol_));
    }
  }
  const int numPatches = Scene_->GetNumberOfPatches();
  const size_t n = 3 * static_cast<size_t>(numPatches);

  // Direct light E and the first bounce S E (paper eq. 7).
  auto start = Clock::now();
  std::vector<double> transmitted;
  Scene_->ComputeDirectIrradiance(lights, Shadows_, E_, transmitted);
  ApplySTransmitted(transmitted, SE_);
  result.DirectMilliseconds = MillisecondsSince(start);

  // B = sum_N (S F)^(N-1) S E = (I - S F)^-1 S E (paper eq. 13-14), iterated.
  start = Clock::now();
  std::vector<double> B = SE_, Bold, H, q;
  const double seNorm = Norm(SE_);
  for (int it = 0; it < MaxIter_; ++it)
  {
    Bold = B;
    if (Iteration_ == Iteration::Jacobi)
    {
      F_->Multiply(Bold, H); // irradiance from the other patches (paper eq. 10-12)
      q.resize(n);
      for (int p = 0; p < numPatches; ++p)
      {
        for (int c = 0; c < 3; ++c)
        {
          q[3 * p + c] = Transmittance_[p] * H[3 * p + c];
        }
      }
      ApplySTransmitted(q, B);
      for (size_t k = 0; k < n; ++k)
      {
        B[k] += SE_[k];
      }
    }
    else
    {
      // Block Gauss-Seidel: objects in turn, each with the newest B.
      for (int k = 0; k < Scene_->GetNumberOfObjects(); ++k)
      {
        const int begin = Scene_->GetPatchOffset(k), end = Scene_->GetPatchOffset(k + 1);
        const RadiosityObject& object = Scene_->GetObject(k);
        if (!object.Translucent)
        {
          for (int p = begin; p < end; ++p)
          {
            double h[3] = { 0.0, 0.0, 0.0 };
            for (int e = F_->RowOffsets[p]; e < F_->RowOffsets[p + 1]; ++e)
            {
              const double f = F_->Values[e];
              const double* b = &B[3 * static_cast<size_t>(F_->Columns[e])];
              h[0] += f * b[0];
              h[1] += f * b[1];
              h[2] += f * b[2];
            }
            for (int c = 0; c < 3; ++c)
            {
              B[3 * p + c] = SE_[3 * p + c] + object.Albedo[3 * (p - begin) + c] * h[c];
            }
          }
        }
        else
        {
          std::vector<double> local(3 * static_cast<size_t>(end - begin), 0.0), out;
#pragma omp parallel for schedule(static, 256) if (end - begin > 16384)
          for (int p = begin; p < end; ++p)
          {
            double h[3] = { 0.0, 0.0, 0.0 };
            for (int e = F_->RowOffsets[p]; e < F_->RowOffsets[p + 1]; ++e)
            {
              const double f = F_->Values[e];
              const double* b = &B[3 * static_cast<size_t>(F_->Columns[e])];
              h[0] += f * b[0];
              h[1] += f * b[1];
              h[2] += f * b[2];
            }
            for (int c = 0; c < 3; ++c)
            {
              local[3 * (p - begin) + c] = Transmittance_[p] * h[c];
            }
          }
          Operators_[k]->Apply(local, out);
          for (int p = begin; p < end; ++p)
          {
            for (int c = 0; c < 3; ++c)
            {
              B[3 * p + c] = SE_[3 * p + c] + out[3 * (p - begin) + c];
            }
          }
        }
      }
    }
    std::vector<double> diff(n);
    for (size_t k = 0; k < n; ++k)
    {
      diff[k] = B[k] - Bold[k];
    }
    const double norm = Norm(B);
    if (!std::isfinite(norm))
    {
      // A NaN norm would read as "no change" below: never converge on it.
      RequireFinite(B, "radiosity B (iteration " + std::to_string(it + 1) + ")", OverflowCause());
      throw Error("radiosity B overflows (its norm is " + FormatNumber(norm) + " at iteration " +
        std::to_string(it + 1) + ")" + OverflowCause());
    }
    const double change = norm > 0.0 ? Norm(diff) / norm : 0.0;
    result.ResidualHistory.push_back(change);
    result.Iterations = it + 1;
    if (change <= RelTol_ || seNorm == 0.0)
    {
      result.Converged = true;
      break;
    }
  }
  result.SolveMilliseconds = MillisecondsSince(start);

  const std::vector<double> albedo = GetDiffuseAlbedo();
  result.DirectIrradiance = E_;
  result.Direct.resize(n);
  result.InterReflection.resize(n);
  for (size_t k = 0; k < n; ++k)
  {
    result.Direct[k] = albedo[k] * E_[k];
    result.InterReflection[k] = B[k] - SE_[k];
  }
  result.FirstBounce = SE_;
  result.Combined = std::move(B);
}

void TranslucentRadiosity::ComputeTranslucentAlbedo(int k)
{
  const RadiosityObject& object = Scene_->GetObject(k);
  const int begin = Scene_->GetPatchOffset(k), end = Scene_->GetPatchOffset(k + 1);
  TranslucentAlbedo_.resize(3 * static_cast<size_t>(Scene_->GetNumberOfPatches()), 0.0);
  // One T_u and R_d per tet material value (the quadrature of T_u is not free).
  double lastEta = -1.0, tu = 0.0;
  for (int p = begin; p < end; ++p)
  {
    const int tet = object.Mesh->GetBoundaryTriangleTets()[p - begin];
    const double eta = object.Material.RefractiveIndex[tet];
    if (eta != lastEta)
    {
      tu = Fresnel::UniformTransmittance(eta);
      lastEta = eta;
    }
    for (int c = 0; c < 3; ++c)
    {
      TranslucentAlbedo_[3 * p + c] = tu *
        DipoleTotalReflectance(object.Material.AbsorptionCoefficient[3 * tet + c],
          object.Material.ReducedScatteringCoefficient[3 * tet + c], eta);
    }
  }
}

std::vector<double> TranslucentRadiosity::GetDiffuseAlbedo()
{
  CheckReady();
  std::vector<double> albedo(3 * static_cast<size_t>(Scene_->GetNumberOfPatches()), 0.0);
  for (int k = 0; k < Scene_->GetNumberOfObjects(); ++k)
  {
    const RadiosityObject& object = Scene_->GetObject(k);
    const int begin = Scene_->GetPatchOffset(k), end = Scene_->GetPatchOffset(k + 1);
    if (object.Translucent)
    {
      std::copy(TranslucentAlbedo_.begin() + 3 * begin, TranslucentAlbedo_.begin() + 3 * end,
        albedo.begin() + 3 * begin);
    }
    else
    {
      std::copy(object.Albedo.begin(), object.Albedo.end(), albedo.begin() + 3 * begin);
    }
  }
  return albedo;
}

void TranslucentRadiosity::SolveHeuristics(std::vector<double>& h1, std::vector<double>& h2)
{
  if (SE_.empty())
  {
    throw Error("SolveHeuristics: call Solve() first");
  }
  const std::vector<double> P = GetDiffuseAlbedo();
  const size_t n = P.size();
  // x = b + P F x by Jacobi (classical diffuse radiosity, paper eq. 2).
  auto diffuse = [&](const std::vector<double>& b) {
    std::vector<double> x = b, fx;
    for (int it = 0; it < MaxIter_; ++it)
    {
      F_->Multiply(x, fx);
      std::vector<double> next(n);
      double dn = 0.0;
      for (size_t k = 0; k < n; ++k)
      {
        next[k] = b[k] + P[k] * fx[k];
      }
      std::vector<double> diff(n);
      for (size_t k = 0; k < n; ++k)
      {
        diff[k] = next[k] - x[k];
      }
      x.swap(next);
      dn = Norm(diff);
      const double nx = Norm(x);
      if (nx == 0.0 || dn <= RelTol_ * nx)
      {
        break;
      }
    }
    return x;
  };
  // Paper Sec. 6.3, first heuristic: (I - F)^-1 S E, F taken with the
  // diffuse albedo (I - P F) so that it converges.
  h1 = diffuse(SE_);
  // Second heuristic: S E + (I - F)^-1 E, read as S E plus the inter-reflected
  // part of classical radiosity, (I - P F)^-1 P E - P E.
  std::vector<double> pe(n);
  for (size_t k = 0; k < n; ++k)
  {
    pe[k] = P[k] * E_[k];
  }
  std::vector<double> classical = diffuse(pe);
  h2.resize(n);
  for (size_t k = 0; k < n; ++k)
  {
    h2[k] = SE_[k] + classical[k] - pe[k];
  }
}

std::array<double, 3> TranslucentRadiosity::EstimateSpectralRadius(int iterations)
{
  CheckReady();
  const int numPatches = Scene_->GetNumberOfPatches();
  std::array<double, 3> rho{ 0.0, 0.0, 0.0 };
  std::vector<double> x(3 * static_cast<size_t>(numPatches), 1.0), fx, y;
  const std::vector<double>& areas = Scene_->GetAreas();
  auto channelNorm = [&](const std::vector<double>& v, int c) {
    double s = 0.0;
    for (int p = 0; p < numPatches; ++p)
    {
      s += areas[p] * v[3 * p + c] * v[3 * p + c];
    }
    return std::sqrt(s);
  };
  for (int it = 0; it < iterations; ++it)
  {
    F_->Multiply(x, fx);
    ApplyS(fx, y);
    for (int c = 0; c < 3; ++c)
    {
      const double nx = channelNorm(x, c), ny = channelNorm(y, c);
      rho[c] = nx > 0.0 ? ny / nx : 0.0;
      for (int p = 0; p < numPatches; ++p)
      {
        x[3 * p + c] = ny > 0.0 ? y[3 * p + c] / ny : 0.0;
      }
    }
  }
  return rho;
}

std::size_t TranslucentRadiosity::GetSubsurfaceMemoryBytes() const
{
  std::size_t bytes = 0;
  for (const auto& op : Operators_)
  {
    if (op)
    {
      bytes += op->GetMemoryBytes();
    }
  }
  return bytes;
}

} // namespace translucency
