/**
 * @class   vtkTranslucentRadiosity
 * @brief   Inter-reflection between translucent and diffuse objects:
 *          B = (I - S F)^-1 S E (TranslucentRadiosity, eq. 14).
 *
 * Input: a vtkPartitionedDataSetCollection or a vtkMultiBlockDataSet whose
 * leaves are
 *  - translucent objects: vtkUnstructuredGrid tet meshes with the cell arrays
 *    `AbsorptionCoefficient`, `ReducedScatteringCoefficient` (3 components,
 *    1/mm) and `RefractiveIndex`; their patches are the boundary triangles;
 *  - opaque diffuse surfaces: vtkPolyData of triangles with the cell array
 *    `Albedo` (3 components, R, G, B in [0, 1]); patches are one-sided, lit
 *    on the side of the normal (p1 - p0) x (p2 - p0).
 *
 * Output: the same structure; every leaf is a vtkPolyData of its patches
 * (an opaque leaf is shallow-copied; a translucent leaf is replaced by its
 * outward-oriented boundary surface with `vtkOriginalCellIds`, the tet owning
 * each patch) with the cell arrays (3 components, W/mm^2):
 * `DirectIrradiance` (E), `DirectRadiosity` (E times the diffuse albedo; for
 * translucent patches the dipole stand-in, see Documentation/Radiosity.md),
 * `SubsurfaceRadiosity` (S E, first bounce), `InterReflectionRadiosity`
 * (B - S E), `Radiosity` (B) and, with ComputeHeuristics, `HeuristicRadiosity1`
 * ((I - P F)^-1 S E) and `HeuristicRadiosity2` (S E + (I - P F)^-1 P F P E).
 *
 * Lights: any number of point, spot and directional lights (AddPointLight,
 * AddSpotLight, AddDirectionalLight; RemoveAllLights), with shadows.
 *
 * The form factors are computed by ray casting (FormFactorComputer) and kept
 * while the geometry of the scene is unchanged, so relighting and changing
 * coefficients re-run only the iteration (and the S set-up). While the input
 * (the composite and each leaf, by modification time) is unchanged, the
 * scene is not even gathered again: a relight costs the solve only.
 *
 * @warning A light inside a closed object, an albedo outside [0, 1], a
 * translucent mesh without coefficients or a non-triangle cell is an error
 * (vtkErrorMacro naming the block). Not converging within MaxIter is a warning.
 *
 * @sa vtkSolveDiffusion vtkSurfaceIrradiance
 */
#ifndef vtkTranslucentRadiosity_h
#define vtkTranslucentRadiosity_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkDataObjectAlgorithm.h"

#include <memory>
#include <string>
#include <vector> // for the steps of RequestData

class vtkCompositeDataSet;
class vtkStringArray;
namespace translucency
{
struct LightSource;
class RadiosityScene;
class TranslucentRadiosity;
}

class vtkTranslucencyCommunicator;
struct vtkTranslucencyParallelPlan;

class TRANSLUCENCYFILTERS_EXPORT vtkTranslucentRadiosity : public vtkDataObjectAlgorithm
{
public:
  static vtkTranslucentRadiosity* New();
  vtkTypeMacro(vtkTranslucentRadiosity, vtkDataObjectAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum SubsurfaceMethods
  {
    SUBSURFACE_DIFFUSION = 0, ///< our diffusion solve (default)
    SUBSURFACE_PROFILE = 1    ///< the paper's dipole profile over optical paths
  };
  enum Iterations
  {
    ITERATION_JACOBI = 0,
    ITERATION_GAUSS_SEIDEL = 1
  };

  ///@{
  /// S operator (SubsurfaceMethods). Default SUBSURFACE_DIFFUSION.
  vtkSetClampMacro(SubsurfaceMethod, int, SUBSURFACE_DIFFUSION, SUBSURFACE_PROFILE);
  vtkGetMacro(SubsurfaceMethod, int);
  ///@}

  ///@{
  /// Iteration (Iterations). Default ITERATION_GAUSS_SEIDEL.
  vtkSetClampMacro(Iteration, int, ITERATION_JACOBI, ITERATION_GAUSS_SEIDEL);
  vtkGetMacro(Iteration, int);
  ///@}

  ///@{
  /// Relative change at which the iteration stops. Default 0.005 (0.5 %).
  vtkSetClampMacro(RelTol, double, 1e-14, 1.0);
  vtkGetMacro(RelTol, double);
  ///@}

  ///@{
  /// Iteration limit. Default 200.
  vtkSetClampMacro(MaxIter, int, 1, VTK_INT_MAX);
  vtkGetMacro(MaxIter, int);
  ///@}

  ///@{
  /// Rays per patch of the form factors. Default 256.
  vtkSetClampMacro(RaysPerPatch, int, 1, VTK_INT_MAX);
  vtkGetMacro(RaysPerPatch, int);
  ///@}

  ///@{
  /// Form factors below this are dropped. Default 0.
  vtkSetClampMacro(FormFactorThreshold, double, 0.0, 1.0);
  vtkGetMacro(FormFactorThreshold, double);
  ///@}

  ///@{
  /// Profile S: voxel size and cut-off max_d (mm; 0 = automatic). Default 0.
  vtkSetClampMacro(VoxelSize, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(VoxelSize, double);
  vtkSetClampMacro(MaxDistance, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(MaxDistance, double);
  ///@}

  ///@{
  /// Diffusion S: linear solver of the diffusion systems (a name of
  /// translucency::GetLinearSolverNames()). Default "cg-jacobi".
  vtkSetStdStringFromCharMacro(LinearSolver);
  vtkGetCharFromStdStringMacro(LinearSolver);
  ///@}

  /// The linear solvers this build has for the diffusion S (the choices of
  /// LinearSolver; the ParaView drop-down reads it).
  vtkStringArray* GetAvailableLinearSolvers();

  ///@{
  /// Shadows of the direct light. Default on.
  vtkSetMacro(Shadows, bool);
  vtkGetMacro(Shadows, bool);
  vtkBooleanMacro(Shadows, bool);
  ///@}

  ///@{
  /// Also output the two heuristics of the paper's Sec. 6.3. Default off.
  vtkSetMacro(ComputeHeuristics, bool);
  vtkGetMacro(ComputeHeuristics, bool);
  vtkBooleanMacro(ComputeHeuristics, bool);
  ///@}

  ///@{
  /// Lights. Power: intensity (W/sr) of point and spot lights, irradiance
  /// (W/mm^2) of directional ones, per channel. Spot: cone half-angle
  /// (degrees) and fall-off exponent.
  void AddPointLight(double x, double y, double z, double r, double g, double b);
  void AddDirectionalLight(double dx, double dy, double dz, double r, double g, double b);
  void AddSpotLight(double x, double y, double z, double dx, double dy, double dz, double cutoff,
    double exponent, double r, double g, double b);
  void RemoveAllLights();
  int GetNumberOfLights() const;
  ///@}

  ///@{
  /// A single light, for the ParaView panel: Type 0 = point, 1 = directional,
  /// 2 = spot (default point at (0, 0, 100)). Used when no light was added
  /// with Add*Light.
  vtkSetClampMacro(LightType, int, 0, 2);
  vtkGetMacro(LightType, int);
  vtkSetVector3Macro(LightPosition, double);
  vtkGetVector3Macro(LightPosition, double);
  vtkSetVector3Macro(LightDirection, double);
  vtkGetVector3Macro(LightDirection, double);
  vtkSetVector3Macro(LightPower, double);
  vtkGetVector3Macro(LightPower, double);
  vtkSetClampMacro(LightCutoff, double, 1e-3, 180.0);
  vtkGetMacro(LightCutoff, double);
  ///@}

  ///@{
  /// Statistics of the last execution: patches, iterations, converged, the
  /// times (ms) of the form factors (0 when reused), the S set-up, the direct
  /// light and S E, and the iteration; memory of F and S (bytes).
  int GetNumberOfPatches() const;
  int GetNumberOfIterations() const;
  bool GetConverged() const;
  double GetFormFactorTime() const;
  double GetSetupTime() const;
  double GetDirectTime() const;
  double GetSolveTime() const;
  vtkTypeInt64 GetFormFactorMemory() const;
  vtkTypeInt64 GetSubsurfaceMemory() const;
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
  vtkTranslucentRadiosity();
  ~vtkTranslucentRadiosity() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestDataObject(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
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

  int SubsurfaceMethod = SUBSURFACE_DIFFUSION;
  int Iteration = ITERATION_GAUSS_SEIDEL;
  double RelTol = 0.005;
  int MaxIter = 200;
  int RaysPerPatch = 256;
  double FormFactorThreshold = 0.0;
  double VoxelSize = 0.0;
  double MaxDistance = 0.0;
  bool Shadows = true;
  bool ComputeHeuristics = false;
  std::string LinearSolver = "cg-jacobi";
  int LightType = 0;
  double LightPosition[3] = { 0.0, 0.0, 100.0 };
  double LightDirection[3] = { 0.0, 0.0, -1.0 };
  double LightPower[3] = { 1000.0, 1000.0, 1000.0 };
  double LightCutoff = 30.0;

private:
  vtkTranslucentRadiosity(const vtkTranslucentRadiosity&) = delete;
  void operator=(const vtkTranslucentRadiosity&) = delete;

  struct Leaf;
  struct Internals;
  std::unique_ptr<Internals> Internal;

  ///@{
  /// The steps of RequestData (each throws translucency::Error on bad input).
  /// Leaves -> scene objects and output surfaces; false when aborted.
  bool GatherScene(
    vtkCompositeDataSet* input, translucency::RadiosityScene& scene, std::vector<Leaf>& leaves);
  /// The lights added, else the one light of the Light* settings.
  std::vector<translucency::LightSource> GetLights() const;
  /// Configure the kept (or a new) solver and solve into the result.
  translucency::TranslucentRadiosity& Solve();
  /// The per-patch results as cell arrays on new output leaves.
  void AttachOutputs(vtkCompositeDataSet* output, const std::vector<Leaf>& leaves,
    const std::vector<double>& h1, const std::vector<double>& h2);
  ///@}
};

#endif
