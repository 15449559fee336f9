#include "SurfaceLightKernel.h"

#include "Error.h"
#include "Fresnel.h"
#include "RayCaster.h"

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
  const int numTriangles = static_cast<int>(surface.GetNumberOfTriangles());
  const SurfaceMeasures measures = MeasureSurface(surface);
  const std::vector<double>& areas = measures.Areas;
  const std::vector<double>& unitNormals = measures.UnitNormals;
  const std::vector<double>& pointArea = measures.PointArea;
  const std::vector<double>& pointNormal = measures.PointNormal;
  const std::vector<int>& offsets = measures.Offsets;
  const std::vector<int>& incident = measures.Incident;

  const double diag = surface.Diagonal;
  const double offset = 1e-5 * diag;
  const bool needRays =
    shadows && (!lights.empty() || (uniformIrradiance > 0.0 && uniformSamples > 0));
  RayCaster caster;
  if (needRays && numTriangles > 0)
  {
    caster.Build(surface.Points, surface.Triangles);
  }
  auto occluded = [&](const double* x, const double* n, const double* w, double reach) {
    const double origin[3] = { x[0] + offset * (n[0] + w[0]), x[1] + offset * (n[1] + w[1]),
      x[2] + offset * (n[2] + w[2]) };
    return numTriangles > 0 && caster.Occluded(origin, w, reach);
  };

  const int count = static_cast<int>(points.size());
  q.assign(3 * points.size(), 0.0);
  if (abort && abort())
  {
    return false;
  }
  std::atomic<bool> aborted(false);
#pragma omp parallel
  {
    std::vector<double> corners; // 3 per incident triangle
#pragma omp for schedule(dynamic, 64)
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
      const int i = points[k];
      if (!(pointArea[i] > 0.0))
      {
        continue; // not a boundary point of the serial mesh: q = 0
      }
      const double* x = &surface.Points[3 * static_cast<std::size_t>(i)];
      const double* ni = &pointNormal[3 * static_cast<std::size_t>(i)];
      const int begin = offsets[i], end = offsets[i + 1];

      // The uniform light (ComputeBoundaryIrradiance with the point's eta).
      double qu = 0.0;
      if (uniformIrradiance > 0.0)
      {
        double etaSum = 0.0;
        for (int m = begin; m < end; ++m)
        {
          etaSum += areas[incident[m]] * surface.TriangleEta[incident[m]];
        }
        const double eta = etaSum / pointArea[i];
        if (!shadows || uniformSamples == 0)
        {
          qu = uniformIrradiance * Fresnel::UniformTransmittance(eta);
        }
        else
        {
          for (int s = 0; s < uniformSamples; ++s)
          {
            double w[3];
            const double cosTheta = HemisphereDirection(ni, s, uniformSamples, rotations[k], w);
            if (!occluded(x, ni, w, 2.0 * diag))
            {
              qu += Fresnel::Transmittance(cosTheta, eta);
            }
          }
          qu *= uniformIrradiance / uniformSamples;
        }
      }
      corners.assign(3 * static_cast<std::size_t>(end - begin), qu);
      for (const auto& light : lights)
      {
        int visible = -1;
        for (int m = begin; m < end; ++m)
        {
          const int f = incident[m];
          double ql[3], w[3], distance;
          if (!DirectIrradiance(light, x, &unitNormals[3 * static_cast<std::size_t>(f)],
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
          double* qc = &corners[3 * static_cast<std::size_t>(m - begin)];
          for (int c = 0; c < 3; ++c)
          {
            qc[c] += ql[c];
          }
        }
      }
      // ProjectCornerIrradiance.
      double load[3] = { 0.0, 0.0, 0.0 };
      double area = 0.0;
      for (int m = begin; m < end; ++m)
      {
        const int f = incident[m];
        area += areas[f];
        for (int c = 0; c < 3; ++c)
        {
          load[c] += areas[f] * corners[3 * static_cast<std::size_t>(m - begin) + c];
        }
      }
      if (area > 0.0)
      {
        for (int c = 0; c < 3; ++c)
        {
          q[3 * static_cast<std::size_t>(k) + c] = load[c] / area;
        }
      }
    }
  }
  return !aborted.load();
}

} // namespace translucency
