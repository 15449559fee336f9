#include "IrradianceCache.h"

#include "Radiance.h"
#include "ShadowCaster.h"
#include "TetMesh.h"

#include <cstring>

namespace translucency
{

IrradianceCache::IrradianceCache() = default;
IrradianceCache::~IrradianceCache() = default;

bool IrradianceCache::SameLight(const LightSource& a, const LightSource& b)
{
  return a.Type == b.Type && a.Direction == b.Direction && a.Position == b.Position &&
    a.Power == b.Power && a.SpotCutoff == b.SpotCutoff && a.SpotExponent == b.SpotExponent;
}

void IrradianceCache::Clear()
{
  Revision_ = 0;
  TetEta_.clear();
  Normals_.clear();
  Diagonal_ = 0.0;
  Caster_.reset();
  HaveUniform_ = false;
  Uniform_.clear();
  Entries_.clear();
}

void IrradianceCache::Rekey(const TetMesh& mesh, const std::vector<double>& tetEta)
{
  const bool sameEta = TetEta_.size() == tetEta.size() &&
    std::memcmp(TetEta_.data(), tetEta.data(), tetEta.size() * sizeof(double)) == 0;
  if (Revision_ == mesh.GetGeometryRevision() && Revision_ != 0 && sameEta)
  {
    return;
  }
  Clear();
  Revision_ = mesh.GetGeometryRevision();
  TetEta_ = tetEta;
  Normals_ = BoundaryTriangleNormals(mesh);
  Diagonal_ = BoundingBoxDiagonal(mesh);
}

std::size_t IrradianceCache::GetMemoryBytes() const
{
  std::size_t bytes = (TetEta_.size() + Normals_.size() + Uniform_.size()) * sizeof(double);
  for (const Entry& e : Entries_)
  {
    bytes += e.Corners.size() * sizeof(double);
  }
  // The ray caster: about one node (52 bytes) and one id per triangle.
  return bytes + (Caster_ ? Caster_->GetMemoryBytes() : 0);
}

bool IrradianceCache::Compute(const TetMesh& mesh, const std::vector<double>& tetEta,
  const std::vector<LightSource>& lights, double uniformIrradiance, int uniformSamples,
  bool shadows, std::vector<double>& q, const std::function<bool()>& abort)
{
  LightsComputed_ = 0;
  UniformComputed_ = false;
  // The checks of the full computation, before any work.
  CheckBoundaryTriangleEta(mesh, tetEta);
  for (size_t l = 0; l < lights.size(); ++l)
  {
    ValidateLight(lights[l], l);
  }
  Rekey(mesh, tetEta);

  // The uniform light per point (its arguments are checked there).
  if (!HaveUniform_ || UniformIrradiance_ != uniformIrradiance ||
    UniformSamples_ != uniformSamples || UniformShadows_ != shadows)
  {
    HaveUniform_ = false;
    if (!ComputeBoundaryIrradiance(mesh, PointRefractiveIndex(mesh, tetEta), {},
          uniformIrradiance, uniformSamples, shadows, Uniform_, abort))
    {
      return false;
    }
    HaveUniform_ = true;
    UniformIrradiance_ = uniformIrradiance;
    UniformSamples_ = uniformSamples;
    UniformShadows_ = shadows;
    UniformComputed_ = true;
  }

  // Each light: its kept term, or computed now.
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  std::vector<Entry> kept;
  kept.reserve(lights.size());
  for (const LightSource& light : lights)
  {
    auto found = Entries_.end();
    for (auto it = Entries_.begin(); it != Entries_.end(); ++it)
    {
      if (it->Shadows == shadows && !it->Corners.empty() && SameLight(it->Light, light))
      {
        found = it;
        break;
      }
    }
    if (found != Entries_.end())
    {
      kept.push_back(std::move(*found)); // leaves an empty entry behind: not found again
      found->Corners.clear();
      continue;
    }
    Entry entry;
    entry.Light = light;
    entry.Shadows = shadows;
    entry.Corners.assign(9 * static_cast<size_t>(numTriangles), 0.0);
    if (shadows && !Caster_)
    {
      Caster_ = std::make_unique<ShadowCaster>();
      Caster_->Build(mesh.GetPoints(), triangles);
    }
    if (!AddLightCornerIrradiance(mesh, tetEta, Normals_, light, shadows, Caster_.get(),
          Diagonal_, entry.Corners, abort))
    {
      // Keep the complete terms, the old ones and those of this call.
      for (Entry& e : Entries_)
      {
        if (!e.Corners.empty())
        {
          kept.push_back(std::move(e));
        }
      }
      Entries_ = std::move(kept);
      return false;
    }
    ++LightsComputed_;
    kept.push_back(std::move(entry));
  }
  Entries_ = std::move(kept);

  // The corners: the uniform light of the point, then each light's term in
  // the order of `lights`, as ComputeTriangleCornerIrradiance sums them.
  std::vector<double> cornerQ(9 * static_cast<size_t>(numTriangles), 0.0);
  for (int f = 0; f < numTriangles; ++f)
  {
    for (int k = 0; k < 3; ++k)
    {
      const int i = triangles[3 * static_cast<size_t>(f) + k];
      for (int c = 0; c < 3; ++c)
      {
        cornerQ[9 * static_cast<size_t>(f) + 3 * k + c] = Uniform_[3 * static_cast<size_t>(i) + c];
      }
    }
  }
  for (const Entry& e : Entries_)
  {
    const double* term = e.Corners.data();
    double* sum = cornerQ.data();
    for (size_t j = 0; j < cornerQ.size(); ++j)
    {
      sum[j] += term[j];
    }
  }
  ProjectCornerIrradiance(mesh, cornerQ, q);
  return true;
}

} // namespace translucency
