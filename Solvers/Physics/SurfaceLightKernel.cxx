#include "SurfaceLightKernel.h"

#include "Error.h"
#include "Fresnel.h"
#include "ShadowCaster.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>

namespace translucency
{

namespace
{
/// ComputeSurfacePointIrradiance's input checks (the errors it lists).
void CheckSurfaceLightInputs(const BoundarySurface& surface, const std::vector<int>& points,
  const std::vector<double>& rotations, const std::vector<LightSource>& lights,
  double uniformIrradiance, int uniformSamples, bool shadows)
{
  const int numPoints = static_cast<int>(surface.GetNumberOfPoints());
  const int numTriangles = static_cast<int>(surface.GetNumberOfTriangles());
  if (surface.TriangleEta.size() != static_cast<std::size_t>(numTriangles) ||
    rotations.size() != points.size())
  {
    std::ostringstream msg;
    msg << "surface irradiance: " << surface.TriangleEta.size() << " refractive indices for "
        << numTriangles << " triangles, " << rotations.size() << " rotations for "
        << points.size() << " points";
    throw Error(msg.str());
  }
  for (int i : points)
  {
    if (i < 0 || i >= numPoints)
    {
      throw Error("surface irradiance: point " + std::to_string(i) + " is not one of the " +
        std::to_string(numPoints) + " surface points");
    }
  }
  for (int f = 0; f < numTriangles; ++f)
  {
    const double eta = surface.TriangleEta[f];
    if (!(eta > 0.0) || !std::isfinite(eta))
    {
      std::ostringstream msg;
      msg << "surface irradiance: the refractive index under surface triangle " << f << " is "
          << eta << ": must be finite and > 0";
      throw Error(msg.str());
    }
  }
  if (!(uniformIrradiance >= 0.0) || !std::isfinite(uniformIrradiance))
  {
    std::ostringstream msg;
    msg << "boundary irradiance: uniform irradiance " << uniformIrradiance
        << " W/mm^2: must be finite and >= 0";
    throw Error(msg.str());
  }
  if (uniformSamples < 0)
  {
    throw Error("boundary irradiance: " + std::to_string(uniformSamples) +
      " uniform light samples: must be >= 0");
  }
  if (shadows && uniformIrradiance > 0.0 &&
    static_cast<double>(numPoints) * uniformSamples > 8589934592.0)
  {
    throw Error("boundary irradiance: " + std::to_string(uniformSamples) +
      " uniform light samples x " + std::to_string(numPoints) +
      " boundary points: above the budget of 8.6e9 shadow rays: use fewer samples");
  }
  for (std::size_t l = 0; l < lights.size(); ++l)
  {
    ValidateLight(lights[l], l);
  }
}

/// ComputeSurfacePointIrradiance: per triangle, area vector / 2
/// (TetMesh::ComputeMeasures) and unit normal (ComputeTriangleCornerIrradiance);
/// per point, area and normal sums in triangle order and its triangles in
/// increasing order (as TetMesh's incidence).
struct SurfaceMeasures
{
  std::vector<double> Areas, UnitNormals, PointArea, PointNormal;
  std::vector<int> Offsets, Incident;
};

SurfaceMeasures MeasureSurface(const BoundarySurface& surface)
{
  const int numPoints = static_cast<int>(surface.GetNumberOfPoints());
  const int numTriangles = static_cast<int>(surface.GetNumberOfTriangles());
  SurfaceMeasures out;
  std::vector<double>& areas = out.Areas;
  std::vector<double>& unitNormals = out.UnitNormals;
  std::vector<double>& pointArea = out.PointArea;
  std::vector<double>& pointNormal = out.PointNormal;
  std::vector<int>& offsets = out.Offsets;
  std::vector<int>& incident = out.Incident;
  areas.assign(static_cast<std::size_t>(numTriangles), 0.0);
  unitNormals.assign(3 * static_cast<std::size_t>(numTriangles), 0.0);
  pointArea.assign(static_cast<std::size_t>(numPoints), 0.0);
  pointNormal.assign(3 * static_cast<std::size_t>(numPoints), 0.0);
  offsets.assign(static_cast<std::size_t>(numPoints) + 1, 0);
  for (int f = 0; f < numTriangles; ++f)
  {
    const int* tri = &surface.Triangles[3 * static_cast<std::size_t>(f)];
    const double* a = &surface.Points[3 * static_cast<std::size_t>(tri[0])];
    const double* b = &surface.Points[3 * static_cast<std::size_t>(tri[1])];
    const double* c = &surface.Points[3 * static_cast<std::size_t>(tri[2])];
    const double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
    const double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
    double n[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
      e1[0] * e2[1] - e1[1] * e2[0] };
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    double* u = &unitNormals[3 * static_cast<std::size_t>(f)];
    for (int k = 0; k < 3; ++k)
    {
      u[k] = length > 0.0 ? n[k] / length : 0.0;
      n[k] *= 0.5;
    }
    const double area = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    areas[f] = area;
    for (int m = 0; m < 3; ++m)
    {
      const std::size_t i = static_cast<std::size_t>(tri[m]);
      pointArea[i] += area;
      pointNormal[3 * i + 0] += n[0];
      pointNormal[3 * i + 1] += n[1];
      pointNormal[3 * i + 2] += n[2];
      ++offsets[i + 1];
    }
  }
  for (int i = 0; i < numPoints; ++i)
  {
    double* n = &pointNormal[3 * static_cast<std::size_t>(i)];
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (pointArea[i] > 0.0 && length > 0.0)
    {
      n[0] /= length;
      n[1] /= length;
      n[2] /= length;
    }
    offsets[i + 1] += offsets[i];
  }
  // Each point's triangles in increasing order (as TetMesh's incidence).
  incident.assign(static_cast<std::size_t>(offsets.back()), 0);
  {
    std::vector<int> cursor(offsets.begin(), offsets.end() - 1);
    for (int f = 0; f < numTriangles; ++f)
    {
      for (int m = 0; m < 3; ++m)
      {
        incident[cursor[surface.Triangles[3 * static_cast<std::size_t>(f) + m]]++] = f;
      }
    }
  }
  return out;
}

/// Per entry k of the points asked for: its corners' slots
/// [slots[k], slots[k + 1]) (one per triangle around the point, in the
/// order of SurfaceMeasures::Incident; 3 values each).
std::vector<int> CornerSlots(const SurfaceMeasures& measures, const std::vector<int>& points)
{
  std::vector<int> slots(points.size() + 1, 0);
  for (std::size_t k = 0; k < points.size(); ++k)
  {
    const std::size_t i = static_cast<std::size_t>(points[k]);
    slots[k + 1] = slots[k] + measures.Offsets[i + 1] - measures.Offsets[i];
  }
  return slots;
}

/// The shadow rays against the whole surface (the ray caster built by
/// Prepare(), before any parallel loop asks).
class Occlusion
{
public:
  explicit Occlusion(const BoundarySurface& surface)
    : Surface_(surface)
    , Offset_(1e-5 * surface.Diagonal)
  {
  }
  void Prepare()
  {
    if (!Caster_ && Surface_.GetNumberOfTriangles() > 0)
    {
      Caster_ = std::make_unique<ShadowCaster>();
      Caster_->Build(Surface_.Points, Surface_.Triangles);
    }
  }
  bool operator()(const double* x, const double* n, const double* w, double reach) const
  {
    const double origin[3] = { x[0] + Offset_ * (n[0] + w[0]), x[1] + Offset_ * (n[1] + w[1]),
      x[2] + Offset_ * (n[2] + w[2]) };
    return Caster_ && Caster_->Occluded(origin, w, reach);
  }
  std::size_t GetMemoryBytes() const
  {
    // About one node (52 bytes) and one id per triangle.
    return Caster_ ? Caster_->GetMemoryBytes() : 0;
  }

private:
  const BoundarySurface& Surface_;
  double Offset_;
  std::unique_ptr<ShadowCaster> Caster_;
};

/// An OpenMP loop over the points asked for, body(k) for each, checking
/// `abort` every 64 points on thread 0; false if aborted.
template <typename Body>
bool ForEachPoint(int count, const std::function<bool()>& abort, const Body& body)
{
  std::atomic<bool> aborted(false);
#pragma omp parallel for schedule(dynamic, 64)
  for (int k = 0; k < count; ++k)
  {
    if (aborted.load(std::memory_order_relaxed))
    {
      continue;
    }
    if (abort && k % 64 == 0 && omp_get_thread_num() == 0 && abort())
    {
      aborted.store(true, std::memory_order_relaxed);
      continue;
    }
    body(k);
  }
  return !aborted.load();
}

/// The uniform light's term per point (ComputeBoundaryIrradiance with the
/// point's area-weighted eta): qu gets one value per entry of `points`.
bool UniformTerm(const BoundarySurface& surface, const SurfaceMeasures& measures,
  const Occlusion& occluded, const std::vector<int>& points, const std::vector<double>& rotations,
  double uniformIrradiance, int uniformSamples, bool shadows, std::vector<double>& qu,
  const std::function<bool()>& abort)
{
  qu.assign(points.size(), 0.0);
  if (!(uniformIrradiance > 0.0))
  {
    return true;
  }
  const double diag = surface.Diagonal;
  return ForEachPoint(static_cast<int>(points.size()), abort, [&](int k) {
    const int i = points[k];
    if (!(measures.PointArea[i] > 0.0))
    {
      return; // not a boundary point of the serial mesh
    }
    const double* x = &surface.Points[3 * static_cast<std::size_t>(i)];
    const double* ni = &measures.PointNormal[3 * static_cast<std::size_t>(i)];
    double etaSum = 0.0;
    for (int m = measures.Offsets[i]; m < measures.Offsets[i + 1]; ++m)
    {
      const int f = measures.Incident[m];
      etaSum += measures.Areas[f] * surface.TriangleEta[f];
    }
    const double eta = etaSum / measures.PointArea[i];
    double value = 0.0;
    if (!shadows || uniformSamples == 0)
    {
      value = uniformIrradiance * Fresnel::UniformTransmittance(eta);
    }
    else
    {
      for (int s = 0; s < uniformSamples; ++s)
      {
        double w[3];
        const double cosTheta = HemisphereDirection(ni, s, uniformSamples, rotations[k], w);
        if (!occluded(x, ni, w, 2.0 * diag))
        {
          value += Fresnel::Transmittance(cosTheta, eta);
        }
      }
      value *= uniformIrradiance / uniformSamples;
    }
    qu[k] = value;
  });
}

/// One light's corner terms: 3 values per slot (CornerSlots), the light's
/// DirectIrradiance() at the corner if the point's shadow ray is free, 0
/// where it does not reach.
bool LightTerm(const BoundarySurface& surface, const SurfaceMeasures& measures,
  const Occlusion& occluded, const std::vector<int>& points, const std::vector<int>& slots,
  const LightSource& light, bool shadows, std::vector<double>& corners,
  const std::function<bool()>& abort)
{
  corners.assign(3 * static_cast<std::size_t>(slots.back()), 0.0);
  const double diag = surface.Diagonal;
  return ForEachPoint(static_cast<int>(points.size()), abort, [&](int k) {
    const int i = points[k];
    if (!(measures.PointArea[i] > 0.0))
    {
      return;
    }
    const double* x = &surface.Points[3 * static_cast<std::size_t>(i)];
    const double* ni = &measures.PointNormal[3 * static_cast<std::size_t>(i)];
    const int begin = measures.Offsets[i], end = measures.Offsets[i + 1];
    int visible = -1;
    for (int m = begin; m < end; ++m)
    {
      const int f = measures.Incident[m];
      double ql[3], w[3], distance;
      if (!DirectIrradiance(light, x, &measures.UnitNormals[3 * static_cast<std::size_t>(f)],
            surface.TriangleEta[f], ql, w, distance))
      {
        continue;
      }
      if (shadows && visible < 0)
      {
        visible = occluded(x, ni, w, std::min(distance, 2.0 * diag)) ? 0 : 1;
      }
      if (shadows && visible == 0)
      {
        break;
      }
      double* qc = &corners[3 * static_cast<std::size_t>(slots[k] + m - begin)];
      for (int c = 0; c < 3; ++c)
      {
        qc[c] += ql[c];
      }
    }
  });
}

/// The corners (the uniform term, then each light's in order) projected
/// to the points (ProjectCornerIrradiance): 3 values per entry in q.
void ProjectCorners(const SurfaceMeasures& measures, const std::vector<int>& points,
  const std::vector<int>& slots, const std::vector<double>& qu,
  const std::vector<const std::vector<double>*>& terms, std::vector<double>& q)
{
  q.assign(3 * points.size(), 0.0);
  ForEachPoint(static_cast<int>(points.size()), {}, [&](int k) {
    const int i = points[k];
    if (!(measures.PointArea[i] > 0.0))
    {
      return;
    }
    const int begin = measures.Offsets[i], end = measures.Offsets[i + 1];
    double load[3] = { 0.0, 0.0, 0.0 };
    double area = 0.0;
    for (int m = begin; m < end; ++m)
    {
      const int f = measures.Incident[m];
      const std::size_t slot = 3 * static_cast<std::size_t>(slots[k] + m - begin);
      double corner[3] = { qu[k], qu[k], qu[k] };
      for (const std::vector<double>* term : terms)
      {
        for (int c = 0; c < 3; ++c)
        {
          corner[c] += (*term)[slot + c];
        }
      }
      area += measures.Areas[f];
      for (int c = 0; c < 3; ++c)
      {
        load[c] += measures.Areas[f] * corner[c];
      }
    }
    if (area > 0.0)
    {
      for (int c = 0; c < 3; ++c)
      {
        q[3 * static_cast<std::size_t>(k) + c] = load[c] / area;
      }
    }
  });
}

bool NeedRays(const std::vector<LightSource>& lights, double uniformIrradiance,
  int uniformSamples, bool shadows)
{
  return shadows && (!lights.empty() || (uniformIrradiance > 0.0 && uniformSamples > 0));
}

} // namespace

std::size_t BoundarySurface::GetMemoryBytes() const
{
  return Points.capacity() * sizeof(double) + Triangles.capacity() * sizeof(int) +
    TriangleEta.capacity() * sizeof(double);
}

bool ComputeSurfacePointIrradiance(const BoundarySurface& surface,
  const std::vector<int>& points, const std::vector<double>& rotations,
  const std::vector<LightSource>& lights, double uniformIrradiance, int uniformSamples,
  bool shadows, std::vector<double>& q, const std::function<bool()>& abort)
{
  CheckSurfaceLightInputs(surface, points, rotations, lights, uniformIrradiance, uniformSamples,
    shadows);
  const SurfaceMeasures measures = MeasureSurface(surface);
  const std::vector<int> slots = CornerSlots(measures, points);
  Occlusion occluded(surface);
  if (NeedRays(lights, uniformIrradiance, uniformSamples, shadows))
  {
    occluded.Prepare();
  }
  q.assign(3 * points.size(), 0.0);
  if (abort && abort())
  {
    return false;
  }
  std::vector<double> qu;
  if (!UniformTerm(surface, measures, occluded, points, rotations, uniformIrradiance,
        uniformSamples, shadows, qu, abort))
  {
    return false;
  }
  std::vector<std::vector<double>> terms(lights.size());
  std::vector<const std::vector<double>*> order;
  for (std::size_t l = 0; l < lights.size(); ++l)
  {
    if (!LightTerm(surface, measures, occluded, points, slots, lights[l], shadows, terms[l], abort))
    {
      return false;
    }
    order.push_back(&terms[l]);
  }
  ProjectCorners(measures, points, slots, qu, order, q);
  return true;
}

struct SurfacePointIrradianceCache::Impl
{
  struct Entry
  {
    LightSource Light;
    bool Shadows = true;
    std::vector<double> Corners; ///< 3 per slot
  };
  static bool SameLight(const LightSource& a, const LightSource& b)
  {
    return a.Type == b.Type && a.Direction == b.Direction && a.Position == b.Position &&
      a.Power == b.Power && a.SpotCutoff == b.SpotCutoff && a.SpotExponent == b.SpotExponent;
  }

  bool HaveSurface = false;
  BoundarySurface Surface;
  std::vector<int> Points;
  std::vector<double> Rotations;
  SurfaceMeasures Measures;
  std::vector<int> Slots;
  std::unique_ptr<Occlusion> Occluded;
  bool HaveUniform = false;
  double UniformIrradiance = 0.0;
  int UniformSamples = 0;
  bool UniformShadows = false;
  std::vector<double> Uniform; ///< 1 per point
  std::vector<Entry> Entries;
  int LightsComputed = 0;
  bool UniformComputed = false;
};

SurfacePointIrradianceCache::SurfacePointIrradianceCache()
  : Impl_(std::make_unique<Impl>())
{
}

SurfacePointIrradianceCache::~SurfacePointIrradianceCache() = default;

void SurfacePointIrradianceCache::Clear()
{
  Impl_ = std::make_unique<Impl>();
}

void SurfacePointIrradianceCache::SetSurface(
  BoundarySurface surface, std::vector<int> points, std::vector<double> rotations)
{
  Clear();
  Impl& in = *Impl_;
  const int numPoints = static_cast<int>(surface.GetNumberOfPoints());
  if (rotations.size() != points.size())
  {
    throw Error("surface irradiance: " + std::to_string(rotations.size()) + " rotations for " +
      std::to_string(points.size()) + " points");
  }
  for (int i : points)
  {
    if (i < 0 || i >= numPoints)
    {
      throw Error("surface irradiance: point " + std::to_string(i) + " is not one of the " +
        std::to_string(numPoints) + " surface points");
    }
  }
  in.Surface = std::move(surface);
  in.Points = std::move(points);
  in.Rotations = std::move(rotations);
  in.Measures = MeasureSurface(in.Surface);
  in.Slots = CornerSlots(in.Measures, in.Points);
  in.Occluded = std::make_unique<Occlusion>(in.Surface);
  in.HaveSurface = true;
}

bool SurfacePointIrradianceCache::HasSurface() const
{
  return Impl_->HaveSurface;
}

const BoundarySurface& SurfacePointIrradianceCache::GetSurface() const
{
  return Impl_->Surface;
}

int SurfacePointIrradianceCache::GetNumberOfLightsComputed() const
{
  return Impl_->LightsComputed;
}

bool SurfacePointIrradianceCache::GetUniformComputed() const
{
  return Impl_->UniformComputed;
}

std::size_t SurfacePointIrradianceCache::GetMemoryBytes() const
{
  const Impl& in = *Impl_;
  const SurfaceMeasures& m = in.Measures;
  std::size_t bytes = in.Surface.GetMemoryBytes() +
    (in.Rotations.capacity() + in.Uniform.capacity() + m.Areas.capacity() +
      m.UnitNormals.capacity() + m.PointArea.capacity() + m.PointNormal.capacity()) *
      sizeof(double) +
    (in.Points.capacity() + in.Slots.capacity() + m.Offsets.capacity() + m.Incident.capacity()) *
      sizeof(int);
  for (const Impl::Entry& e : in.Entries)
  {
    bytes += e.Corners.capacity() * sizeof(double);
  }
  return bytes + (in.Occluded ? in.Occluded->GetMemoryBytes() : 0);
}

bool SurfacePointIrradianceCache::Compute(const std::vector<LightSource>& lights,
  double uniformIrradiance, int uniformSamples, bool shadows, std::vector<double>& q,
  const std::function<bool()>& abort)
{
  Impl& in = *Impl_;
  in.LightsComputed = 0;
  in.UniformComputed = false;
  if (!in.HaveSurface)
  {
    throw Error("surface irradiance: Compute() called before SetSurface()");
  }
  CheckSurfaceLightInputs(in.Surface, in.Points, in.Rotations, lights, uniformIrradiance,
    uniformSamples, shadows);
  q.assign(3 * in.Points.size(), 0.0);
  if (abort && abort())
  {
    return false;
  }

  // The uniform light per point, unless kept.
  if (!in.HaveUniform || in.UniformIrradiance != uniformIrradiance ||
    in.UniformSamples != uniformSamples || in.UniformShadows != shadows)
  {
    in.HaveUniform = false;
    if (NeedRays({}, uniformIrradiance, uniformSamples, shadows))
    {
      in.Occluded->Prepare();
    }
    if (!UniformTerm(in.Surface, in.Measures, *in.Occluded, in.Points, in.Rotations,
          uniformIrradiance, uniformSamples, shadows, in.Uniform, abort))
    {
      return false;
    }
    in.HaveUniform = true;
    in.UniformIrradiance = uniformIrradiance;
    in.UniformSamples = uniformSamples;
    in.UniformShadows = shadows;
    in.UniformComputed = true;
  }

  // Each light: its kept term, or computed now.
  std::vector<Impl::Entry> kept;
  kept.reserve(lights.size());
  for (const LightSource& light : lights)
  {
    auto found = in.Entries.end();
    for (auto it = in.Entries.begin(); it != in.Entries.end(); ++it)
    {
      if (it->Shadows == shadows && !it->Corners.empty() && Impl::SameLight(it->Light, light))
      {
        found = it;
        break;
      }
    }
    if (found != in.Entries.end())
    {
      kept.push_back(std::move(*found)); // leaves an empty entry behind: not found again
      found->Corners.clear();
      continue;
    }
    Impl::Entry entry;
    entry.Light = light;
    entry.Shadows = shadows;
    if (shadows)
    {
      in.Occluded->Prepare();
    }
    if (!LightTerm(in.Surface, in.Measures, *in.Occluded, in.Points, in.Slots, light, shadows,
          entry.Corners, abort))
    {
      // Keep the complete terms, the old ones and those of this call.
      for (Impl::Entry& e : in.Entries)
      {
        if (!e.Corners.empty())
        {
          kept.push_back(std::move(e));
        }
      }
      in.Entries = std::move(kept);
      return false;
    }
    ++in.LightsComputed;
    kept.push_back(std::move(entry));
  }
  in.Entries = std::move(kept);

  // The corners: the uniform term, then each light's in the order of `lights`.
  std::vector<const std::vector<double>*> order;
  for (const Impl::Entry& e : in.Entries)
  {
    order.push_back(&e.Corners);
  }
  ProjectCorners(in.Measures, in.Points, in.Slots, in.Uniform, order, q);
  return true;
}

} // namespace translucency
