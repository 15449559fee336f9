#include "LightSources.h"
#include "ResourceLimits.h"

#include "Error.h"
#include "Fresnel.h"
#include "Radiance.h"
#include "ShadowCaster.h"
#include "TetMesh.h"
#include "TriangleGeometry.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>

namespace translucency
{

bool DirectIrradiance(const LightSource& light, const double x[3], const double n[3], double eta,
  double q[3], double toLight[3], double& distance)
{
  double scale = 1.0;
  if (light.Type == LightSource::Kind::Directional)
  {
    const double len = std::sqrt(light.Direction[0] * light.Direction[0] +
      light.Direction[1] * light.Direction[1] + light.Direction[2] * light.Direction[2]);
    for (int k = 0; k < 3; ++k)
    {
      toLight[k] = -light.Direction[k] / len;
    }
    distance = std::numeric_limits<double>::infinity();
  }
  else
  {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k)
    {
      toLight[k] = light.Position[k] - x[k];
      d2 += toLight[k] * toLight[k];
    }
    distance = std::sqrt(d2);
    for (int k = 0; k < 3; ++k)
    {
      toLight[k] /= distance;
    }
    scale = 1.0 / d2; // inverse-square fall-off of a point source
    if (light.Type == LightSource::Kind::Spot)
    {
      // Cone of the spot light: cos(alpha) between the axis and the direction
      // of travel from the light to x.
      const double axisLength = std::sqrt(light.Direction[0] * light.Direction[0] +
        light.Direction[1] * light.Direction[1] + light.Direction[2] * light.Direction[2]);
      const double cosAlpha = -(toLight[0] * light.Direction[0] +
                                toLight[1] * light.Direction[1] + toLight[2] * light.Direction[2]) /
        axisLength;
      if (cosAlpha < std::cos(light.SpotCutoff * 3.14159265358979323846 / 180.0))
      {
        q[0] = q[1] = q[2] = 0.0;
        return false;
      }
      if (light.SpotExponent > 0.0)
      {
        scale *= std::pow(std::max(cosAlpha, 0.0), light.SpotExponent);
      }
    }
  }
  const double cosIn = n[0] * toLight[0] + n[1] * toLight[1] + n[2] * toLight[2];
  if (cosIn <= 0.0)
  {
    q[0] = q[1] = q[2] = 0.0;
    return false;
  }
  // q = L_i (n . w_i) F_t(w_i) integrated over a delta distribution of directions.
  const double transmitted = cosIn * Fresnel::Transmittance(cosIn, eta) * scale;
  for (int c = 0; c < 3; ++c)
  {
    q[c] = light.Power[c] * transmitted;
  }
  return true;
}

double UniformSampleRotation(const double x[3])
{
  // SplitMix64 (Steele, Lea & Flood 2014) over the three coordinates' bits.
  auto mix = [](std::uint64_t z) {
    z += 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  };
  std::uint64_t h = 0;
  for (int k = 0; k < 3; ++k)
  {
    const double v = x[k] == 0.0 ? 0.0 : x[k]; // -0 and +0: one point
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    h = mix(h ^ bits);
  }
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

double HemisphereDirection(const double n[3], int k, int count, double rotation, double w[3])
{
  double t[3], b[3];
  OrthonormalFrame(n, t, b);
  // Cosine-weighted: r = sqrt(u) on the unit disk, lifted to the hemisphere.
  const double golden = 2.399963229728653; // pi (3 - sqrt 5)
  const double u = (k + 0.5) / count;
  const double r = std::sqrt(u);
  const double phi = golden * k + 2.0 * 3.141592653589793 * rotation;
  const double cosTheta = std::sqrt(std::max(0.0, 1.0 - u));
  const double a = r * std::cos(phi), c = r * std::sin(phi);
  for (int d = 0; d < 3; ++d)
  {
    w[d] = a * t[d] + c * b[d] + cosTheta * n[d];
  }
  return cosTheta;
}

void ValidateLight(const LightSource& light, size_t index)
{
  std::ostringstream msg;
  msg << "light " << index << ": ";
  if (light.Type == LightSource::Kind::Uniform)
  {
    msg << "a uniform light is not accepted in the light list: pass its irradiance as "
           "uniformIrradiance";
    throw Error(msg.str());
  }
  for (int c = 0; c < 3; ++c)
  {
    if (!(light.Power[c] >= 0.0) || !std::isfinite(light.Power[c]))
    {
      msg << "power " << light.Power[c] << " in channel " << c
          << " is negative or not finite: it must be finite and >= 0";
      throw Error(msg.str());
    }
  }
  if (light.Type == LightSource::Kind::Directional || light.Type == LightSource::Kind::Spot)
  {
    const double len2 = light.Direction[0] * light.Direction[0] +
      light.Direction[1] * light.Direction[1] + light.Direction[2] * light.Direction[2];
    if (!(len2 > 0.0) || !std::isfinite(len2))
    {
      msg << "a directional or spot light has a zero or non-finite direction";
      throw Error(msg.str());
    }
  }
  if (light.Type == LightSource::Kind::Spot &&
    !(light.SpotCutoff > 0.0 && light.SpotCutoff <= 180.0 && light.SpotExponent >= 0.0 &&
      std::isfinite(light.SpotExponent)))
  {
    msg << "spot cut-off " << light.SpotCutoff << " degrees and exponent " << light.SpotExponent
        << ": need 0 < cut-off <= 180 and a finite exponent >= 0";
    throw Error(msg.str());
  }
  if (light.Type != LightSource::Kind::Directional && (!std::isfinite(light.Position[0]) || !std::isfinite(light.Position[1]) ||
    !std::isfinite(light.Position[2])))
  {
    msg << "a point or spot light has a non-finite position";
    throw Error(msg.str());
  }
}


bool ComputeBoundaryIrradiance(const TetMesh& mesh, const std::vector<double>& pointEta,
  const std::vector<LightSource>& lights, double uniformIrradiance, int uniformSamples,
  bool shadows, std::vector<double>& q, const std::function<bool()>& abort)
{
  const int numPoints = mesh.GetNumberOfPoints();
  if (pointEta.size() != static_cast<size_t>(numPoints))
  {
    std::ostringstream msg;
    msg << "boundary irradiance: " << pointEta.size() << " refractive indices for "
        << numPoints << " points";
    throw Error(msg.str());
  }
  const std::vector<int>& boundary = mesh.GetBoundaryPoints();
  for (int i : boundary)
  {
    if (!(pointEta[i] > 0.0) || !std::isfinite(pointEta[i]))
    {
      std::ostringstream msg;
      msg << "boundary irradiance: the refractive index at point " << i << " is " << pointEta[i]
          << ": must be finite and > 0";
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
    std::ostringstream msg;
    msg << "boundary irradiance: " << uniformSamples << " uniform light samples: must be >= 0";
    throw Error(msg.str());
  }
  if (shadows && uniformIrradiance > 0.0 &&
    static_cast<double>(boundary.size()) * uniformSamples > 8589934592.0)
  {
    throw Error("boundary irradiance: " + std::to_string(uniformSamples) +
      " uniform light samples x " + std::to_string(boundary.size()) + " boundary points = " +
      FormatNumber(static_cast<double>(boundary.size()) * uniformSamples) +
      " shadow rays, above the budget of 8.6e9 rays: use fewer samples (--uniform-samples)");
  }
  for (size_t l = 0; l < lights.size(); ++l)
  {
    ValidateLight(lights[l], l);
  }

  q.assign(3 * static_cast<size_t>(numPoints), 0.0);
  if (boundary.empty())
  {
    return true;
  }

  // Bounding box diagonal (mm): scale of the ray offset and reach.
  const double diag = BoundingBoxDiagonal(mesh);
  const double offset = 1e-5 * diag;

  const bool needRays =
    shadows && (!lights.empty() || (uniformIrradiance > 0.0 && uniformSamples > 0));
  ShadowCaster caster;
  if (needRays)
  {
    caster.Build(mesh.GetPoints(), mesh.GetBoundaryTriangles());
  }
  // Visibility of direction w from boundary point x with normal n: the ray
  // starts just off the surface so that it does not hit the triangles at x.
  auto occluded = [&](const double* x, const double* n, const double* w, double distance) {
    const double reach = std::min(distance, 2.0 * diag);
    const double origin[3] = { x[0] + offset * (n[0] + w[0]), x[1] + offset * (n[1] + w[1]),
      x[2] + offset * (n[2] + w[2]) };
    return caster.Occluded(origin, w, reach);
  };

  const std::vector<double>& normals = mesh.GetPointNormals();
  const int numBoundary = static_cast<int>(boundary.size());
  if (abort && abort())
  {
    return false;
  }
  // Only the calling thread (thread 0 of the team) calls abort(): the callback
  // need not be thread-safe (a VTK filter's may fire events).
  std::atomic<bool> aborted(false);
#pragma omp parallel for schedule(dynamic, 64)
  for (int b = 0; b < numBoundary; ++b)
  {
    if (aborted.load(std::memory_order_relaxed))
    {
      continue; // an OpenMP loop cannot break: skip the remaining points
    }
    if (abort && b % 64 == 0 && omp_get_thread_num() == 0 && abort())
    {
      aborted.store(true, std::memory_order_relaxed);
      continue;
    }
    const int i = boundary[b];
    const double* x = mesh.GetPoint(i);
    const double* n = &normals[3 * static_cast<size_t>(i)];
    const double eta = pointEta[i];
    double* qi = &q[3 * static_cast<size_t>(i)];
    for (const auto& light : lights)
    {
      double ql[3], w[3], distance;
      if (DirectIrradiance(light, x, n, eta, ql, w, distance) &&
        !(shadows && occluded(x, n, w, distance)))
      {
        for (int c = 0; c < 3; ++c)
        {
          qi[c] += ql[c];
        }
      }
    }
    if (uniformIrradiance > 0.0)
    {
      double qu = 0.0;
      if (!shadows || uniformSamples == 0)
      {
        // q = pi L * (1/pi) int F_t cos dw = E * UniformTransmittance.
        qu = uniformIrradiance * Fresnel::UniformTransmittance(eta);
      }
      else
      {
        // Cosine-weighted estimate of (1/pi) int V F_t cos dw.
        const double rotation = UniformSampleRotation(x);
        for (int k = 0; k < uniformSamples; ++k)
        {
          double w[3];
          const double cosTheta = HemisphereDirection(n, k, uniformSamples, rotation, w);
          if (!occluded(x, n, w, 2.0 * diag))
          {
            qu += Fresnel::Transmittance(cosTheta, eta);
          }
        }
        qu *= uniformIrradiance / uniformSamples;
      }
      for (int c = 0; c < 3; ++c)
      {
        qi[c] += qu;
      }
    }
  }
  return !aborted.load();
}


double BoundingBoxDiagonal(const TetMesh& mesh)
{
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k)
  {
    lo[k] = std::numeric_limits<double>::infinity();
    hi[k] = -lo[k];
  }
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    const double* x = mesh.GetPoint(i);
    for (int k = 0; k < 3; ++k)
    {
      lo[k] = std::min(lo[k], x[k]);
      hi[k] = std::max(hi[k], x[k]);
    }
  }
  return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
    (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

void CheckBoundaryTriangleEta(const TetMesh& mesh, const std::vector<double>& tetEta)
{
  const int numTets = mesh.GetNumberOfTets();
  if (tetEta.size() != static_cast<size_t>(numTets))
  {
    std::ostringstream msg;
    msg << "boundary irradiance: " << tetEta.size() << " refractive indices for " << numTets
        << " tets";
    throw Error(msg.str());
  }
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  const std::vector<int>& triangleTets = mesh.GetBoundaryTriangleTets();
  for (int f = 0; f < numTriangles; ++f)
  {
    const double eta = tetEta[triangleTets[f]];
    if (!(eta > 0.0) || !std::isfinite(eta))
    {
      std::ostringstream msg;
      msg << "boundary irradiance: the refractive index of tet " << triangleTets[f]
          << " (under boundary triangle " << f << ") is " << eta << ": must be finite and > 0";
      throw Error(msg.str());
    }
  }
}

std::vector<double> BoundaryTriangleNormals(const TetMesh& mesh)
{
  // Unit outward normals of the triangles (TetMesh orients them outwards:
  // the area vector (b - a) x (c - a) / 2 points out of the object).
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  std::vector<double> normals(3 * static_cast<size_t>(numTriangles), 0.0);
  for (int f = 0; f < numTriangles; ++f)
  {
    const int* tri = &triangles[3 * static_cast<size_t>(f)];
    const double* a = mesh.GetPoint(tri[0]);
    const double* b = mesh.GetPoint(tri[1]);
    const double* c = mesh.GetPoint(tri[2]);
    const double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
    const double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
    double* n = &normals[3 * static_cast<size_t>(f)];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; ++k)
    {
      n[k] = length > 0.0 ? n[k] / length : 0.0;
    }
  }
  return normals;
}

bool AddLightCornerIrradiance(const TetMesh& mesh, const std::vector<double>& tetEta,
  const std::vector<double>& triangleNormals, const LightSource& light, bool shadows,
  const ShadowCaster* caster, double diagonal, std::vector<double>& cornerQ,
  const std::function<bool()>& abort)
{
  const std::vector<int>& boundary = mesh.GetBoundaryPoints();
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const std::vector<int>& triangleTets = mesh.GetBoundaryTriangleTets();
  const std::vector<double>& pointNormals = mesh.GetPointNormals();
  const std::vector<int>& offsets = mesh.GetBoundaryPointTriangleOffsets();
  const std::vector<int>& incident = mesh.GetBoundaryPointTriangles();
  const int numBoundary = static_cast<int>(boundary.size());
  if (shadows && !caster)
  {
    throw Error("boundary irradiance: shadows need a ray caster over the boundary triangles");
  }
  const double offset = 1e-5 * diagonal;
  if (abort && abort())
  {
    return false;
  }
  // Each corner value is written by the one thread handling its point.
  std::atomic<bool> aborted(false);
#pragma omp parallel for schedule(dynamic, 64)
  for (int k = 0; k < numBoundary; ++k)
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
    const int i = boundary[k];
    const double* x = mesh.GetPoint(i);
    const double* ni = &pointNormals[3 * static_cast<size_t>(i)];
    int visible = -1; // unknown until a triangle faces the light
    for (int m = offsets[k]; m < offsets[k + 1]; ++m)
    {
      const int f = incident[m];
      const double* n = &triangleNormals[3 * static_cast<size_t>(f)];
      double ql[3], w[3], distance;
      if (!DirectIrradiance(light, x, n, tetEta[triangleTets[f]], ql, w, distance))
      {
        continue;
      }
      if (shadows && visible < 0)
      {
        // The point's shadow ray, as in ComputeBoundaryIrradiance.
        const double reach = std::min(distance, 2.0 * diagonal);
        const double origin[3] = { x[0] + offset * (ni[0] + w[0]), x[1] + offset * (ni[1] + w[1]),
          x[2] + offset * (ni[2] + w[2]) };
        visible = caster->Occluded(origin, w, reach) ? 0 : 1;
      }
      if (shadows && visible == 0)
      {
        break;
      }
      const int* tri = &triangles[3 * static_cast<size_t>(f)];
      const int corner = tri[0] == i ? 0 : (tri[1] == i ? 1 : 2);
      double* qc = &cornerQ[9 * static_cast<size_t>(f) + 3 * static_cast<size_t>(corner)];
      for (int c = 0; c < 3; ++c)
      {
        qc[c] += ql[c];
      }
    }
  }
  return !aborted.load();
}

bool ComputeTriangleCornerIrradiance(const TetMesh& mesh, const std::vector<double>& tetEta,
  const std::vector<LightSource>& lights, double uniformIrradiance, int uniformSamples,
  bool shadows, std::vector<double>& cornerQ, const std::function<bool()>& abort)
{
  CheckBoundaryTriangleEta(mesh, tetEta);
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  // The uniform light per point, and every check of the arguments, by the
  // point version (no directional or point light: no rays for them there).
  const std::vector<double> pointEta = PointRefractiveIndex(mesh, tetEta);
  std::vector<double> uniform;
  for (size_t l = 0; l < lights.size(); ++l)
  {
    ValidateLight(lights[l], l);
  }
  if (!ComputeBoundaryIrradiance(
        mesh, pointEta, {}, uniformIrradiance, uniformSamples, shadows, uniform, abort))
  {
    return false;
  }
  cornerQ.assign(9 * static_cast<size_t>(numTriangles), 0.0);
  if (mesh.GetBoundaryPoints().empty())
  {
    return true;
  }
  // Every corner starts with the uniform light of its point, then each light
  // adds its own contribution, in the order of `lights`.
  for (int f = 0; f < numTriangles; ++f)
  {
    for (int k = 0; k < 3; ++k)
    {
      const int i = triangles[3 * static_cast<size_t>(f) + k];
      for (int c = 0; c < 3; ++c)
      {
        cornerQ[9 * static_cast<size_t>(f) + 3 * k + c] = uniform[3 * static_cast<size_t>(i) + c];
      }
    }
  }
  const std::vector<double> normals = BoundaryTriangleNormals(mesh);
  const double diag = BoundingBoxDiagonal(mesh);
  ShadowCaster caster;
  if (shadows && !lights.empty())
  {
    caster.Build(mesh.GetPoints(), triangles);
  }
  for (const auto& light : lights)
  {
    if (!AddLightCornerIrradiance(
          mesh, tetEta, normals, light, shadows, &caster, diag, cornerQ, abort))
    {
      return false;
    }
  }
  return true;
}

void ProjectCornerIrradiance(
  const TetMesh& mesh, const std::vector<double>& cornerQ, std::vector<double>& pointQ)
{
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  if (cornerQ.size() != 9 * static_cast<size_t>(numTriangles))
  {
    std::ostringstream msg;
    msg << "boundary irradiance: " << cornerQ.size() << " corner values for " << numTriangles
        << " boundary triangles (expected 9 per triangle)";
    throw Error(msg.str());
  }
  pointQ.assign(3 * static_cast<size_t>(mesh.GetNumberOfPoints()), 0.0);
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const std::vector<int>& boundary = mesh.GetBoundaryPoints();
  const std::vector<int>& offsets = mesh.GetBoundaryPointTriangleOffsets();
  const std::vector<int>& incident = mesh.GetBoundaryPointTriangles();
  const std::vector<double>& areas = mesh.GetBoundaryTriangleAreas();
  const int numBoundary = static_cast<int>(boundary.size());
#pragma omp parallel for schedule(static)
  for (int k = 0; k < numBoundary; ++k)
  {
    const int i = boundary[k];
    double load[3] = { 0.0, 0.0, 0.0 };
    double area = 0.0;
    for (int m = offsets[k]; m < offsets[k + 1]; ++m)
    {
      const int f = incident[m];
      const int* tri = &triangles[3 * static_cast<size_t>(f)];
      const int corner = tri[0] == i ? 0 : (tri[1] == i ? 1 : 2);
      area += areas[f];
      for (int c = 0; c < 3; ++c)
      {
        load[c] += areas[f] * cornerQ[9 * static_cast<size_t>(f) + 3 * corner + c];
      }
    }
    if (area > 0.0)
    {
      for (int c = 0; c < 3; ++c)
      {
        pointQ[3 * static_cast<size_t>(i) + c] = load[c] / area;
      }
    }
  }
}

bool ComputeProjectedIrradiance(const TetMesh& mesh, const std::vector<double>& tetEta,
  const std::vector<LightSource>& lights, double uniformIrradiance, int uniformSamples,
  bool shadows, std::vector<double>& q, const std::function<bool()>& abort)
{
  std::vector<double> cornerQ;
  if (!ComputeTriangleCornerIrradiance(
        mesh, tetEta, lights, uniformIrradiance, uniformSamples, shadows, cornerQ, abort))
  {
    return false;
  }
  ProjectCornerIrradiance(mesh, cornerQ, q);
  return true;
}

} // namespace translucency
