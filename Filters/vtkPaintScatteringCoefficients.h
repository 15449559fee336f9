/**
 * @class   vtkPaintScatteringCoefficients
 * @brief   Paint the optical coefficients of a tet mesh along a 3D stroke.
 *
 * The painting interaction of TransCut (Sec. 5.2): a stroke is a set of 3D
 * points (AddStrokePoint, mm; e.g. picked on the surface). Every tet t gets
 * the influence weight
 *
 *     w_t = Strength * exp(-d_t^2 / (2 Width^2))
 *
 * where d_t is the distance (mm) from the tet's centroid (mean of its four
 * vertices) to the nearest stroke point, and for each channel c enabled in
 * ChannelMask its coefficients x (mu_a and sigma_s', 1/mm) become, with the
 * target value T of the same coefficient and channel:
 *  - SET:      x' = (1 - w) x + w T         (T: the target value, 1/mm)
 *  - MULTIPLY: x' = x (1 + w (T - 1))       (T: a factor; w = 1 gives x T)
 *  - ADD:      x' = x + w T                 (T: a change, 1/mm, may be < 0)
 * then x' is clamped to >= 0. If a channel of a tet would end with
 * mu_a + sigma_s' = 0, that channel keeps its old values and the filter warns
 * with the count. Tets with w = 0 (and masked channels) keep their values bit
 * for bit; so Width = 0 or Strength = 0 change nothing. The refractive index
 * is not painted.
 *
 * The input is a tet mesh with the cell arrays `AbsorptionCoefficient` and
 * `ReducedScatteringCoefficient` (3 components each; vtkAssignScatteringCoefficients).
 * The output is a shallow copy of the input with new (double) arrays of those
 * names and a cell array `PaintWeight` (w_t, 1 component).
 *
 * @warning Painting applies to the tets present in the input. On a cut mesh
 * (which carries `vtkOriginalCellIds`), mapping the new values back to the
 * tets of the original mesh is the caller's job (scatter by those ids).
 * The nearest stroke point is found by brute force (cost: tets x stroke
 * points), fine for strokes of up to a few hundred points.
 * No stroke point, a negative or non-finite Width, or a missing / wrongly
 * sized coefficient array is an error naming the problem.
 *
 * @sa vtkAssignScatteringCoefficients vtkSolveDiffusion
 */
#ifndef vtkPaintScatteringCoefficients_h
#define vtkPaintScatteringCoefficients_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkUnstructuredGridAlgorithm.h"

#include <vector> // for the stroke points

class TRANSLUCENCYFILTERS_EXPORT vtkPaintScatteringCoefficients
  : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkPaintScatteringCoefficients* New();
  vtkTypeMacro(vtkPaintScatteringCoefficients, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// Stroke points (mm). Default none (an error at execution).
  void AddStrokePoint(double x, double y, double z);
  void RemoveAllStrokePoints();
  int GetNumberOfStrokePoints() const { return static_cast<int>(this->StrokePoints.size() / 3); }
  ///@}

  ///@{
  /// Width sigma of the Gaussian, mm (>= 0; 0 paints nothing). Default 1.
  vtkSetMacro(Width, double);
  vtkGetMacro(Width, double);
  ///@}

  ///@{
  /// Strength in [0, 1] (0 paints nothing). Default 1.
  vtkSetClampMacro(Strength, double, 0.0, 1.0);
  vtkGetMacro(Strength, double);
  ///@}

  /// How the target combines with the old value (see the class documentation).
  enum Modes
  {
    SET = 0,
    MULTIPLY = 1,
    ADD = 2
  };

  ///@{
  /// One of Modes. Default SET.
  vtkSetClampMacro(Mode, int, SET, ADD);
  vtkGetMacro(Mode, int);
  void SetModeToSet() { this->SetMode(SET); }
  void SetModeToMultiply() { this->SetMode(MULTIPLY); }
  void SetModeToAdd() { this->SetMode(ADD); }
  ///@}

  ///@{
  /**
   * Target of mu_a (R, G, B): a value (1/mm, SET), a factor (MULTIPLY) or a
   * change (1/mm, ADD). Default ketchup's mu_a (0.061, 0.97, 1.45) 1/mm.
   */
  vtkSetVector3Macro(TargetAbsorptionCoefficient, double);
  vtkGetVector3Macro(TargetAbsorptionCoefficient, double);
  ///@}

  ///@{
  /// Target of sigma_s' (R, G, B), as above. Default ketchup's (0.18, 0.07, 0.03) 1/mm.
  vtkSetVector3Macro(TargetReducedScatteringCoefficient, double);
  vtkGetVector3Macro(TargetReducedScatteringCoefficient, double);
  ///@}

  ///@{
  /// Channels painted (R, G, B; non-zero = painted). Default (1, 1, 1).
  vtkSetVector3Macro(ChannelMask, int);
  vtkGetVector3Macro(ChannelMask, int);
  ///@}

protected:
  vtkPaintScatteringCoefficients() = default;
  ~vtkPaintScatteringCoefficients() override = default;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  std::vector<double> StrokePoints;
  double Width = 1.0;
  double Strength = 1.0;
  int Mode = SET;
  double TargetAbsorptionCoefficient[3] = { 0.061, 0.97, 1.45 };
  double TargetReducedScatteringCoefficient[3] = { 0.18, 0.07, 0.03 };
  int ChannelMask[3] = { 1, 1, 1 };

private:
  vtkPaintScatteringCoefficients(const vtkPaintScatteringCoefficients&) = delete;
  void operator=(const vtkPaintScatteringCoefficients&) = delete;
};

#endif
