/**
 * @file TranslucencyHxtMesher.h
 * @brief gmsh's HXT parallel Delaunay mesher (gmsh >= 4.8, `Mesh.Algorithm3D
 * = 10`) behind a plain C++ call: a checked closed triangle surface in,
 * points and tets out.
 *
 * Private to the Filters module (vtkTetrahedralizeSurface is its only user).
 * It is VTK-free but lives here, not in Solvers/Mesh: gmsh is an optional
 * dependency (CMake option TRANSLUCENCY_USE_GMSH, on when libgmsh-dev is
 * found), like TetGen a mesher the filters call, and the core library must
 * build and link the same with or without it. Without gmsh the functions
 * exist and RunHxtMesher fails with "this build has no gmsh".
 *
 * gmsh keeps global state (one API instance per process, options, a current
 * model, its own logger, and it calls omp_set_num_threads): every call is
 * serialised by a mutex, gmsh is initialised once and never finalised, its
 * terminal output is off (messages go to its logger, from which errors are
 * taken), its errors come back through its C API's error codes
 * (General.AbortOnError = 2: gmsh throws inside, the C API catches; it does
 * not exit()), and the caller's OpenMP thread count is restored afterwards.
 *
 * gmsh is loaded with dlmopen(LM_ID_NEWLM) into a link-map namespace of its
 * own, not linked: libgmsh carries its own TetGen under the same symbol names
 * as Debian's libtet, which the TetGen path links; linked together, gmsh's
 * calls went to libtet's functions and crashed (SIGSEGV in the first HXT run
 * after a TetGen run). dlopen(RTLD_DEEPBIND) avoided that but broke gmsh's
 * std::regex (std::bad_cast from its locale facets in gmsh::initialize, in the
 * CLI). In its own namespace gmsh has its own C++ and OpenMP runtimes; every
 * array it returns is freed with its gmshFree.
 *
 * RunHxtMesher runs all of this in a child process (fork; the result comes
 * back through a pipe, as TetGen's in vtkTetrahedralizeSurface.cxx): loaded
 * into the caller, the TBB runtime of gmsh's namespace crashed every pvbatch,
 * pvpython and ParaView GUI process that had used hxt at its exit (SIGSEGV in
 * libtbb's static destructors); and a crash inside gmsh is a clean error.
 */
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace translucency
{

/// Options of one HXT run.
struct HxtMesherOptions
{
  /// Target edge length inside (mm, > 0): gmsh's Mesh.MeshSizeMax.
  double MeshSize = 1.0;
  /// Uniform sizing: the surface is re-meshed to MeshSize first (gmsh's
  /// classifySurfaces (40 degrees) + createGeometry + 2D meshing) and every size is
  /// MeshSize (Mesh.MeshSizeMin = Mesh.MeshSizeMax). Off: the input triangles are
  /// kept and sizes grow from theirs to at most MeshSize.
  bool RemeshSurface = false;
  /// Run HXT's optimisation pass (gmsh Mesh.Optimize = 1), which improves
  /// every tet whose quality (HXT's aspect ratio, 1 for the regular tet) is
  /// below OptimizeThreshold. Off here; the filter turns it on (with
  /// SurfaceEdgeLength): on the input surface as it is (coarse against the
  /// interior) it cost 9x the meshing time on the bunny at 200k tets, on the
  /// refined surface about 1.2-1.3x.
  bool Optimize = false;
  /// gmsh Mesh.OptimizeThreshold (default 0.3).
  double OptimizeThreshold = 0.3;
  /// Refine the input surface before HXT sees it (mm; 0, the default: keep
  /// it): longest-edge bisection (RefineSurfaceLongestEdge) until no edge is
  /// longer than this. HXT keeps the surface it is given and sizes the
  /// interior from it (Mesh.MeshSizeExtendFromBoundary), so a surface much
  /// coarser than MeshSize grades into slivers; refined to about MeshSize the
  /// mesh is near uniform. Ignored with RemeshSurface.
  double SurfaceEdgeLength = 0.0;
  /// Threads for HXT (gmsh General.NumThreads and Mesh.MaxNumThreads3D); 0:
  /// omp_get_max_threads().
  int Threads = 0;
};

/**
 * Refines a closed triangle surface (points: x, y, z per point; triangles: 3
 * ids per triangle, every edge shared by exactly two triangles) by
 * longest-edge bisection until no edge is longer than maxEdge (mm, > 0): the
 * longest edge of the whole surface is split at its midpoint, and with it
 * both triangles that share it, again and again (an edge that is the longest
 * of all is the longest of each of its triangles, so this is Rivara's
 * bisection: no angle drops below half the smallest input angle; the
 * surface's shape is unchanged, only subdivided). New points are appended;
 * the triangles are replaced, each keeping its orientation. Returns false
 * with a message in error on a non-manifold edge or a bad id.
 */
bool RefineSurfaceLongestEdge(std::vector<double>& points, std::vector<int>& triangles,
  double maxEdge, std::string& error);

/// The number of connected parts of a triangle surface (points joined by
/// triangles); the hxt mesher fills one.
int CountSurfaceParts(std::size_t numPoints, const std::vector<int>& triangles);

/// True when this build links gmsh.
bool HasHxtMesher();

/// gmsh's version string ("4.8.4"), or "" without gmsh.
std::string GetHxtMesherVersion();

/**
 * Tetrahedralises the closed surface (points: x, y, z per point in mm;
 * triangles: 3 ids per triangle, 0-based, already checked: closed, manifold,
 * no self-intersection) with HXT. Fills points (x, y, z) and tets (4 ids,
 * 0-based, only points used by a tet are returned; flat tets whose four
 * corners lie on the surface, |6V| <= 1e-10 (longest edge)^3, are dropped:
 * HXT leaves them on planar parts of the surface). Returns false with a
 * message in error (gmsh's own last error where it gave one), never throws.
 */
bool RunHxtMesher(const std::vector<double>& points, const std::vector<int>& triangles,
  const HxtMesherOptions& options, std::vector<double>& outPoints, std::vector<int>& outTets,
  std::string& error);

} // namespace translucency
