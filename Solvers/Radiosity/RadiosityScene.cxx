#include "RadiosityScene.h"

#include "Error.h"
#include "TetMesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

namespace translucency
{

namespace
{

std::string ObjectName(const std::string& name, int index)
{
  std::ostringstream os;
  os << "object " << index;
  if (!name.empty())
  {
    os << " '" << name << "'";
  }
  return os.str();
}

/// Every edge used by exactly two triangles (orientation not checked).
bool IsClosed(const std::vector<int>& triangles)
{
  std::map<std::pair<int, int>, int> edges;
  for (size_t t = 0; t + 2 < triangles.size(); t += 3)
  {
    for (int e = 0; e < 3; ++e)
    {
      int a = triangles[t + e], b = triangles[t + (e + 1) % 3];
      if (a > b)
      {
        std::swap(a, b);
      }
      ++edges[{ a, b }];
    }
  }
  if (edges.empty())
  {
    return false;
  }
  for (const auto& e : edges)
  {
    if (e.second != 2)
    {
      return false;
    }
  }
  return true;
}

} // namespace

int RadiosityScene::AddOpaque(const std::string& name, std::vector<double> points,
  std::vector<int> triangles, std::vector<double> albedo)
{
  const int index = GetNumberOfObjects();
  const std::string what = ObjectName(name, index);
  if (points.size() % 3 != 0 || triangles.size() % 3 != 0 || triangles.empty())
  {
    throw Error(what + ": needs 3 coordinates per point and at least one triangle (3 ids each)");
  }
  const int numPoints = static_cast<int>(points.size() / 3);
  const int numTriangles = static_cast<int>(triangles.size() / 3);
  if (albedo.size() != 3 * static_cast<size_t>(numTriangles))
  {
    std::ostringstream os;
    os << what << ": " << albedo.size() << " albedo values for " << numTriangles
       << " triangles (need 3 per triangle: R, G, B)";
    throw Error(os.str());
  }
  for (size_t k = 0; k < points.size(); ++k)
  {
    if (!std::isfinite(points[k]))
    {
      std::ostringstream os;
      os << what << ": point " << k / 3 << " has a non-finite coordinate";
      throw Error(os.str());
    }
  }
  for (int t = 0; t < numTriangles; ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double a = albedo[3 * t + c];
      if (!(a >= 0.0 && a <= 1.0))
      {
        std::ostringstream os;
        os << what << ": triangle " << t << " has albedo " << a << " in channel " << c
           << ": an albedo must be in [0, 1]";
        throw Error(os.str());
      }
      const int id = triangles[3 * t + c];
      if (id < 0 || id >= numPoints)
      {
        std::ostringstream os;
        os << what << ": triangle " << t << " uses point " << id << " but there are "
           << numPoints << " points";
        throw Error(os.str());
      }
    }
    const double* a = &points[3 * triangles[3 * t]];
    const double* b = &points[3 * triangles[3 * t + 1]];
    const double* c = &points[3 * triangles[3 * t + 2]];
    const double u[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
    const double v[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
    const double n[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
      u[0] * v[1] - u[1] * v[0] };
    if (!(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 0.0))
    {
      std::ostringstream os;
      os << what << ": triangle " << t << " has zero area";
      throw Error(os.str());
    }
  }
  RadiosityObject object;
  object.Name = name;
  object.Translucent = false;
  object.Points = std::move(points);
  object.Triangles = std::move(triangles);
  object.Albedo = std::move(albedo);
  Objects_.push_back(std::move(object));
  return index;
}

void RadiosityScene::ValidateMaterial(const RadiosityObject& object) const
{
  const int index = static_cast<int>(&object - Objects_.data());
  const std::string what = ObjectName(object.Name, index);
  const OpticalProperties& m = object.Material;
  if (m.AbsorptionCoefficient.empty() && m.ReducedScatteringCoefficient.empty() &&
    m.RefractiveIndex.empty())
  {
    throw Error(what + ": translucent object without coefficients (needs AbsorptionCoefficient, "
                       "ReducedScatteringCoefficient and RefractiveIndex per tet)");
  }
  try
  {
    m.Validate(object.Mesh->GetNumberOfTets());
  }
  catch (const Error& e)
  {
    throw Error(what + ": " + e.what());
  }
}

int RadiosityScene::AddTranslucent(
  const std::string& name, std::shared_ptr<const TetMesh> mesh, OpticalProperties material)
{
  const int index = GetNumberOfObjects();
  if (!mesh || mesh->GetNumberOfTets() == 0)
  {
    throw Error(ObjectName(name, index) + ": translucent object without a tet mesh");
  }
  RadiosityObject object;
  object.Name = name;
  object.Translucent = true;
  object.Mesh = std::move(mesh);
  object.Material = std::move(material);
  Objects_.push_back(std::move(object));
  try
  {
    ValidateMaterial(Objects_.back());
  }
  catch (...)
  {
    Objects_.pop_back();
    throw;
  }
  return index;
}

void RadiosityScene::SetMaterial(int k, OpticalProperties material)
{
  if (k < 0 || k >= GetNumberOfObjects() || !Objects_[k].Translucent)
  {
    throw Error("SetMaterial: object " + std::to_string(k) + " is not a translucent object");
  }
  OpticalProperties old = std::move(Objects_[k].Material);
  Objects_[k].Material = std::move(material);
  try
  {
    ValidateMaterial(Objects_[k]);
  }
  catch (...)
  {
    Objects_[k].Material = std::move(old);
    throw;
  }
  // Refractive index per patch may have changed.
  if (!PatchEta_.empty())
  {
    const auto& owners = Objects_[k].Mesh->GetBoundaryTriangleTets();
    for (size_t f = 0; f < owners.size(); ++f)
    {
      PatchEta_[PatchOffsets_[k] + f] = Objects_[k].Material.RefractiveIndex[owners[f]];
    }
  }
}

void RadiosityScene::SetAlbedo(int k, std::vector<double> albedo)
{
  if (k < 0 || k >= GetNumberOfObjects() || Objects_[k].Translucent)
  {
    throw Error("SetAlbedo: object " + std::to_string(k) + " is not an opaque object");
  }
  const RadiosityObject& object = Objects_[k];
  const std::string what = ObjectName(object.Name, k);
  if (albedo.size() != object.Albedo.size())
  {
    std::ostringstream os;
    os << what << ": " << albedo.size() << " albedo values for " << object.Triangles.size() / 3
       << " triangles (need 3 per triangle: R, G, B)";
    throw Error(os.str());
  }
  for (size_t i = 0; i < albedo.size(); ++i)
  {
    if (!(albedo[i] >= 0.0 && albedo[i] <= 1.0))
    {
      std::ostringstream os;
      os << what << ": triangle " << i / 3 << " has albedo " << albedo[i] << " in channel "
         << i % 3 << ": an albedo must be in [0, 1]";
      throw Error(os.str());
    }
  }
  Objects_[k].Albedo = std::move(albedo);
}

void RadiosityScene::Build(bool buildRayCaster)
{
  if (Objects_.empty())
  {
    throw Error("radiosity scene: no objects");
  }
  PatchOffsets_.assign(1, 0);
  PatchObject_.clear();
  Points_.clear();
  Triangles_.clear();
  PatchEta_.clear();
  Closed_.clear();
  for (int k = 0; k < GetNumberOfObjects(); ++k)
  {
    const RadiosityObject& object = Objects_[k];
    const int base = static_cast<int>(Points_.size() / 3);
    const std::vector<double>& points = object.Translucent ? object.Mesh->GetPoints() : object.Points;
    const std::vector<int>& triangles =
      object.Translucent ? object.Mesh->GetBoundaryTriangles() : object.Triangles;
    Points_.insert(Points_.end(), points.begin(), points.end());
    for (int id : triangles)
    {
      Triangles_.push_back(base + id);
    }
    const int numTriangles = static_cast<int>(triangles.size() / 3);
    for (int f = 0; f < numTriangles; ++f)
    {
      PatchObject_.push_back(k);
      PatchEta_.push_back(object.Translucent
          ? object.Material.RefractiveIndex[object.Mesh->GetBoundaryTriangleTets()[f]]
          : 1.0);
    }
    PatchOffsets_.push_back(PatchOffsets_.back() + numTriangles);
    Closed_.push_back(object.Translucent || IsClosed(triangles));
  }
  const int numPatches = GetNumberOfPatches();
  Centroids_.assign(3 * static_cast<size_t>(numPatches), 0.0);
  Normals_.assign(3 * static_cast<size_t>(numPatches), 0.0);
  Areas_.assign(numPatches, 0.0);
  for (int p = 0; p < numPatches; ++p)
  {
    const double* a = &Points_[3 * Triangles_[3 * p]];
    const double* b = &Points_[3 * Triangles_[3 * p + 1]];
    const double* c = &Points_[3 * Triangles_[3 * p + 2]];
    const double u[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
    const double v[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
    double n[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
      u[0] * v[1] - u[1] * v[0] };
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    Areas_[p] = 0.5 * len;
    for (int d = 0; d < 3; ++d)
    {
      Normals_[3 * p + d] = len > 0.0 ? n[d] / len : 0.0;
      Centroids_[3 * p + d] = (a[d] + b[d] + c[d]) / 3.0;
    }
  }
  double lo[3], hi[3];
  for (int d = 0; d < 3; ++d)
  {
    lo[d] = std::numeric_limits<double>::infinity();
    hi[d] = -lo[d];
  }
  for (size_t i = 0; i < Points_.size(); i += 3)
  {
    for (int d = 0; d < 3; ++d)
    {
      lo[d] = std::min(lo[d], Points_[i + d]);
      hi[d] = std::max(hi[d], Points_[i + d]);
    }
  }
  Diagonal_ = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
    (hi[2] - lo[2]) * (hi[2] - lo[2]));
  if (buildRayCaster)
  {
    Caster_.Build(Points_, Triangles_);
  }
  else
  {
    Caster_ = RayCaster();
  }
}

void RadiosityScene::CheckLights(const std::vector<LightSource>& lights) const
{
  for (size_t l = 0; l < lights.size(); ++l)
  {
    const LightSource& light = lights[l];
    if (light.Type == LightSource::Kind::Uniform)
    {
      throw Error("light " + std::to_string(l) +
        ": uniform (environment) lights are not supported by the radiosity solver");
    }
    ValidateLight(light, l); // power, direction, position, cone
    if (light.Type == LightSource::Kind::Directional)
    {
      continue;
    }
    const double* x = light.Position.data();
    // Parity test against each closed object: an irrational-ish direction
    // avoids rays through shared edges.
    const double dir[3] = { 0.5773502691896258 + 0.0123, 0.5773502691896258 - 0.0311,
      0.5773502691896258 + 0.0071 };
    const double len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    const double d[3] = { dir[0] / len, dir[1] / len, dir[2] / len };
    for (int k = 0; k < GetNumberOfObjects(); ++k)
    {
      if (!Closed_[k])
      {
        continue;
      }
      // Inside if the ray crosses the object an odd number of times and the
      // nearest crossing is seen from behind (a room seen from inside is
      // closed too, but its walls face the light).
      int crossings = 0;
      double nearest = std::numeric_limits<double>::infinity();
      bool nearestFromBehind = false;
      for (int p = PatchOffsets_[k]; p < PatchOffsets_[k + 1]; ++p)
      {
        double t;
        if (RayCaster::IntersectTriangle(x, d, &Points_[3 * Triangles_[3 * p]],
              &Points_[3 * Triangles_[3 * p + 1]], &Points_[3 * Triangles_[3 * p + 2]], 0.0,
              std::numeric_limits<double>::infinity(), t))
        {
          ++crossings;
          if (t < nearest)
          {
            nearest = t;
            const double* n = &Normals_[3 * p];
            nearestFromBehind = n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0.0;
          }
        }
      }
      if (crossings % 2 == 1 && nearestFromBehind)
      {
        std::ostringstream os;
        os << "light " << l << " at (" << x[0] << ", " << x[1] << ", " << x[2]
           << ") is inside the closed " << (Objects_[k].Translucent ? "translucent" : "opaque")
           << " " << ObjectName(Objects_[k].Name, k) << ": it would light nothing";
        throw Error(os.str());
      }
    }
  }
}

void RadiosityScene::ComputeDirectIrradiance(const std::vector<LightSource>& lights, bool shadows,
  std::vector<double>& incident, std::vector<double>& transmitted) const
{
  CheckLights(lights);
  const int numPatches = GetNumberOfPatches();
  incident.assign(3 * static_cast<size_t>(numPatches), 0.0);
  transmitted.assign(3 * static_cast<size_t>(numPatches), 0.0);
  const double offset = GetRayOffset();
#pragma omp parallel for schedule(dynamic, 64)
  for (int p = 0; p < numPatches; ++p)
  {
    const double* x = &Centroids_[3 * p];
    const double* n = &Normals_[3 * p];
    const bool translucent = Objects_[PatchObject_[p]].Translucent;
    for (const LightSource& light : lights)
    {
      double e[3], q[3], w[3], distance;
      // eta = 1: no interface, the plain irradiance n . w_i (I / d^2 or E).
      if (!DirectIrradiance(light, x, n, 1.0, e, w, distance))
      {
        continue;
      }
      if (shadows)
      {
        const double origin[3] = { x[0] + offset * n[0], x[1] + offset * n[1],
          x[2] + offset * n[2] };
        if (Caster_.Occluded(origin, w, distance))
        {
          continue;
        }
      }
      if (translucent)
      {
        DirectIrradiance(light, x, n, PatchEta_[p], q, w, distance);
      }
      for (int c = 0; c < 3; ++c)
      {
        incident[3 * p + c] += e[c];
        transmitted[3 * p + c] += translucent ? q[c] : e[c];
      }
    }
  }
}

void RadiosityScene::BoxSurface(const double lo[3], const double hi[3], double cellSize,
  bool inward, int skipFace, std::vector<double>& points, std::vector<int>& triangles,
  std::vector<int>* faceIds, std::size_t memoryLimit)
{
  if (!(cellSize > 0.0) || !std::isfinite(cellSize))
  {
    throw Error("box surface: cell size must be finite and > 0, not " + FormatNumber(cellSize));
  }
  for (int d = 0; d < 3; ++d)
  {
    if (!(hi[d] > lo[d]))
    {
      throw Error("box surface: every side must have a positive length");
    }
  }
  double counts[3];
  for (int d = 0; d < 3; ++d)
  {
    counts[d] = std::max(1.0, std::round((hi[d] - lo[d]) / cellSize)); // inf for an overflow
  }
  const double patches =
    4.0 * (counts[0] * counts[1] + counts[1] * counts[2] + counts[0] * counts[2]);
  {
    std::ostringstream what;
    what << "box surface: " << FormatNumber(patches) << " patches (cell size "
         << FormatNumber(cellSize) << " mm on a box of " << FormatNumber(hi[0] - lo[0]) << " x "
         << FormatNumber(hi[1] - lo[1]) << " x " << FormatNumber(hi[2] - lo[2]) << " mm)";
    CheckMemory(what.str(), patches * 1024.0, memoryLimit, "use a larger cell_size");
    if (!(patches * 3.0 < static_cast<double>(std::numeric_limits<int>::max())))
    {
      throw Error(what.str() + ", more than the 32-bit indices hold: use a larger cell_size");
    }
  }
  int cells[3];
  for (int d = 0; d < 3; ++d)
  {
    cells[d] = static_cast<int>(counts[d]);
  }
  // Shared grid points on the surface: index every lattice point once.
  std::map<std::array<int, 3>, int> ids;
  auto pointId = [&](int i, int j, int k) {
    const std::array<int, 3> key{ i, j, k };
    auto it = ids.find(key);
    if (it != ids.end())
    {
      return it->second;
    }
    const int id = static_cast<int>(points.size() / 3);
    const int ijk[3] = { i, j, k };
    for (int d = 0; d < 3; ++d)
    {
      points.push_back(lo[d] + (hi[d] - lo[d]) * ijk[d] / cells[d]);
    }
    ids.emplace(key, id);
    return id;
  };
  points.clear();
  triangles.clear();
  if (faceIds)
  {
    faceIds->clear();
  }
  for (int face = 0; face < 6; ++face)
  {
    if (face == skipFace)
    {
      continue;
    }
    const int axis = face / 2, side = face % 2;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    // (u, v, axis) is right-handed: e_u x e_v = e_axis. Outward normal of
    // the max face is +e_axis.
    const bool flip = (side == 1) == inward;
    for (int a = 0; a < cells[u]; ++a)
    {
      for (int b = 0; b < cells[v]; ++b)
      {
        int corner[4];
        const int du[4] = { 0, 1, 1, 0 }, dv[4] = { 0, 0, 1, 1 };
        for (int m = 0; m < 4; ++m)
        {
          int ijk[3];
          ijk[axis] = side * cells[axis];
          ijk[u] = a + du[m];
          ijk[v] = b + dv[m];
          corner[m] = pointId(ijk[0], ijk[1], ijk[2]);
        }
        const int tri[2][3] = { { corner[0], corner[1], corner[2] },
          { corner[0], corner[2], corner[3] } };
        for (const auto& t : tri)
        {
          triangles.push_back(t[0]);
          triangles.push_back(flip ? t[2] : t[1]);
          triangles.push_back(flip ? t[1] : t[2]);
          if (faceIds)
          {
            faceIds->push_back(face);
          }
        }
      }
    }
  }
}

} // namespace translucency
