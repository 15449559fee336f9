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
 * @warning An unknown preset name or a negative / non-finite value is an
 * error (the filter returns 0 and says which value).
 *
 * @sa vtkTetrahedralizeSurface vtkSolveDiffusion
 */
#ifndef vtkAssignScatteringCoefficients_h
#define vtkAssignScatteringCoefficients_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkUnstructuredGridAlgorithm.h"

#include <string>

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

protected:
  vtkAssignScatteringCoefficients();
  ~vtkAssignScatteringCoefficients() override = default;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  std::string MaterialName = "marble";
  double AbsorptionCoefficient[3] = { 0.0021, 0.0041, 0.0071 };
  double ReducedScatteringCoefficient[3] = { 2.19, 2.62, 3.00 };
  double RefractiveIndex = 1.3;
  double ScaleFactor = 1.0;

private:
  vtkAssignScatteringCoefficients(const vtkAssignScatteringCoefficients&) = delete;
  void operator=(const vtkAssignScatteringCoefficients&) = delete;
};

#endif
