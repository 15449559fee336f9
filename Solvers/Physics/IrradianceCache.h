/**
 * @file IrradianceCache.h
 * @brief ComputeProjectedIrradiance() kept across the calls of an
 * interactive session: each light's term is computed once and kept while
 * the light, the geometry and the refractive index stay the same, so a
 * change of one light (the user turns it) recomputes that light only.
 *
 * What is kept (issue 31):
 *  - per directional, point or spot light (coloured or not): its corner
 *    irradiance, 9 doubles per boundary triangle (AddLightCornerIrradiance():
 *    the DirectIrradiance() terms times the visibility from one shadow ray
 *    per point and light), keyed on every field of the LightSource and on
 *    the shadow flag;
 *  - the uniform light's per-point irradiance (its occlusion sampling, the
 *    costliest part), keyed on its irradiance, samples and the shadow flag;
 *  - the ShadowCaster over the boundary triangles and the triangle normals;
 * all keyed on the TetMesh's geometry revision (process-wide unique) and the
 * refractive index of every tet (compared bit for bit): another geometry or
 * index forgets everything.
 *
 * The result equals ComputeProjectedIrradiance() of the same arguments bit
 * for bit: each corner sums the uniform term, then the lights' terms in the
 * order of `lights`, exactly as the full computation does (a corner that a
 * light does not reach adds 0.0).
 *
 * Memory: 72 bytes per boundary triangle and light, 24 per point for the
 * uniform light, the ray caster (GetMemoryBytes()).
 */
#pragma once

#include "LightSources.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace translucency
{

class ShadowCaster;

class IrradianceCache
{
public:
  IrradianceCache();
  ~IrradianceCache();
  IrradianceCache(const IrradianceCache&) = delete;
  IrradianceCache& operator=(const IrradianceCache&) = delete;

  /**
   * ComputeProjectedIrradiance(mesh, tetEta, lights, uniformIrradiance,
   * uniformSamples, shadows, q, abort), re-using the terms kept from the
   * previous calls (see the file comment). Same arguments, errors and abort
   * contract; an aborted call keeps only the terms that were complete.
   */
  bool Compute(const TetMesh& mesh, const std::vector<double>& tetEta,
    const std::vector<LightSource>& lights, double uniformIrradiance, int uniformSamples,
    bool shadows, std::vector<double>& q, const std::function<bool()>& abort = {});

  ///@{
  /// What the last Compute() computed (the rest came from the cache): the
  /// number of lights, and whether the uniform light's term.
  int GetNumberOfLightsComputed() const { return LightsComputed_; }
  bool GetUniformComputed() const { return UniformComputed_; }
  ///@}

  /// Forget every kept term.
  void Clear();

  /// Bytes held by the kept terms, normals and index, and about those of the ray caster.
  std::size_t GetMemoryBytes() const;

private:
  struct Entry
  {
    LightSource Light;
    bool Shadows = true;
    std::vector<double> Corners; ///< 9 per boundary triangle
  };
  static bool SameLight(const LightSource& a, const LightSource& b);
  void Rekey(const TetMesh& mesh, const std::vector<double>& tetEta);

  std::uint64_t Revision_ = 0;
  std::vector<double> TetEta_;
  std::vector<double> Normals_;
  double Diagonal_ = 0.0;
  std::unique_ptr<ShadowCaster> Caster_; ///< built at the first shadowed light
  bool HaveUniform_ = false;
  double UniformIrradiance_ = 0.0;
  int UniformSamples_ = 0;
  bool UniformShadows_ = false;
  std::vector<double> Uniform_; ///< 3 per mesh point
  std::vector<Entry> Entries_;
  int LightsComputed_ = 0;
  bool UniformComputed_ = false;
};

} // namespace translucency
