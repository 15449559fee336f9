#include "TranslucencyHxtMesher.h"

#include <array>
#include <climits>
#include <cmath>
#include <cstdint>
#include <queue>
#include <tuple>
#include <unordered_map>

#ifdef TRANSLUCENCY_HAVE_GMSH
#include "TranslucencyChildProcess.h"

#include <dlfcn.h>
#include <gmshc.h>
#include <omp.h>

#include <cstring>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <mutex>
#endif

namespace translucency
{

namespace
{
/// The key of the undirected edge {a, b}.
std::uint64_t EdgeKey(int a, int b)
{
  const auto lo = static_cast<std::uint32_t>(a < b ? a : b);
  const auto hi = static_cast<std::uint32_t>(a < b ? b : a);
  return (static_cast<std::uint64_t>(lo) << 32) | hi;
}
} // namespace

int CountSurfaceParts(std::size_t numPoints, const std::vector<int>& triangles)
{
  // Union-find over the points of each triangle: the parts are the
  // connected components of the points used by triangles.
  std::vector<int> parent(numPoints);
  for (std::size_t i = 0; i < numPoints; ++i)
  {
    parent[i] = static_cast<int>(i);
  }
  auto find = [&parent](int i) {
    while (parent[static_cast<std::size_t>(i)] != i)
    {
      parent[static_cast<std::size_t>(i)] =
        parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
      i = parent[static_cast<std::size_t>(i)];
    }
    return i;
  };
  std::vector<char> used(numPoints, 0);
  for (std::size_t k = 0; k < triangles.size(); ++k)
  {
    used[static_cast<std::size_t>(triangles[k])] = 1;
    if (k % 3 != 0)
    {
      const int a = find(triangles[k - k % 3]), b = find(triangles[k]);
      parent[static_cast<std::size_t>(a)] = b;
    }
  }
  int parts = 0;
  for (std::size_t i = 0; i < numPoints; ++i)
  {
    parts += used[i] && find(static_cast<int>(i)) == static_cast<int>(i) ? 1 : 0;
  }
  return parts;
}

bool RefineSurfaceLongestEdge(
  std::vector<double>& points, std::vector<int>& triangles, double maxEdge, std::string& error)
{
  if (!(maxEdge > 0.0) || !std::isfinite(maxEdge))
  {
    error = "surface refinement needs a finite edge length > 0 mm";
    return false;
  }
  const long long numPoints = static_cast<long long>(points.size() / 3);
  for (const int id : triangles)
  {
    if (id < 0 || id >= numPoints)
    {
      error = "surface refinement: point id " + std::to_string(id) + " out of range";
      return false;
    }
  }
  // Edge -> the two triangles sharing it.
  std::unordered_map<std::uint64_t, std::array<int, 2>> edges;
  edges.reserve(triangles.size());
  auto attach = [&edges](int a, int b, int triangle) {
    std::array<int, 2>& slot =
      edges.emplace(EdgeKey(a, b), std::array<int, 2>{ -1, -1 }).first->second;
    int& free = slot[0] < 0 ? slot[0] : slot[1];
    if (free >= 0)
    {
      return false; // a third triangle on this edge
    }
    free = triangle;
    return true;
  };
  auto length2 = [&points](int a, int b) {
    double sum = 0.0;
    for (int d = 0; d < 3; ++d)
    {
      const double e = points[3 * static_cast<std::size_t>(a) + d] -
        points[3 * static_cast<std::size_t>(b) + d];
      sum += e * e;
    }
    return sum;
  };
  const double limit2 = maxEdge * maxEdge;
  // The longest edge first; ties by ids, so the result does not depend on
  // the hash map's order.
  using Entry = std::tuple<double, int, int>;
  std::priority_queue<Entry> queue;
  auto consider = [&](int a, int b) {
    const double l2 = length2(a, b);
    if (l2 > limit2)
    {
      queue.emplace(l2, a < b ? a : b, a < b ? b : a);
    }
  };
  const int numTriangles = static_cast<int>(triangles.size() / 3);
  for (int t = 0; t < numTriangles; ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      if (!attach(triangles[3 * t + k], triangles[3 * t + (k + 1) % 3], t))
      {
        error = "surface refinement: an edge is shared by more than two triangles";
        return false;
      }
    }
  }
  for (const auto& edge : edges)
  {
    if (edge.second[1] < 0)
    {
      error = "surface refinement: the surface is not closed";
      return false;
    }
    consider(static_cast<int>(edge.first >> 32), static_cast<int>(edge.first & 0xffffffffu));
  }
  while (!queue.empty())
  {
    const int a = std::get<1>(queue.top());
    const int b = std::get<2>(queue.top());
    queue.pop();
    const std::uint64_t key = EdgeKey(a, b);
    const auto found = edges.find(key);
    if (found == edges.end())
    {
      continue; // split already (an entry pushed twice)
    }
    const std::array<int, 2> sharing = found->second;
    edges.erase(found);
    if (points.size() / 3 >= static_cast<std::size_t>(INT_MAX / 2) ||
      triangles.size() / 3 >= static_cast<std::size_t>(INT_MAX / 2))
    {
      error = "surface refinement: more points than 32-bit ids hold (edge length too small)";
      return false;
    }
    const int m = static_cast<int>(points.size() / 3);
    for (int d = 0; d < 3; ++d)
    {
      points.push_back(0.5 * (points[3 * static_cast<std::size_t>(a) + d] +
        points[3 * static_cast<std::size_t>(b) + d]));
    }
    for (const int t : sharing)
    {
      int k = 0;
      while (k < 3 && EdgeKey(triangles[3 * t + k], triangles[3 * t + (k + 1) % 3]) != key)
      {
        ++k;
      }
      if (k == 3)
      {
        error = "surface refinement: inconsistent edge map"; // cannot happen
        return false;
      }
      // t = (x, y, c) with the split edge x -> y in t's own order: t becomes
      // (x, m, c) and the new triangle (m, y, c), both oriented as t.
      const int x = triangles[3 * t + k], y = triangles[3 * t + (k + 1) % 3],
                c = triangles[3 * t + (k + 2) % 3];
      const int added = static_cast<int>(triangles.size() / 3);
      triangles[3 * t] = x;
      triangles[3 * t + 1] = m;
      triangles[3 * t + 2] = c;
      triangles.push_back(m);
      triangles.push_back(y);
      triangles.push_back(c);
      std::array<int, 2>& yc = edges[EdgeKey(y, c)];
      (yc[0] == t ? yc[0] : yc[1]) = added;
      attach(x, m, t);
      attach(m, y, added);
      attach(m, c, t);
      attach(m, c, added);
      consider(m, c);
    }
    consider(a, m);
    consider(m, b);
  }
  return true;
}

#ifndef TRANSLUCENCY_HAVE_GMSH

bool HasHxtMesher()
{
  return false;
}

std::string GetHxtMesherVersion()
{
  return "";
}

bool RunHxtMesher(const std::vector<double>&, const std::vector<int>&, const HxtMesherOptions&,
  std::vector<double>&, std::vector<int>&, std::string& error)
{
  error = "this build has no gmsh: the hxt mesher needs libgmsh-dev at build time "
          "(scripts/install-deps.sh, CMake option TRANSLUCENCY_USE_GMSH); use the tetgen mesher";
  return false;
}

#else

namespace
{
/// gmsh's C API, loaded with dlmopen(LM_ID_NEWLM) instead of linked (see
/// the header): libgmsh's own TetGen clashes with Debian's libtet, which our
/// TetGen path links, and RTLD_DEEPBIND broke gmsh's std::regex.
struct GmshApi
{
  void* Handle = nullptr;
  std::string LoadError;
#define TRANSLUCENCY_GMSH_FUNCTIONS(X)                                                             \
  X(Initialize)                                                                                    \
  X(Clear)                                                                                         \
  X(Free)                                                                                          \
  X(OptionSetNumber)                                                                               \
  X(OptionGetString)                                                                               \
  X(ModelAdd)                                                                                      \
  X(ModelAddDiscreteEntity)                                                                        \
  X(ModelGetEntities)                                                                              \
  X(ModelMeshAddNodes)                                                                             \
  X(ModelMeshAddElementsByType)                                                                    \
  X(ModelMeshClassifySurfaces)                                                                     \
  X(ModelMeshCreateGeometry)                                                                       \
  X(ModelGeoAddSurfaceLoop)                                                                        \
  X(ModelGeoAddVolume)                                                                             \
  X(ModelGeoSynchronize)                                                                           \
  X(ModelMeshGenerate)                                                                             \
  X(ModelMeshGetElementsByType)                                                                    \
  X(ModelMeshGetNodes)                                                                             \
  X(LoggerStart)                                                                                   \
  X(LoggerStop)                                                                                    \
  X(LoggerGetLastError)
#define TRANSLUCENCY_GMSH_MEMBER(name) decltype(&gmsh##name) name = nullptr;
  TRANSLUCENCY_GMSH_FUNCTIONS(TRANSLUCENCY_GMSH_MEMBER)
#undef TRANSLUCENCY_GMSH_MEMBER
  bool Initialized = false;
};

std::mutex& GmshMutex()
{
  static std::mutex mutex;
  return mutex;
}

/// Restores the caller's OpenMP thread count: gmsh sets it from its options.
struct OmpThreadsGuard
{
  int Saved = omp_get_max_threads();
  ~OmpThreadsGuard() { omp_set_num_threads(Saved); }
};

/// Thrown by Check; caught in this file only.
struct GmshFailure
{
  std::string Message;
};

/// Loads gmsh once (under GmshMutex). On failure LoadError says why.
/// Set after a failed mesh: gmsh 4.8.4's GenerateMesh sets CTX::lock and an
/// exception (AbortOnError) skips its release, so every later mesh in that
/// instance returns nothing ("I'm busy!"). The next call loads a fresh copy.
bool& NeedsFreshGmsh()
{
  static bool fresh = false;
  return fresh;
}

GmshApi& Api()
{
  static GmshApi* current = nullptr;
  static int loads = 0;
  if (current && !NeedsFreshGmsh())
  {
    return *current;
  }
  // A fresh copy in a new link-map namespace; the old one is left loaded
  // (unloading gmsh with its OpenMP runtime is not safe). glibc allows 16
  // namespaces: past that dlmopen fails and LoadError says so.
  NeedsFreshGmsh() = false;
  current = new GmshApi;
  GmshApi& api = *current;
  if (++loads > 8)
  {
    api.LoadError = "gmsh failed too often in this process (after each failed mesh gmsh 4.8.4 "
                    "has to be loaded anew, at most 8 times): restart, or use the tetgen mesher";
    return api;
  }
  api.Handle = dlmopen(LM_ID_NEWLM, TRANSLUCENCY_GMSH_LIBRARY, RTLD_NOW | RTLD_LOCAL);
  if (!api.Handle)
  {
    const char* why = dlerror();
    api.LoadError = std::string("cannot load gmsh (") + TRANSLUCENCY_GMSH_LIBRARY +
      "): " + (why ? why : "unknown error") + "; install libgmsh4.8 (scripts/install-deps.sh)";
    return api;
  }
#define TRANSLUCENCY_GMSH_LOAD(name)                                                               \
  api.name = reinterpret_cast<decltype(&gmsh##name)>(dlsym(api.Handle, "gmsh" #name));             \
  if (!api.name)                                                                                   \
  {                                                                                                \
    api.LoadError = std::string("gmsh (") + TRANSLUCENCY_GMSH_LIBRARY + ") has no gmsh" #name;     \
    return api;                                                                                    \
  }
  TRANSLUCENCY_GMSH_FUNCTIONS(TRANSLUCENCY_GMSH_LOAD)
#undef TRANSLUCENCY_GMSH_LOAD
  return api;
}

/// gmsh's last error after a failed call (ierr != 0).
std::string LastError(GmshApi& api)
{
  char* text = nullptr;
  int ierr = 0;
  api.LoggerGetLastError(&text, &ierr);
  std::string last = text ? text : "";
  if (text)
  {
    api.Free(text);
  }
  while (!last.empty() && (last.back() == ' ' || last.back() == '\n'))
  {
    last.pop_back();
  }
  return last;
}

void Check(GmshApi& api, int ierr, const char* call)
{
  if (ierr != 0)
  {
    const std::string last = LastError(api);
    throw GmshFailure{ last.empty() ? std::string("gmsh ") + call + " failed" : last };
  }
}

/// Loads and initialises gmsh once (under GmshMutex): no configuration files,
/// no terminal output, errors as exceptions inside gmsh (which its C API
/// turns into ierr), never exit().
GmshApi& Ready()
{
  GmshApi& api = Api();
  if (!api.LoadError.empty())
  {
    throw GmshFailure{ api.LoadError };
  }
  if (!api.Initialized)
  {
    int ierr = 0;
    api.Initialize(0, nullptr, 0, &ierr);
    Check(api, ierr, "initialize");
    api.OptionSetNumber("General.Terminal", 0, &ierr);
    Check(api, ierr, "General.Terminal");
    api.OptionSetNumber("General.Verbosity", 2, &ierr); // errors and warnings, to its logger
    Check(api, ierr, "General.Verbosity");
    api.OptionSetNumber("General.AbortOnError", 2, &ierr);
    Check(api, ierr, "General.AbortOnError");
    api.LoggerStart(&ierr); // keeps the last error for LastError
    Check(api, ierr, "logger");
    api.Initialized = true;
  }
  return api;
}

/**
 * HXT's optimisation pass (gmsh 4.8.4) can return two nodes at the same
 * coordinates, each carrying tets (measured: 3 such pairs in a 3,626-tet mesh
 * of a sphere, none without the pass): a crack through the mesh. The points
 * of equal coordinates are merged (the first kept, ids renumbered); a tet
 * left with a repeated corner (zero volume) is dropped.
 */
void MergeCoincidentPoints(std::vector<double>& points, std::vector<int>& tets)
{
  const std::size_t n = points.size() / 3;
  std::vector<int> order(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    order[i] = static_cast<int>(i);
  }
  const double* p = points.data();
  std::sort(order.begin(), order.end(), [p](int a, int b) {
    return std::lexicographical_compare(p + 3 * static_cast<std::size_t>(a),
      p + 3 * static_cast<std::size_t>(a) + 3, p + 3 * static_cast<std::size_t>(b),
      p + 3 * static_cast<std::size_t>(b) + 3);
  });
  std::vector<int> first(order.size());
  bool merged = false;
  for (std::size_t k = 0; k < order.size(); ++k)
  {
    const std::size_t i = static_cast<std::size_t>(order[k]);
    first[i] = order[k];
    if (k > 0 && std::equal(p + 3 * i, p + 3 * i + 3, p + 3 * static_cast<std::size_t>(order[k - 1])))
    {
      first[i] = first[static_cast<std::size_t>(order[k - 1])];
      merged = true;
    }
  }
  if (!merged)
  {
    return;
  }
  std::vector<int> newId(n, -1);
  std::vector<double> kept;
  kept.reserve(points.size());
  for (std::size_t i = 0; i < n; ++i)
  {
    if (first[i] == static_cast<int>(i))
    {
      newId[i] = static_cast<int>(kept.size() / 3);
      kept.insert(kept.end(), p + 3 * i, p + 3 * i + 3);
    }
  }
  std::vector<int> keptTets;
  keptTets.reserve(tets.size());
  for (std::size_t t = 0; 4 * t < tets.size(); ++t)
  {
    int ids[4];
    for (int k = 0; k < 4; ++k)
    {
      ids[k] = newId[static_cast<std::size_t>(first[static_cast<std::size_t>(tets[4 * t + k])])];
    }
    if (ids[0] == ids[1] || ids[0] == ids[2] || ids[0] == ids[3] || ids[1] == ids[2] ||
      ids[1] == ids[3] || ids[2] == ids[3])
    {
      continue;
    }
    keptTets.insert(keptTets.end(), ids, ids + 4);
  }
  points.swap(kept);
  tets.swap(keptTets);
}

/// Frees arrays gmsh allocated.
template <typename T>
struct GmshArray
{
  GmshApi& Owner;
  T* Data = nullptr;
  size_t Size = 0;
  explicit GmshArray(GmshApi& owner)
    : Owner(owner)
  {
  }
  ~GmshArray()
  {
    if (Data)
    {
      Owner.Free(Data);
    }
  }
  GmshArray(const GmshArray&) = delete;
  GmshArray& operator=(const GmshArray&) = delete;
};
} // namespace

bool HasHxtMesher()
{
  return true;
}

std::string GetHxtMesherVersion()
{
  std::lock_guard<std::mutex> lock(GmshMutex());
  OmpThreadsGuard threads;
  try
  {
    GmshApi& api = Ready();
    char* text = nullptr;
    int ierr = 0;
    api.OptionGetString("General.Version", &text, &ierr);
    std::string version = (ierr == 0 && text) ? text : "";
    if (text)
    {
      api.Free(text);
    }
    return version;
  }
  catch (const GmshFailure&)
  {
    return "";
  }
}

namespace
{
/// RunHxtMesher in the calling process (the child RunHxtMesher forks).
bool RunHxtMesherHere(const std::vector<double>& points, const std::vector<int>& triangles,
  const HxtMesherOptions& options, std::vector<double>& outPoints, std::vector<int>& outTets,
  std::string& error)
{
  if (!(options.MeshSize > 0) || !std::isfinite(options.MeshSize))
  {
    error = "the hxt mesher needs a mesh size > 0 mm";
    return false;
  }
  // One closed surface: HXT fails on several (measured: two disjoint
  // spheres, "HXT 3D mesh failed").
  const int parts = CountSurfaceParts(points.size() / 3, triangles);
  if (parts > 1)
  {
    error = "the hxt mesher fills one closed surface; this one has " + std::to_string(parts) +
      " separate parts: use the tetgen mesher, or mesh the parts one by one";
    return false;
  }
  // The surface HXT gets: the input, or the input refined (not with
  // RemeshSurface: gmsh re-meshes it to MeshSize itself).
  std::vector<double> refinedPoints;
  std::vector<int> refinedTriangles;
  const bool refine = !options.RemeshSurface && options.SurfaceEdgeLength > 0.0;
  if (refine)
  {
    refinedPoints = points;
    refinedTriangles = triangles;
    if (!RefineSurfaceLongestEdge(
          refinedPoints, refinedTriangles, options.SurfaceEdgeLength, error))
    {
      return false;
    }
  }
  const std::vector<double>& surfacePoints = refine ? refinedPoints : points;
  const std::vector<int>& surfaceTriangles = refine ? refinedTriangles : triangles;
  const std::size_t numPoints = surfacePoints.size() / 3;
  std::lock_guard<std::mutex> lock(GmshMutex());
  OmpThreadsGuard threadsGuard;
  GmshApi* apiPointer = nullptr;
  try
  {
    GmshApi& api = Ready();
    apiPointer = &api;
    int ierr = 0;
    api.Clear(&ierr);
    Check(api, ierr, "clear");
    auto set = [&api](const char* name, double value) {
      int e = 0;
      api.OptionSetNumber(name, value, &e);
      Check(api, e, name);
    };
    const int threads = options.Threads > 0 ? options.Threads : threadsGuard.Saved;
    set("General.NumThreads", threads);
    set("Mesh.MaxNumThreads3D", threads);
    set("Mesh.Algorithm3D", 10); // HXT
    set("Mesh.Optimize", options.Optimize ? 1 : 0);
    set("Mesh.OptimizeThreshold", options.OptimizeThreshold);
    set("Mesh.MeshSizeMax", options.MeshSize);
    set("Mesh.MeshSizeMin", options.RemeshSurface ? options.MeshSize : 0.0);
    set("Mesh.MeshSizeFromPoints", options.RemeshSurface ? 0 : 1);
    // On a refined surface the interior takes MeshSize, not the sizes
    // interpolated from the surface: the count then follows MeshSize smoothly.
    set("Mesh.MeshSizeExtendFromBoundary", options.RemeshSurface || refine ? 0 : 1);
    set("Mesh.MeshSizeFromCurvature", 0);

    api.ModelAdd("translucency", &ierr);
    Check(api, ierr, "model/add");
    const int surface = api.ModelAddDiscreteEntity(2, -1, nullptr, 0, &ierr);
    Check(api, ierr, "model/addDiscreteEntity");
    std::vector<std::size_t> nodeTags(numPoints);
    for (std::size_t i = 0; i < numPoints; ++i)
    {
      nodeTags[i] = i + 1;
    }
    std::vector<double> coordinates(surfacePoints);
    api.ModelMeshAddNodes(2, surface, nodeTags.data(), nodeTags.size(), coordinates.data(),
      coordinates.size(), nullptr, 0, &ierr);
    Check(api, ierr, "mesh/addNodes");
    std::vector<std::size_t> triangleNodes(surfaceTriangles.size());
    for (std::size_t i = 0; i < surfaceTriangles.size(); ++i)
    {
      triangleNodes[i] = static_cast<std::size_t>(surfaceTriangles[i]) + 1;
    }
    api.ModelMeshAddElementsByType(
      surface, 2, nullptr, 0, triangleNodes.data(), triangleNodes.size(), &ierr);
    Check(api, ierr, "mesh/addElementsByType");
    // One closed discrete surface -> a geo volume bounded by it. To re-mesh the
    // surface it must be split into patches gmsh can parametrise (tutorial t13).
    if (options.RemeshSurface)
    {
      api.ModelMeshClassifySurfaces(40.0 * M_PI / 180.0, 0, 1, M_PI, 1, &ierr);
      Check(api, ierr, "mesh/classifySurfaces");
      api.ModelMeshCreateGeometry(nullptr, 0, &ierr);
      Check(api, ierr, "mesh/createGeometry");
    }
    // Kept as it is, the one discrete surface bounds the volume directly: no
    // classification (which took 1.2 of 10.3 s at 200k tets, for one patch).
    std::vector<int> surfaceTags;
    {
      GmshArray<int> dimTags(api);
      api.ModelGetEntities(&dimTags.Data, &dimTags.Size, 2, &ierr);
      Check(api, ierr, "model/getEntities");
      for (std::size_t i = 0; i + 1 < dimTags.Size; i += 2)
      {
        surfaceTags.push_back(dimTags.Data[i + 1]);
      }
    }
    int loop = api.ModelGeoAddSurfaceLoop(surfaceTags.data(), surfaceTags.size(), -1, &ierr);
    Check(api, ierr, "geo/addSurfaceLoop");
    api.ModelGeoAddVolume(&loop, 1, -1, &ierr);
    Check(api, ierr, "geo/addVolume");
    api.ModelGeoSynchronize(&ierr);
    Check(api, ierr, "geo/synchronize");
    api.ModelMeshGenerate(3, &ierr);
    Check(api, ierr, "mesh/generate");

    GmshArray<std::size_t> tetTags(api), tetNodes(api);
    api.ModelMeshGetElementsByType(
      4, &tetTags.Data, &tetTags.Size, &tetNodes.Data, &tetNodes.Size, -1, 0, 1, &ierr);
    Check(api, ierr, "mesh/getElementsByType");
    if (tetTags.Size == 0)
    {
      throw GmshFailure{ "hxt produced no tetrahedra" };
    }
    GmshArray<std::size_t> allTags(api);
    GmshArray<double> coords(api), parametric(api);
    api.ModelMeshGetNodes(&allTags.Data, &allTags.Size, &coords.Data, &coords.Size,
      &parametric.Data, &parametric.Size, -1, -1, 1, 0, &ierr);
    Check(api, ierr, "mesh/getNodes");
    std::size_t maxTag = 0;
    for (std::size_t i = 0; i < allTags.Size; ++i)
    {
      maxTag = std::max(maxTag, allTags.Data[i]);
    }
    std::vector<long long> where(maxTag + 1, -1); // tag -> index in coords
    for (std::size_t i = 0; i < allTags.Size; ++i)
    {
      where[allTags.Data[i]] = static_cast<long long>(i);
    }
    for (std::size_t k = 0; k < tetNodes.Size; ++k)
    {
      if (tetNodes.Data[k] > maxTag || where[tetNodes.Data[k]] < 0)
      {
        throw GmshFailure{ "hxt returned a tet with an unknown node" };
      }
    }
    // Nodes on the surface (classified on a surface or below it).
    std::vector<char> onSurface(maxTag + 1, 0);
    {
      GmshArray<std::size_t> surfaceNodes(api);
      GmshArray<double> surfaceCoords(api), surfaceParametric(api);
      api.ModelMeshGetNodes(&surfaceNodes.Data, &surfaceNodes.Size, &surfaceCoords.Data,
        &surfaceCoords.Size, &surfaceParametric.Data, &surfaceParametric.Size, 2, -1, 1, 0, &ierr);
      Check(api, ierr, "mesh/getNodes(2)");
      for (std::size_t i = 0; i < surfaceNodes.Size; ++i)
      {
        if (surfaceNodes.Data[i] <= maxTag)
        {
          onSurface[surfaceNodes.Data[i]] = 1;
        }
      }
    }
    // HXT (without its optimisation pass) keeps flat tets whose four corners
    // lie on a planar part of the surface (measured: the bunny's flat base,
    // the quads of a UV sphere): zero volume, which the solvers reject. Such a
    // tet is dropped; the two faces it hid take its place on the (same, flat)
    // boundary, so the domain is unchanged.
    std::vector<int> newId(allTags.Size, -1);
    outPoints.clear();
    outTets.clear();
    outTets.reserve(tetNodes.Size);
    for (std::size_t t = 0; 4 * t < tetNodes.Size; ++t)
    {
      const double* p[4];
      bool allOnSurface = true;
      for (int k = 0; k < 4; ++k)
      {
        const std::size_t tag = tetNodes.Data[4 * t + k];
        p[k] = &coords.Data[3 * static_cast<std::size_t>(where[tag])];
        allOnSurface = allOnSurface && onSurface[tag];
      }
      if (allOnSurface)
      {
        double e[3][3], longest = 0.0;
        for (int k = 0; k < 3; ++k)
        {
          for (int d = 0; d < 3; ++d)
          {
            e[k][d] = p[k + 1][d] - p[0][d];
          }
        }
        for (int a = 0; a < 4; ++a)
        {
          for (int b = a + 1; b < 4; ++b)
          {
            const double dx = p[a][0] - p[b][0], dy = p[a][1] - p[b][1], dz = p[a][2] - p[b][2];
            longest = std::max(longest, std::sqrt(dx * dx + dy * dy + dz * dz));
          }
        }
        const double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
          e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
          e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
        if (std::abs(det) <= 1e-10 * longest * longest * longest)
        {
          continue;
        }
      }
      for (int k = 0; k < 4; ++k)
      {
        const std::size_t i = static_cast<std::size_t>(where[tetNodes.Data[4 * t + k]]);
        if (newId[i] < 0)
        {
          newId[i] = static_cast<int>(outPoints.size() / 3);
          outPoints.insert(outPoints.end(), &coords.Data[3 * i], &coords.Data[3 * i] + 3);
        }
        outTets.push_back(newId[i]);
      }
    }
    api.Clear(&ierr);
    MergeCoincidentPoints(outPoints, outTets);
    return true;
  }
  catch (const GmshFailure& failure)
  {
    error = "hxt failed: " + failure.Message;
  }
  catch (const std::exception& e)
  {
    error = std::string("hxt failed: ") + e.what();
  }
  if (apiPointer)
  {
    int ierr = 0;
    apiPointer->Clear(&ierr);
    NeedsFreshGmsh() = true; // this instance may be locked (see NeedsFreshGmsh)
  }
  return false;
}

/// What the child sends back before its arrays.
struct HxtResultHeader
{
  std::uint64_t Done = 0; ///< 1: meshed; 0: Message is the error
  std::uint64_t MessageSize = 0;
  std::uint64_t PointValues = 0; ///< 3 per point
  std::uint64_t TetValues = 0;   ///< 4 per tet
};

/// The child's side: mesh and send the result down `fd`.
bool MeshInChild(int fd, const std::vector<double>& points, const std::vector<int>& triangles,
  const HxtMesherOptions& options)
{
  std::vector<double> outPoints;
  std::vector<int> outTets;
  std::string message;
  bool done = false;
  try
  {
    done = RunHxtMesherHere(points, triangles, options, outPoints, outTets, message);
  }
  catch (const std::exception& e)
  {
    message = std::string("hxt failed: ") + e.what();
  }
  HxtResultHeader header;
  header.Done = done ? 1 : 0;
  header.MessageSize = message.size();
  header.PointValues = done ? outPoints.size() : 0;
  header.TetValues = done ? outTets.size() : 0;
  bool ok = WriteAll(fd, &header, sizeof(header));
  ok = ok && WriteAll(fd, message.data(), message.size());
  ok = ok && WriteAll(fd, outPoints.data(), sizeof(double) * header.PointValues);
  return ok && WriteAll(fd, outTets.data(), sizeof(int) * header.TetValues);
}
} // namespace

bool RunHxtMesher(const std::vector<double>& points, const std::vector<int>& triangles,
  const HxtMesherOptions& options, std::vector<double>& outPoints, std::vector<int>& outTets,
  std::string& error)
{
  // In a child process, as TetGen (vtkTetrahedralizeSurface.cxx): gmsh is
  // loaded there only. Loaded into the caller, the TBB runtime of gmsh's
  // link-map namespace crashed the process at its exit (SIGSEGV in libtbb's
  // static destructors under __cxa_finalize: every pvbatch, pvpython and
  // ParaView GUI run that had used hxt, session 27); and a crash inside gmsh
  // is now a clean error instead of the caller's end.
  HxtResultHeader header;
  std::string message;
  auto read = [&](int fd) {
    // Sizes the child could not have made are a broken stream, not a mesh.
    bool received = ReadAll(fd, &header, sizeof(header)) &&
      header.MessageSize < (std::uint64_t(1) << 20) && header.PointValues % 3 == 0 &&
      header.TetValues % 4 == 0 && header.PointValues < (std::uint64_t(1) << 40) &&
      header.TetValues < (std::uint64_t(1) << 40);
    message.assign(received ? header.MessageSize : 0, '\0');
    received = received && ReadAll(fd, &message[0], message.size());
    if (received && header.Done == 1)
    {
      outPoints.resize(header.PointValues);
      outTets.resize(header.TetValues);
      received = ReadAll(fd, outPoints.data(), sizeof(double) * outPoints.size()) &&
        ReadAll(fd, outTets.data(), sizeof(int) * outTets.size());
    }
    return received;
  };
  const ChildOutcome outcome = RunInChildProcess(
    [&](int fd) { return MeshInChild(fd, points, triangles, options); }, read);
  if (!outcome.Started)
  {
    error = "hxt could not be started (" + outcome.StartError + ")";
  }
  else if (outcome.Signal != 0)
  {
    error = "hxt crashed on this surface (signal " + std::to_string(outcome.Signal) + ", " +
      strsignal(outcome.Signal) + "): check the surface, or try the tetgen mesher";
  }
  else if (!outcome.Received || outcome.ExitStatus != 0)
  {
    error = "hxt stopped without handing back its result (exit status " +
      std::to_string(outcome.ExitStatus) + ")";
  }
  else if (header.Done != 1)
  {
    error = message;
  }
  else
  {
    return true;
  }
  outPoints.clear();
  outTets.clear();
  return false;
}

#endif

} // namespace translucency
