/**
 * @class   vtkAssignScatteringCoefficients
 * @brief   Attach per-tet optical coefficients to a tetrahedral mesh.
 *
 * Writes the three cell arrays of the data contract on a copy of the input:
 * `AbsorptionCoefficient` (mu_a, 3 components R, G, B, 1/mm),
 * `ReducedScatteringCoefficient` (sigma_s', 3 components, 1/mm) and
 * `RefractiveIndex` (eta, 1 component). Values are uniform: either a named
 * measured preset (Jensen et al. 2001: apple, chicken1, chicken2, cream,
 * ketchup, marble, potato, skimmilk, skin1, skin2, spectralon, wholemilk) or
 * the values set explicitly. A `vtkOriginalCellIds` array (the input cell
 * ids) is added when the input has none, so later cuts can map back.
 *
 * MaterialMode chooses how the coefficients vary (Documentation/Materials.md):
 * - UNIFORM (default): one material everywhere, the preset or the explicit
 *   values above (the behaviour of earlier versions).
 * - MATERIAL_IDS: a cell array of integer ids (MaterialIdArrayName, default
 *   TetGen's `RegionAttribute`) picks each tet's entry of the JSON material
 *   table MaterialTableFileName (read with vtkMaterialTableReader).
 * - SPHERICAL_INCLUSION: tets whose centroid lies in the closed ball
 *   (InclusionCenter, InclusionRadius) get InsideMaterial, the others
 *   OutsideMaterial.
 * - LAYERS: skin-like layers by depth below the surface. The depth of a tet
 *   is the distance from its centroid to the closest boundary triangle of
 *   the mesh; layer k (added with AddLayer, outermost first) holds depths in
 *   [sum of the thicknesses before k, that sum + thickness k); tets deeper
 *   than all layers get the last layer's material.
 * - VEINS: marble-like veins. With the turbulence
 *   t(x) = sum_{o < VeinOctaves} 2^-o |N(2^o f x + p)| (N: vtkPerlinNoise,
 *   amplitude 1, frequency 2^o f in each axis, phase p from VeinSeed),
 *   s(x) = sin(2 pi (f d.x + VeinTurbulence t(x))) (f = VeinFrequency,
 *   d = unit VeinDirection) and the vein weight w = (1 - |s|)^VeinSharpness,
 *   a tet with centroid x gets (1 - w) BaseMaterial + w VeinMaterial (each
 *   coefficient and eta blended linearly).
 * - VOLUME: values probed from a vtkImageData connected to the second input
 *   port (SetVolumeConnection / SetVolumeData), at each tet's centroid x.
 *   The voxel of x is found with vtkImageData::ComputeStructuredCoordinates
 *   (so origin, spacing and direction matrix are honoured); x outside the
 *   image bounds is an error. With VolumeMaterialIdArrayName empty, mu_a and
 *   sigma_s' come from the 3-component arrays VolumeAbsorptionArrayName /
 *   VolumeScatteringArrayName (1/mm, before ScaleFactor): a point array is
 *   interpolated trilinearly from the 8 voxel corners (exact for fields
 *   linear in x, y, z), a cell array gives the value of the voxel containing
 *   x; eta is RefractiveIndex. With VolumeMaterialIdArrayName set, that
 *   array holds integer material ids, taken without interpolation from the
 *   nearest voxel (point array: the nearest grid point, ties toward the
 *   higher index; cell array: the voxel containing x) and looked up in the
 *   material table as in MATERIAL_IDS (the table's entry gives mu_a,
 *   sigma_s' and eta). Point arrays are looked up before cell arrays.
 *
 * In the procedural modes a material is named by a reference: the name of a
 * table entry (when MaterialTableFileName is set), else the id of a table
 * entry written as an integer, else a measured preset name.
 *
 * @warning An unknown preset name or a negative / non-finite value is an
 * error (the filter returns 0 and says which value). So are a table error
 * (see vtkMaterialTableReader), a missing id array, a non-integer id or an
 * id absent from the table (the message names the tet and the id), an
 * unknown material reference and LAYERS mode without layers. In VOLUME
 * mode: no volume connected, a missing array or one with the wrong number
 * of components, a tet centroid outside the volume (the message names the
 * tet and the point) and a negative or NaN probed value (names the tet).
 *
 * @sa vtkTetrahedralizeSurface vtkSolveDiffusion
 */
#ifndef vtkAssignScatteringCoefficients_h
#define vtkAssignScatteringCoefficients_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkUnstructuredGridAlgorithm.h"

#include <string>
#include <vector> // for the layers

class vtkImageData;
class vtkPolyData;
class vtkUnstructuredGrid;
namespace translucency
{
struct MaterialField;
}


class vtkTranslucencyCommunicator;
struct vtkTranslucencyParallelPlan;

class TRANSLUCENCYFILTERS_EXPORT vtkAssignScatteringCoefficients
  : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkAssignScatteringCoefficients* New();
  vtkTypeMacro(vtkAssignScatteringCoefficients, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /**
   * Name of a measured preset (case-insensitive). When non-empty (default
   * "marble") it overrides the explicit coefficients below; set it to ""
   * to use them.
   */
  vtkSetStdStringFromCharMacro(MaterialName);
  vtkGetCharFromStdStringMacro(MaterialName);
  ///@}

  ///@{
  /// Explicit absorption coefficient mu_a (R, G, B), 1/mm. Default marble's.
  vtkSetVector3Macro(AbsorptionCoefficient, double);
  vtkGetVector3Macro(AbsorptionCoefficient, double);
  ///@}

  ///@{
  /// Explicit reduced scattering coefficient sigma_s' (R, G, B), 1/mm. Default marble's.
  vtkSetVector3Macro(ReducedScatteringCoefficient, double);
  vtkGetVector3Macro(ReducedScatteringCoefficient, double);
  ///@}

  ///@{
  /// Explicit refractive index eta. Default 1.3.
  vtkSetMacro(RefractiveIndex, double);
  vtkGetMacro(RefractiveIndex, double);
  ///@}

  ///@{
  /**
   * Multiply both coefficients by this factor (> 0, default 1). Scaling
   * the coefficients is the same as scaling the object by 1/ScaleFactor:
   * a user's way to say "the model is in cm, the coefficients in 1/mm".
   */
  vtkSetClampMacro(ScaleFactor, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(ScaleFactor, double);
  ///@}

  /// How the coefficients vary over the mesh (see the class documentation).
  enum MaterialModes
  {
    UNIFORM = 0,
    MATERIAL_IDS = 1,
    SPHERICAL_INCLUSION = 2,
    LAYERS = 3,
    VEINS = 4,
    VOLUME = 5
  };

  ///@{
  /// One of MaterialModes. Default UNIFORM.
  vtkSetClampMacro(MaterialMode, int, UNIFORM, VOLUME);
  vtkGetMacro(MaterialMode, int);
  void SetMaterialModeToUniform() { this->SetMaterialMode(UNIFORM); }
  void SetMaterialModeToMaterialIds() { this->SetMaterialMode(MATERIAL_IDS); }
  void SetMaterialModeToSphericalInclusion() { this->SetMaterialMode(SPHERICAL_INCLUSION); }
  void SetMaterialModeToLayers() { this->SetMaterialMode(LAYERS); }
  void SetMaterialModeToVeins() { this->SetMaterialMode(VEINS); }
  void SetMaterialModeToVolume() { this->SetMaterialMode(VOLUME); }
  ///@}

  ///@{
  /**
   * VOLUME: the vtkImageData probed at the tet centroids (optional second
   * input port, required in VOLUME mode only).
   */
  void SetVolumeConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetVolumeData(vtkDataObject* volume) { this->SetInputData(1, volume); }
  ///@}

  ///@{
  /// VOLUME: point or cell array of mu_a (3 components, 1/mm). Default "AbsorptionCoefficient".
  vtkSetStdStringFromCharMacro(VolumeAbsorptionArrayName);
  vtkGetCharFromStdStringMacro(VolumeAbsorptionArrayName);
  ///@}

  ///@{
  /// VOLUME: point or cell array of sigma_s' (3 components, 1/mm). Default "ReducedScatteringCoefficient".
  vtkSetStdStringFromCharMacro(VolumeScatteringArrayName);
  vtkGetCharFromStdStringMacro(VolumeScatteringArrayName);
  ///@}

  ///@{
  /**
   * VOLUME: point or cell array of integer material ids (1 component), looked
   * up in MaterialTableFileName. When set, the two arrays above are not used.
   * Default "" (probe the coefficients).
   */
  vtkSetStdStringFromCharMacro(VolumeMaterialIdArrayName);
  vtkGetCharFromStdStringMacro(VolumeMaterialIdArrayName);
  ///@}

  ///@{
  /**
   * JSON material table (format: vtkMaterialTableReader,
   * Documentation/Materials.md). Required by MATERIAL_IDS; optional in the
   * procedural modes (its names and ids become material references).
   * Default "" (none). Read at every execution.
   */
  vtkSetStdStringFromCharMacro(MaterialTableFileName);
  vtkGetCharFromStdStringMacro(MaterialTableFileName);
  ///@}

  ///@{
  /**
   * Cell array of integer material ids used by MATERIAL_IDS (any numeric
   * type, first component, values must be integers). Default
   * "RegionAttribute" (vtkTetGenReader's region attribute).
   */
  vtkSetStdStringFromCharMacro(MaterialIdArrayName);
  vtkGetCharFromStdStringMacro(MaterialIdArrayName);
  ///@}

  ///@{
  /// Centre of the inclusion of SPHERICAL_INCLUSION, mm. Default (0, 0, 0).
  vtkSetVector3Macro(InclusionCenter, double);
  vtkGetVector3Macro(InclusionCenter, double);
  ///@}

  ///@{
  /// Radius of the inclusion, mm (>= 0). Default 1.
  vtkSetClampMacro(InclusionRadius, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(InclusionRadius, double);
  ///@}

  ///@{
  /// Material reference inside the inclusion. Default "ketchup".
  vtkSetStdStringFromCharMacro(InsideMaterial);
  vtkGetCharFromStdStringMacro(InsideMaterial);
  ///@}

  ///@{
  /// Material reference outside the inclusion. Default "marble".
  vtkSetStdStringFromCharMacro(OutsideMaterial);
  vtkGetCharFromStdStringMacro(OutsideMaterial);
  ///@}

  ///@{
  /**
   * Layers of LAYERS mode, outermost first: a thickness (mm, >= 0) and a
   * material reference. Default none.
   */
  void AddLayer(double thickness, const char* material);
  void RemoveAllLayers();
  int GetNumberOfLayers() const { return static_cast<int>(this->LayerMaterials.size()); }
  ///@}

  ///@{
  /// VEINS: material between the veins (reference). Default "marble".
  vtkSetStdStringFromCharMacro(BaseMaterial);
  vtkGetCharFromStdStringMacro(BaseMaterial);
  ///@}

  ///@{
  /// VEINS: material of the vein centres (reference). Default "chicken1".
  vtkSetStdStringFromCharMacro(VeinMaterial);
  vtkGetCharFromStdStringMacro(VeinMaterial);
  ///@}

  ///@{
  /// VEINS: direction across the vein bands (normalized; not zero). Default (1, 0, 0).
  vtkSetVector3Macro(VeinDirection, double);
  vtkGetVector3Macro(VeinDirection, double);
  ///@}

  ///@{
  /// VEINS: f, vein bands per mm along VeinDirection and base noise frequency (1/mm, > 0). Default 0.2.
  vtkSetMacro(VeinFrequency, double);
  vtkGetMacro(VeinFrequency, double);
  ///@}

  ///@{
  /// VEINS: number of noise octaves (1 to 16). Default 4.
  vtkSetClampMacro(VeinOctaves, int, 1, 16);
  vtkGetMacro(VeinOctaves, int);
  ///@}

  ///@{
  /// VEINS: how far the noise bends the bands (>= 0; 0 gives straight bands). Default 1.
  vtkSetClampMacro(VeinTurbulence, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(VeinTurbulence, double);
  ///@}

  ///@{
  /// VEINS: exponent making the veins thin (>= 1). Default 8.
  vtkSetClampMacro(VeinSharpness, double, 1.0, VTK_DOUBLE_MAX);
  vtkGetMacro(VeinSharpness, double);
  ///@}

  ///@{
  /**
   * VEINS: seed of the noise; it sets the phase p = frac(seed * (0.7548776662,
   * 0.5698402910, 0.4301597090)) of vtkPerlinNoise. Default 0.
   */
  vtkSetMacro(VeinSeed, int);
  vtkGetMacro(VeinSeed, int);
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
  vtkAssignScatteringCoefficients();
  ~vtkAssignScatteringCoefficients() override = default;

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

  /**
   * The materials of MaterialMode on the tets of input (volume: the second
   * input, may be null). Throws translucency::Error on bad settings; returns
   * false when aborted.
   */
  bool ComputeMaterials(
    vtkUnstructuredGrid* input, vtkImageData* volume, translucency::MaterialField& field);
  int FillInputPortInformation(int port, vtkInformation* info) override;
  /// Under MPI, the per-tet modes on this rank's piece (collective).
  int RequestPerPiece(vtkInformationVector** inputVector, vtkInformationVector* outputVector,
    const vtkTranslucencyCommunicator& comm);
  /// output = input with the material arrays of `field`, and vtkOriginalCellIds
  /// firstId, firstId + 1, ... if the input has none.
  void AttachMaterials(vtkUnstructuredGrid* input, vtkUnstructuredGrid* output,
    const translucency::MaterialField& field, long long firstId);
  /// LAYERS per piece: the whole object's boundary surface (all-gathered),
  /// set during RequestPerPiece only (not owned); null: this input's own.
  vtkPolyData* WholeSurface = nullptr;
  /// VOLUME per piece: the number of this piece's first tet in the ranks'
  /// order (vtkOriginalCellIds), so that an error names the tet as the whole
  /// mesh numbers it; set during RequestPerPiece only.
  long long FirstTetNumber = 0;

  std::string MaterialName = "marble";
  double AbsorptionCoefficient[3] = { 0.0021, 0.0041, 0.0071 };
  double ReducedScatteringCoefficient[3] = { 2.19, 2.62, 3.00 };
  double RefractiveIndex = 1.3;
  double ScaleFactor = 1.0;
  int MaterialMode = UNIFORM;
  std::string MaterialTableFileName;
  std::string MaterialIdArrayName = "RegionAttribute";
  double InclusionCenter[3] = { 0.0, 0.0, 0.0 };
  double InclusionRadius = 1.0;
  std::string InsideMaterial = "ketchup";
  std::string OutsideMaterial = "marble";
  std::vector<double> LayerThicknesses;
  std::vector<std::string> LayerMaterials;
  std::string BaseMaterial = "marble";
  std::string VeinMaterial = "chicken1";
  double VeinDirection[3] = { 1.0, 0.0, 0.0 };
  double VeinFrequency = 0.2;
  int VeinOctaves = 4;
  double VeinTurbulence = 1.0;
  double VeinSharpness = 8.0;
  int VeinSeed = 0;
  std::string VolumeAbsorptionArrayName = "AbsorptionCoefficient";
  std::string VolumeScatteringArrayName = "ReducedScatteringCoefficient";
  std::string VolumeMaterialIdArrayName;

private:
  vtkAssignScatteringCoefficients(const vtkAssignScatteringCoefficients&) = delete;
  void operator=(const vtkAssignScatteringCoefficients&) = delete;
};

#endif
