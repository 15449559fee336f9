#include "ShadowCaster.h"

#include "Error.h"

#ifdef TRANSLUCENCY_HAVE_EMBREE
#include <embree3/rtcore.h>
#endif

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <sstream>
#include <string>

namespace translucency
{

#ifdef TRANSLUCENCY_HAVE_EMBREE
namespace
{

/// The process's Embree device, made at the first use (thread-safe).
RTCDevice Device()
{
  static std::once_flag once;
  static RTCDevice device = nullptr;
  std::call_once(once, [] { device = rtcNewDevice(nullptr); });
  if (!device)
  {
    throw Error("ShadowCaster: Embree could not create a device (error " +
      std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
  }
  return device;
}

} // namespace

/// The Embree scene of one surface; its coordinates relative to Centre.
struct ShadowCaster::EmbreeScene
{
  RTCScene Scene = nullptr;
  double Centre[3] = { 0.0, 0.0, 0.0 };
  ~EmbreeScene()
  {
    if (Scene)
    {
      rtcReleaseScene(Scene);
    }
  }
};
#else
struct ShadowCaster::EmbreeScene
{
};
#endif

ShadowCaster::ShadowCaster() = default;
ShadowCaster::~ShadowCaster() = default;

bool ShadowCaster::UsesEmbree()
{
#ifdef TRANSLUCENCY_HAVE_EMBREE
  return true;
#else
  return false;
#endif
}

void ShadowCaster::Build(const std::vector<double>& points, const std::vector<int>& triangles)
{
  Embree_.reset();
  Triangles_ = 0;
#ifndef TRANSLUCENCY_HAVE_EMBREE
  Fallback_.Build(points, triangles);
  Triangles_ = triangles.size() / 3;
#else
  if (points.size() % 3 != 0 || triangles.size() % 3 != 0)
  {
    std::ostringstream msg;
    msg << "ShadowCaster: " << points.size() << " point coordinates and " << triangles.size()
        << " triangle ids: both must be multiples of 3";
    throw Error(msg.str());
  }
  const long long numPoints = static_cast<long long>(points.size() / 3);
  const std::size_t numTriangles = triangles.size() / 3;
  if (numTriangles > static_cast<std::size_t>(std::numeric_limits<int>::max()))
  {
    throw Error("ShadowCaster: too many triangles (more than 2^31 - 1)");
  }
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k)
  {
    lo[k] = std::numeric_limits<double>::infinity();
    hi[k] = -lo[k];
  }
  for (std::size_t f = 0; f < numTriangles; ++f)
  {
    for (int v = 0; v < 3; ++v)
    {
      const int id = triangles[3 * f + v];
      if (id < 0 || id >= numPoints)
      {
        std::ostringstream msg;
        msg << "ShadowCaster: triangle " << f << " has point id " << id << ", out of range [0, "
            << numPoints << ")";
        throw Error(msg.str());
      }
      const double* x = &points[3 * static_cast<std::size_t>(id)];
      for (int k = 0; k < 3; ++k)
      {
        if (!std::isfinite(x[k]))
        {
          std::ostringstream msg;
          msg << "ShadowCaster: triangle " << f << " uses point " << id
              << " whose coordinates are not finite";
          throw Error(msg.str());
        }
        lo[k] = std::min(lo[k], x[k]);
        hi[k] = std::max(hi[k], x[k]);
      }
    }
  }
  if (numTriangles == 0)
  {
    return;
  }
  auto scene = std::make_unique<EmbreeScene>();
  for (int k = 0; k < 3; ++k)
  {
    scene->Centre[k] = 0.5 * (lo[k] + hi[k]);
  }
  RTCDevice device = Device();
  scene->Scene = rtcNewScene(device);
  rtcSetSceneFlags(scene->Scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene->Scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  // Only the points the triangles use would do; all of them are simpler and
  // the ids stay the caller's.
  float* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX,
    0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), static_cast<std::size_t>(numPoints)));
  unsigned* ids = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
    geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), numTriangles));
  if (!vertices || !ids)
  {
    rtcReleaseGeometry(geometry);
    throw Error("ShadowCaster: Embree could not allocate the geometry buffers");
  }
  for (long long i = 0; i < numPoints; ++i)
  {
    for (int k = 0; k < 3; ++k)
    {
      const double x = points[3 * static_cast<std::size_t>(i) + k];
      // Unused points may be anything: Embree reads only the indexed ones.
      vertices[3 * i + k] = std::isfinite(x) ? static_cast<float>(x - scene->Centre[k]) : 0.0f;
    }
  }
  for (std::size_t k = 0; k < 3 * numTriangles; ++k)
  {
    ids[k] = static_cast<unsigned>(triangles[k]);
  }
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene->Scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene->Scene);
  const RTCError error = rtcGetDeviceError(device);
  if (error != RTC_ERROR_NONE)
  {
    throw Error("ShadowCaster: Embree could not build the scene (error " +
      std::to_string(static_cast<int>(error)) + ")");
  }
  Embree_ = std::move(scene);
  Triangles_ = numTriangles;
#endif
}

bool ShadowCaster::Occluded(const double origin[3], const double direction[3], double tMax) const
{
#ifndef TRANSLUCENCY_HAVE_EMBREE
  return Fallback_.Occluded(origin, direction, tMax);
#else
  if (!Embree_ || !(tMax > 0.0))
  {
    return false;
  }
  double unit[3];
  if (!RayCaster::UnitDirection(origin, direction, unit))
  {
    return false;
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray;
  ray.org_x = static_cast<float>(origin[0] - Embree_->Centre[0]);
  ray.org_y = static_cast<float>(origin[1] - Embree_->Centre[1]);
  ray.org_z = static_cast<float>(origin[2] - Embree_->Centre[2]);
  ray.tnear = 0.0f;
  ray.dir_x = static_cast<float>(unit[0]);
  ray.dir_y = static_cast<float>(unit[1]);
  ray.dir_z = static_cast<float>(unit[2]);
  ray.time = 0.0f;
  ray.tfar = static_cast<float>(std::min(tMax, static_cast<double>(std::numeric_limits<float>::max())));
  ray.mask = 0xFFFFFFFFu;
  ray.id = 0;
  ray.flags = 0;
  rtcOccluded1(Embree_->Scene, &context, &ray);
  // Embree sets tfar to -infinity when the ray is occluded.
  return ray.tfar < 0.0f;
#endif
}

std::size_t ShadowCaster::GetMemoryBytes() const
{
  // About: the vertices and ids, and a tree of about 64 bytes per triangle
  // (Embree's BVH4 with triangle4 leaves).
  return Triangles_ * (3 * sizeof(unsigned) + 64);
}

} // namespace translucency
