/**
 * @class   vtkTetrahedralizeSurface
 * @brief   Fill a closed triangle surface with quality tetrahedra (TetGen or gmsh's HXT).
 *
 * vtkTetrahedralizeSurface takes a vtkPolyData holding a closed, manifold,
 * non-degenerate triangle surface (lengths in mm) and produces a
 * vtkUnstructuredGrid of linear tetrahedra filling it, with either a maximum
 * tet volume or a target number of tets, by one of two meshers (SetMesher):
 * - "tetgen" (default): TetGen 1.5, Delaunay refinement with a radius-edge
 *   quality bound (-q Quality), single-threaded;
 * - "hxt", when the build has gmsh (HasMesher("hxt")): gmsh's
 *   HXT parallel Delaunay mesher (gmsh 4.8, Mesh.Algorithm3D = 10). HXT keeps
 *   the surface it is given and sizes the interior from it, so the input
 *   surface is first refined by longest-edge bisection to about the interior
 *   edge length (its shape unchanged), then HXT fills it and its
 *   optimisation pass (SetHxtOptimization, on) removes the Delaunay slivers.
 *   HXT bounds edge lengths, not volumes or radius-edge ratios: MaxTetVolume
 *   V maps to the edge length of the regular tet of that volume, h = (6
 *   sqrt(2) V)^(1/3); Quality is not used. The meshes meet the quality
 *   criterion of Documentation/Performance.md ("Tetrahedralisers": smallest
 *   dihedral angle, tets below 5 degrees, radius-edge ratio, each at least
 *   TetGen's); translucency::ComputeTetQuality measures them, `translucency
 *   bench --meshers` prints them. Not the default (yet): see that section.
 * Both see the same checked surface and fail with the same messages on bad
 * input, and both outputs get the same Morton reordering and orientation.
 * Neither produces region attributes (one region: the whole enclosed volume).
 *
 * Sizing (SetUniformSizing): by default the meshes are graded: TetGen keeps
 * the input surface and refines towards it (quality bound near coarse
 * triangles), so cells near the surface are smaller than inside. With
 * uniform sizing every cell aims at one edge length h (from the target count
 * or MaxTetVolume): TetGen gets h as a sizing function at every surface point
 * (-m), which also splits surface triangles longer than h (it cannot coarsen
 * a surface finer than h: such a surface keeps its finer cells); HXT re-meshes
 * the surface to h (gmsh classifySurfaces + createGeometry + 2D meshing; this
 * coarsens too). Uniform meshes are what QuadGraph needs (its eq. 5 does not
 * conserve light on graded meshes, Documentation/Solvers.md). Between the
 * two, SetGradingFactor(g) asks for surface cells g times smaller than the
 * interior ones, with a linear transition one interior cell deep (tetgen).
 *
 * The output points and tets are put in a spatial (Morton)
 * order, which makes the downstream assembly and solves cache-friendly.
 *
 * The input is checked before TetGen sees it; the error names the problem:
 * a non-finite coordinate or one of magnitude MaxCoordinate (1e15 mm) or
 * more, a point id out of range or an inconsistent cell array (these first,
 * before any VTK filter touches the data), empty input, a non-triangle cell, a degenerate (zero-area) triangle, an
 * edge used by one triangle (the surface is open; the count and the first
 * edge's position are given) or by more than two (non-manifold), a flat
 * surface enclosing no volume, and triangles crossing each other
 * (self-intersection, found by a TetGen -d pass, because TetGen 1.5.0 crashes
 * instead of reporting it when meshing).
 *
 * @warning TetGen is single-threaded: about 6 s for a million tets. With a
 * target number of tets, the mesher may run up to three times (the second
 * run corrects the size bound from the first run's count, the third on the
 * secant through the two; the closest count is kept). The count aims at
 * +-25 % of the target; when it misses by more, a warning says why and what
 * to do (one more run of the mesher at its coarsest tells it): a target
 * below what the input surface's resolution allows (TetGen keeps every
 * input triangle: the bunny's 3,674 triangles give at least 45,113
 * tets; decimate the surface or let hxt re-mesh it), or a count that does
 * not follow the bound (set MaxTetVolume instead).
 *
 * @sa vtkAssignScatteringCoefficients vtkSolveDiffusion
 */
#ifndef vtkTetrahedralizeSurface_h
#define vtkTetrahedralizeSurface_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkUnstructuredGridAlgorithm.h"

#include <string> // for the mesher's name

class vtkTranslucencyCommunicator;
struct vtkTranslucencyParallelPlan;

class TRANSLUCENCYFILTERS_EXPORT vtkTetrahedralizeSurface : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkTetrahedralizeSurface* New();
  vtkTypeMacro(vtkTetrahedralizeSurface, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// The largest coordinate magnitude accepted (mm): 1e15 mm (a million km)
  /// is far beyond any object while leaving TetGen's predicates and the
  /// squared lengths of the checks far from overflow.
  static constexpr double MaxCoordinate = 1e15;

  ///@{
  /**
   * Upper bound on the radius-edge ratio of every tet (TetGen -q). Must be
   * >= 1.1 (TetGen may not terminate below); default 1.414.
   */
  vtkSetClampMacro(Quality, double, 1.1, 100.0);
  vtkGetMacro(Quality, double);
  ///@}

  ///@{
  /**
   * Maximum volume of a tet in mm^3 (TetGen -a). 0 (default) means no bound
   * (unless a target number of tets is set).
   */
  vtkSetClampMacro(MaxTetVolume, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(MaxTetVolume, double);
  ///@}

  ///@{
  /**
   * Aim for about this many tets (0 = off, the default). When set it takes
   * precedence over MaxTetVolume.
   */
  vtkSetClampMacro(TargetNumberOfTets, vtkIdType, 0, VTK_ID_MAX);
  vtkGetMacro(TargetNumberOfTets, vtkIdType);
  ///@}

  ///@{
  /**
   * Memory limit in GiB (default 0: translucency::GetDefaultMemoryLimit(),
   * 8 GiB unless changed, e.g. by the CLI's --memory-limit). Before TetGen
   * runs, the tet count is estimated (TargetNumberOfTets, or the enclosed
   * volume / MaxTetVolume) at ~400 bytes per tet; above the limit the filter
   * fails with a message stating the count, the bytes and this override.
   */
  vtkSetClampMacro(MemoryLimit, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(MemoryLimit, double);
  ///@}

  ///@{
  /**
   * The mesher: "tetgen" (default) or "hxt" (case-insensitive). An unknown
   * name, or "hxt" in a build without gmsh, fails in RequestData with a
   * message naming the known meshers.
   */
  vtkSetStdStringFromCharMacro(Mesher);
  vtkGetCharFromStdStringMacro(Mesher);
  ///@}

  /// True for "tetgen", and for "hxt" when this build has gmsh.
  static bool HasMesher(const char* name);

  ///@{
  /**
   * Uniform sizing (default off): every cell aims at one edge length instead
   * of the mesher's grading towards the surface (see the class description).
   */
  vtkSetMacro(UniformSizing, bool);
  vtkGetMacro(UniformSizing, bool);
  vtkBooleanMacro(UniformSizing, bool);
  ///@}

  ///@{
  /**
   * Grading factor g (default 0: off, the mesher's own grading; else 1 <= g
   * <= 8): the ratio of the interior edge length h (from the target count or
   * MaxTetVolume) to the edge length at the surface, h / g. Between them the
   * target edge length grows linearly with the distance d from the surface,
   * h(d) = min(h, h / g + (1 - 1 / g) d), reaching h one interior edge length
   * deep. g = 1 is uniform sizing (as UniformSizing); g = 2 halves the surface
   * cells' edges. tetgen only: the sizing function is a background mesh
   * (TetGen -m with a coarse first mesh carrying h(d) at its points, d the
   * exact distance to the input surface). Like uniform sizing, TetGen refines
   * a coarser surface but cannot coarsen a finer one. Set together with
   * UniformSizing, or with hxt, RequestData fails with an error naming both.
   */
  vtkSetMacro(GradingFactor, double);
  vtkGetMacro(GradingFactor, double);
  ///@}

  ///@{
  /**
   * hxt only: run HXT's optimisation pass (gmsh Mesh.Optimize: edge removal,
   * small polyhedron reconnection and smoothing of every tet whose quality,
   * HXT's aspect ratio, is below 0.3) to remove the slivers of the Delaunay
   * mesh. Default on: on the surface refined to the interior size (which
   * the hxt path does first) it leaves no tet below 5 degrees on the bunny
   * (Documentation/Performance.md, "Tetrahedralisers": the criterion and the
   * measured table); off, the Delaunay mesh keeps slivers down to 0 degrees.
   */
  vtkSetMacro(HxtOptimization, bool);
  vtkGetMacro(HxtOptimization, bool);
  vtkBooleanMacro(HxtOptimization, bool);
  ///@}

  ///@{
  /**
   * Threads for the hxt mesher (0, the default: OpenMP's maximum, i.e.
   * OMP_NUM_THREADS or the number of cores). TetGen always uses one.
   */
  vtkSetClampMacro(NumberOfThreads, int, 0, 1024);
  vtkGetMacro(NumberOfThreads, int);
  ///@}

  ///@{
  /**
   * Reorder points and tets along a Morton curve (default on).
   */
  vtkSetMacro(SpatialReordering, bool);
  vtkGetMacro(SpatialReordering, bool);
  vtkBooleanMacro(SpatialReordering, bool);
  ///@}

  ///@{
  /**
   * The parallel seam (Documentation/Parallel.md, "What runs where").
   * GetParallelPath(): the path the last execution took: "serial" (one
   * process), "per piece", "distributed" or "gathered".
   * GetParallelPlan(): the plan this filter declares for more than one MPI
   * process, with its reason ("per piece: ..."); set by every execution, a
   * one-process one included ("" before the first).
   */
  const char* GetParallelPath() const { return this->ParallelPath.c_str(); }
  const char* GetParallelPlan() const { return this->ParallelPlan.c_str(); }
  ///@}

protected:
  vtkTetrahedralizeSurface();
  ~vtkTetrahedralizeSurface() override = default;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  /// Empties the outputs before anything upstream runs, so that a failure
  /// upstream leaves them empty (vtkTranslucencyDispatch::UpdateExtent).
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  friend struct vtkTranslucencyDispatchAccess; // RunFilter, UpdateExtent
  /// The plan for more than one process (vtkTranslucencyDispatch: called on
  /// every rank; collective over `comm`).
  vtkTranslucencyParallelPlan PlanParallel(
    vtkInformationVector** inputVector, const vtkTranslucencyCommunicator& comm);
  /// The serial path (one process, or rank 0 of a gathered run).
  int RequestSerial(vtkInformation*, vtkInformationVector**, vtkInformationVector*);
  std::string ParallelPath = "serial";
  std::string ParallelPlan;

  double Quality = 1.414;
  double MaxTetVolume = 0.0;
  vtkIdType TargetNumberOfTets = 0;
  double MemoryLimit = 0.0;
  bool SpatialReordering = true;
  std::string Mesher = "tetgen";
  bool UniformSizing = false;
  double GradingFactor = 0.0;
  int NumberOfThreads = 0;
  bool HxtOptimization = true;

private:
  vtkTetrahedralizeSurface(const vtkTetrahedralizeSurface&) = delete;
  void operator=(const vtkTetrahedralizeSurface&) = delete;
};

#endif
