/**
 * @class   vtkSurfaceIrradiance
 * @brief   Boundary irradiance q transmitted into a translucent tet mesh.
 *
 * For every boundary point of the input tetrahedral mesh, computes
 * q(x) = integral of L_i (n . w_i) F_t(w_i) dw_i (TransCut eq. 2), the light
 * that crosses the smooth dielectric surface (Fresnel transmittance F_t with
 * the mesh's `RefractiveIndex`), from:
 *  - directional lights: irradiance E (W/mm^2) on a surface facing the light,
 *    given with the direction the light travels;
 *  - point lights: radiant intensity I (W/sr) at a position (mm), with
 *    inverse-square fall-off;
 *  - a uniform (environment) light: irradiance E (W/mm^2) that an unoccluded
 *    flat surface would receive.
 * The object shadows itself: a light contributes at a point only if a ray
 * from the point towards the light leaves without hitting the boundary
 * surface again (translucency::RayCaster, a bounding volume hierarchy over
 * the boundary triangles; the points are processed in parallel with OpenMP by
 * translucency::ComputeBoundaryIrradiance). The uniform light is integrated
 * with UniformLightSamples cosine-weighted rays per point (ambient
 * occlusion); with 0 samples it is unoccluded and exact.
 *
 * q is evaluated per boundary triangle (at each corner with the triangle's
 * own normal) and projected to the points
 * (translucency::ComputeProjectedIrradiance), so the solvers' load is the
 * triangle-integrated irradiance: a flat lit face injects E cos F_t S and a
 * face parallel to a light nothing (Documentation/DiffuseOptics.md).
 *
 * Output: a shallow copy of the input with the point array `Irradiance`
 * (3 components R, G, B, W/mm^2; 0 at interior points). The lights are
 * also recorded in the field data (`TranslucencyLights`: 12 components per
 * light — kind 0 directional / 1 point / 2 spot, direction or position,
 * power R, G, B, then the spot's axis (3), cut-off (degrees) and exponent;
 * `TranslucencyUniformLight`; `TranslucencyShadows`) for solvers that launch
 * photons from them (vtkSolveDiffusion's Monte Carlo reference).
 *
 * **Default lights**: when no light is given (no directional or point light,
 * no interactive light and UniformLightIrradiance 0) and DefaultLights is on
 * (the default), the filter uses the project's one default lighting, the
 * same as `translucency` without `--light` and the ParaView panel: a
 * directional light along (0, -1, -1) of 1 W/mm^2 and a uniform light of
 * 0.1 W/mm^2 (translucency/Physics/DefaultLights.h). Turn DefaultLights off
 * for no boundary light at all (interior sources alone). The lights used are
 * described in the field data (`TranslucencyLightsDescription`, in the CLI's
 * --light syntax) and by GetLightsDescription().
 *
 * **Under MPI** (more than one process) each rank computes its own piece:
 * only the physical boundary surface is all-gathered, for the shadow rays
 * (vtkTranslucencyDistributedIrradiance.h, Documentation/Parallel.md); the
 * result equals the serial one to round-off. TRANSLUCENCY_GATHERED_IRRADIANCE=1
 * gathers the mesh to rank 0 instead. GetParallelPath() tells which ran.
 *
 * @warning The input must hold
 * only linear tetrahedra and the cell array `RefractiveIndex`.
 *
 * @sa vtkSolveDiffusion vtkOutgoingRadiance
 */
#ifndef vtkSurfaceIrradiance_h
#define vtkSurfaceIrradiance_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkUnstructuredGridAlgorithm.h"

#include <memory>
#include <string>
#include <vector>

namespace translucency
{
struct LightSource;
}

class vtkTranslucencyCommunicator;
struct vtkTranslucencyParallelPlan;

class TRANSLUCENCYFILTERS_EXPORT vtkSurfaceIrradiance : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkSurfaceIrradiance* New();
  vtkTypeMacro(vtkSurfaceIrradiance, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /**
   * Directional lights: direction of travel (need not be unit) and
   * irradiance E (W/mm^2, >= 0). None by default.
   */
  void AddDirectionalLight(double dx, double dy, double dz, double irradiance);
  void RemoveAllDirectionalLights();
  int GetNumberOfDirectionalLights() const;
  ///@}

  ///@{
  /// Point lights: position (mm) and radiant intensity I (W/sr, >= 0). None by default.
  void AddPointLight(double x, double y, double z, double intensity);
  void RemoveAllPointLights();
  int GetNumberOfPointLights() const;
  ///@}

  ///@{
  /// Coloured directional and point lights: E (W/mm^2) or I (W/sr) per
  /// channel R, G, B (each >= 0); they join the lists above.
  void AddDirectionalLightRGB(double dx, double dy, double dz, double r, double g, double b);
  void AddPointLightRGB(double x, double y, double z, double r, double g, double b);
  ///@}

  ///@{
  /**
   * The ParaView panel's coloured tables (properties ColouredDirectionalLights
   * and ColouredPointLights): the same lights as AddDirectionalLightRGB and
   * AddPointLightRGB, kept in lists of their own so that each panel table
   * clears only its own rows (ParaView pushes one table at a time, calling
   * its clean command first; the grey tables keep RemoveAllDirectionalLights
   * and RemoveAllPointLights, so existing state files and scripts are
   * unchanged). They join the lights of the other lists. None by default.
   */
  void AddColouredDirectionalLight(double dx, double dy, double dz, double r, double g, double b);
  void RemoveAllColouredDirectionalLights();
  void AddColouredPointLight(double x, double y, double z, double r, double g, double b);
  void RemoveAllColouredPointLights();
  ///@}

  ///@{
  /**
   * Spot lights: position (mm), axis direction (any length), cone half-angle
   * `cutoff` (degrees, in (0, 180]), fall-off exponent (>= 0) and intensity
   * I (W/sr) per channel on the axis; at angle alpha from the axis the
   * intensity is I cos(alpha)^exponent inside the cone and 0 outside
   * (translucency::LightSource::Kind::Spot). None by default.
   */
  void AddSpotLight(double x, double y, double z, double dx, double dy, double dz,
    double cutoff, double exponent, double r, double g, double b);
  void RemoveAllSpotLights();
  int GetNumberOfSpotLights() const;
  ///@}

  ///@{
  /// Uniform light irradiance E (W/mm^2); 0 (default) means none.
  vtkSetClampMacro(UniformLightIrradiance, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(UniformLightIrradiance, double);
  ///@}

  ///@{
  /**
   * Rays per boundary point for the occlusion of the uniform light.
   * Default 32; 0 disables its occlusion (then q = E * hemispherical F_t).
   */
  vtkSetClampMacro(UniformLightSamples, int, 0, 4096);
  vtkGetMacro(UniformLightSamples, int);
  ///@}

  /// How the directional (collimated) lights enter the diffusion model.
  /// The values 0-2 are translucency::CollimatedModel's (the core table
  /// translucency::GetCollimatedModelTable(), which the plugin's list is
  /// tested against).
  enum CollimatedModels
  {
    COLLIMATED_SURFACE = 0,  ///< as boundary irradiance q
    COLLIMATED_EXTENDED = 1, ///< as a volume source (translucency::ComputeCollimatedSource)
    /// as COLLIMATED_EXTENDED, with the Robin condition from the Fresnel
    /// moments (translucency::CollimatedModel::ExtendedMoments)
    COLLIMATED_EXTENDED_MOMENTS = 2,
    /// the default: the model of the scene's light kinds
    /// (translucency::DefaultCollimatedModel, measured against Monte Carlo)
    COLLIMATED_DEFAULT = 3
  };

  ///@{
  /**
   * COLLIMATED_DEFAULT (the default): `Irradiance` holds every light, as
   * under COLLIMATED_SURFACE, and the field data marks the choice as the
   * default (`TranslucencyCollimatedModel` = 0,
   * `TranslucencyCollimatedModelByDefault` = 1): vtkSolveDiffusion then
   * solves the model of the core's default table for the scene's light
   * kinds (translucency::DefaultCollimatedModel, measured against Monte
   * Carlo; Documentation/DiffuseOptics.md, "Which collimated model by
   * default"), taking the directional lights out of its irradiance when
   * that model is an extended one (divergence and fem, where the table
   * was measured; quadgraph, grid and sp3 solve the surface model).
   * COLLIMATED_SURFACE: the directional lights are part of `Irradiance`.
   * COLLIMATED_EXTENDED: they are left out of `Irradiance` (the point and
   * uniform lights stay) and the field data records the model
   * (`TranslucencyCollimatedModel` = 1), so that vtkSolveDiffusion adds the
   * unscattered beam and its volume source (Documentation/DiffuseOptics.md,
   * "Collimated beams: the extended source"); quadgraph and grid refuse it.
   * COLLIMATED_EXTENDED_MOMENTS (= 2 in the field data): the same, and the
   * solve's Robin condition takes A and Fdr from the Fresnel moments.
   */
  vtkSetClampMacro(CollimatedModel, int, COLLIMATED_SURFACE, COLLIMATED_DEFAULT);
  vtkGetMacro(CollimatedModel, int);
  /// Set the model by its name: "default" or a name of the core table
  /// ("surface", "extended", "extended-moments"); false (and an error) for
  /// an unknown name.
  bool SetCollimatedModelByName(const char* name);
  ///@}

  ///@{
  /// The core tables, for scripts and the test that compares them with the
  /// plugin XML: the number of models, the name and label of model `i` (in
  /// the enum's order), and the default model's name for a light kind
  /// ("directional", "coloured", "spot", "pencil"; "" for an unknown kind).
  static int GetNumberOfCollimatedModels();
  static std::string GetCollimatedModelName(int i);
  static std::string GetCollimatedModelLabel(int i);
  static std::string GetDefaultCollimatedModelName(const char* kind);
  /// "directional: extended-moments, coloured: ..." (the plugin's help).
  static std::string DescribeCollimatedDefaults();
  ///@}

  ///@{
  /**
   * Use the default lights (directional (0, -1, -1) 1 W/mm^2 + uniform
   * 0.1 W/mm^2) when no light is given. Default on; off means no light.
   */
  vtkSetMacro(DefaultLights, bool);
  vtkGetMacro(DefaultLights, bool);
  vtkBooleanMacro(DefaultLights, bool);
  ///@}

  ///@{
  /**
   * One more light placed with a line widget in ParaView (off by default).
   * Type 0: directional, travelling from Point1 to Point2 (mm; only the
   * direction matters), irradiance Power (W/mm^2). Type 1: point light at
   * Point1 (Point2 unused), intensity Power (W/sr).
   */
  vtkSetMacro(InteractiveLight, bool);
  vtkGetMacro(InteractiveLight, bool);
  vtkBooleanMacro(InteractiveLight, bool);
  vtkSetClampMacro(InteractiveLightType, int, 0, 1);
  vtkGetMacro(InteractiveLightType, int);
  vtkSetVector3Macro(InteractiveLightPoint1, double);
  vtkGetVector3Macro(InteractiveLightPoint1, double);
  vtkSetVector3Macro(InteractiveLightPoint2, double);
  vtkGetVector3Macro(InteractiveLightPoint2, double);
  vtkSetMacro(InteractiveLightPower, double);
  vtkGetMacro(InteractiveLightPower, double);
  ///@}

  /// The lights of the last execution in the CLI's --light syntax, e.g.
  /// "directional:0,-1,-1:1 uniform:0.1 (the default)"; "none" for no light.
  const char* GetLightsDescription() const { return this->LightsDescription.c_str(); }

  ///@{
  /// Self-shadowing by ray casting (default on).
  vtkSetMacro(Shadows, bool);
  vtkGetMacro(Shadows, bool);
  vtkBooleanMacro(Shadows, bool);
  ///@}

  /// Wall time (ms) this filter spent building the mesh topology in its last
  /// execution; 0 when the topology came from the shared cache.
  double GetTopologyTime() const { return this->TopologyTime; }

  ///@{
  /**
   * What the last execution computed: the number of directional, point and
   * spot lights, and whether the uniform light's occlusion. Serial runs keep
   * each light's term and the uniform light's across executions
   * (translucency::IrradianceCache, keyed on the mesh geometry, the
   * refractive index and the light's parameters), so turning one light
   * recomputes that light only; so does the distributed path
   * (vtkTranslucencyDistributedIrradiance::State: the gathered surface and
   * the terms kept while every rank's piece and refractive index are the same).
   */
  int GetNumberOfLightsComputed() const { return this->LightsComputed; }
  bool GetUniformComputed() const { return this->UniformComputed; }
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

  /// The distributed path's boundary surface in the last execution (0 on
  /// the other paths): its triangles, the bytes every rank received for it,
  /// and the wall time (ms) of the numbering, face count and gather.
  long long GetBoundarySurfaceTriangles() const { return this->BoundarySurfaceTriangles; }
  long long GetBoundarySurfaceBytes() const { return this->BoundarySurfaceBytes; }
  double GetBoundarySurfaceTime() const { return this->BoundarySurfaceTime; }

protected:
  vtkSurfaceIrradiance();
  ~vtkSurfaceIrradiance() override;

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
  /// The lights on this rank's piece: the serial code, or (`distributed`,
  /// collective) the distributed path on the all-gathered boundary surface.
  int RequestLights(
    vtkInformationVector** inputVector, vtkInformationVector* outputVector, bool distributed);

  double UniformLightIrradiance = 0.0;
  int UniformLightSamples = 32;
  bool Shadows = true;
  bool DefaultLights = true;
  bool InteractiveLight = false;
  int InteractiveLightType = 0;
  double InteractiveLightPoint1[3] = { 0.0, 1.0, 1.0 };
  double InteractiveLightPoint2[3] = { 0.0, 0.0, 0.0 };
  double InteractiveLightPower = 1.0;
  int CollimatedModel = COLLIMATED_DEFAULT;
  double TopologyTime = 0.0;
  std::string LightsDescription;
  long long BoundarySurfaceTriangles = 0;
  long long BoundarySurfaceBytes = 0;
  double BoundarySurfaceTime = 0.0;
  int LightsComputed = 0;
  bool UniformComputed = false;

private:
  vtkSurfaceIrradiance(const vtkSurfaceIrradiance&) = delete;
  void operator=(const vtkSurfaceIrradiance&) = delete;

  struct Internals;
  std::unique_ptr<Internals> Internal;

  /// The output: `input` with the Irradiance `q` and the lights' field data.
  bool AttachOutputs(vtkUnstructuredGrid* input, vtkUnstructuredGrid* output,
    const std::vector<translucency::LightSource>& lights, double uniformIrradiance,
    const std::vector<double>& q);

  /// The lights in the CLI's --light syntax ("none" for none).
  static std::string DescribeLights(
    const std::vector<translucency::LightSource>& lights, double uniformIrradiance);
};

#endif
