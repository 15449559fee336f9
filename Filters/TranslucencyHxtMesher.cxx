#include "TranslucencyHxtMesher.h"

#ifdef TRANSLUCENCY_HAVE_GMSH
#include <dlfcn.h>
#include <gmshc.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <mutex>
#endif

namespace translucency
{

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
GmshApi& Api()
{
  static GmshApi api;
  static bool tried = false;
  if (tried)
  {
    return api;
  }
  tried = true;
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

bool RunHxtMesher(const std::vector<double>& points, const std::vector<int>& triangles,
  const HxtMesherOptions& options, std::vector<double>& outPoints, std::vector<int>& outTets,
  std::string& error)
{
  if (!(options.MeshSize > 0) || !std::isfinite(options.MeshSize))
  {
    error = "the hxt mesher needs a mesh size > 0 mm";
    return false;
  }
  const std::size_t numPoints = points.size() / 3;
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
    set("Mesh.MeshSizeExtendFromBoundary", options.RemeshSurface ? 0 : 1);
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
    std::vector<double> coordinates(points);
    api.ModelMeshAddNodes(2, surface, nodeTags.data(), nodeTags.size(), coordinates.data(),
      coordinates.size(), nullptr, 0, &ierr);
    Check(api, ierr, "mesh/addNodes");
    std::vector<std::size_t> triangleNodes(triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i)
    {
      triangleNodes[i] = static_cast<std::size_t>(triangles[i]) + 1;
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
    else
    {
      api.ModelMeshClassifySurfaces(M_PI, 0, 0, M_PI, 1, &ierr);
      Check(api, ierr, "mesh/classifySurfaces");
    }
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
  }
  return false;
}

#endif

} // namespace translucency
