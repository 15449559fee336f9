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
 * vertices) to the nearest stroke point, cut off (w_t = 0) beyond the radius
 * R = Width sqrt(2 ln(Strength / CutoffWeight)) where the weight falls below
 * CutoffWeight (default 1e-6; 0 = the exact Gaussian everywhere; see
 * Documentation/Materials.md), and for each channel c enabled in
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
 * names, a cell array `PaintWeight` (w_t, 1 component) and a field-data
 * array `PaintedCellIds` (vtkIdTypeArray, ascending): the ids of the output
 * cells whose coefficients changed (for incremental updates downstream).
 *
 * Painting a cut mesh (TransCut, Sec. 5.2: the distances are
 * computed for each tet of the ORIGINAL mesh): connect the original uncut mesh
 * to the optional input port 1 ("OriginalMesh", SetOriginalMeshConnection /
 * SetOriginalMeshData) and the cut mesh the stroke was drawn on to port 0.
 * The filter then paints the original mesh: the output is a copy of port 1
 * with the painted arrays, the weights computed from the original tets'
 * centroids, so tets removed by the cut are painted too when they are near
 * the stroke. Port 0 is then only checked: its cell array
 * `vtkOriginalCellIds` (written by vtkStrokeCut, composed over repeated cuts)
 * must refer to tets of port 1 (integer ids in [0, number of tets of port 1));
 * otherwise the filter fails with an error naming the first bad id. A port 0
 * without `vtkOriginalCellIds` is accepted only if it has as many cells as
 * port 1 (the uncut mesh itself); an empty port 0 (a cut that removed
 * everything) is accepted. Re-cutting the painted original then gives a cut
 * mesh whose coefficients are the painted ones. Without port 1 the input
 * (port 0) is painted as it is.
 *
 * The computation is translucency::TetPaint (Solvers/Editing/TetPaint.h): OpenMP,
 * cells outside the stroke's bounding box inflated by R are skipped after a
 * centroid and a box test, the nearest stroke point of the others is looked
 * up in a uniform grid over the stroke points.
 *
 * No stroke point, a negative or non-finite Width, or a missing / wrongly
 * sized coefficient array is an error naming the problem.
 *
 * Under MPI (the global controller runs more than one process) each rank
 * paints its own piece of the painted mesh, no gather: w_t depends only on
 * the tet's centroid, so the arrays equal the serial run's cell by cell, and
 * a ghost cell gets the value of the tet it copies. The checks that need the
 * whole mesh count over every rank's owned cells (ghost copies left out): the
 * empty mesh, and the cut mesh's vtkOriginalCellIds against the number of
 * tets of the original mesh (all ranks' pieces of port 1; the ids number the
 * gathered mesh, as vtkStrokeCut writes them). An error on any rank is
 * reported by every rank with the same text ("rank r: ..."); an empty piece
 * gives an empty output. `PaintedCellIds` then lists the changed cells of the
 * rank's own piece (its cell ids); the warning about kept channels is given
 * by rank 0 with the total over the pieces (ghost copies counted too).
 * Documentation/Parallel.md.
 *
 * **No needless re-execution** (Documentation/Pipeline.md): when the
 * filter executes again with the same painted mesh (the same points, cells
 * and coefficient arrays: the same objects, unmodified) and none of its own
 * properties changed, e.g. because a light upstream was turned, it does not
 * paint again: the output is a shallow copy of the input carrying the
 * arrays of the previous execution, in O(1) (GetLastExecutionReused()).
 *
 * @sa vtkAssignScatteringCoefficients vtkSolveDiffusion
 */
#ifndef vtkPaintScatteringCoefficients_h
#define vtkPaintScatteringCoefficients_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkUnstructuredGridAlgorithm.h"

#include <vtkSmartPointer.h> // for the kept arrays
#include <vtkWeakPointer.h>  // for the inputs of the kept arrays

#include <string> // for the parallel path
#include <vector> // for the stroke points

class vtkTranslucencyCommunicator;
struct vtkTranslucencyParallelPlan;

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
  /**
   * Treat the stroke points as the vertices of a polyline and paint along
   * the line: it is sampled every Width / 4 (translucency::TetPaint::
   * SamplePolyline), so d_t is the distance to the line within Width / 8.
   * Default off (each point paints on its own, the points of a picked
   * stroke); the ParaView panel, whose polyline widget gives a few handles,
   * turns it on.
   */
  vtkSetMacro(StrokeIsPolyline, bool);
  vtkGetMacro(StrokeIsPolyline, bool);
  vtkBooleanMacro(StrokeIsPolyline, bool);
  ///@}

  ///@{
  /**
   * The original uncut mesh (optional input port 1). When set, it is the
   * mesh painted and output; port 0 (the cut mesh) is only validated.
   * Pass nullptr to disconnect.
   */
  void SetOriginalMeshConnection(vtkAlgorithmOutput* output);
  void SetOriginalMeshData(vtkUnstructuredGrid* mesh);
  ///@}

  ///@{
  /// Width sigma of the Gaussian, mm (>= 0; 0 paints nothing). Default 1.
  vtkSetMacro(Width, double);
  vtkGetMacro(Width, double);
  ///@}

  ///@{
  /**
   * Weight below which a tet is not painted, in [0, 1]: tets farther than
   * R = Width sqrt(2 ln(Strength / CutoffWeight)) from the stroke keep their
   * values. 0 = no cut-off (exact Gaussian, every tet examined). Default 1e-6.
   */
  vtkSetClampMacro(CutoffWeight, double, 0.0, 1.0);
  vtkGetMacro(CutoffWeight, double);
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

  ///@{
  /**
   * Whether the last execution re-used the arrays of the one before (same
   * painted mesh and coefficient arrays, same properties: no per-tet work),
   * and how many executions painted (did the per-tet work) since the
   * filter was created.
   */
  bool GetLastExecutionReused() const { return this->LastExecutionReused; }
  vtkIdType GetNumberOfPaintings() const { return this->NumberOfPaintings; }
  ///@}

protected:
  vtkPaintScatteringCoefficients();
  ~vtkPaintScatteringCoefficients() override = default;

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
  /// Paint this rank's piece; the whole-mesh checks count over `comm`
  /// (collective; size one: the serial run).
  int RequestPerPiece(vtkInformationVector** inputVector, vtkInformationVector* outputVector,
    const vtkTranslucencyCommunicator& comm);

  std::vector<double> StrokePoints;
  bool StrokeIsPolyline = false;
  double Width = 1.0;
  double Strength = 1.0;
  double CutoffWeight = 1e-6;
  int Mode = SET;
  double TargetAbsorptionCoefficient[3] = { 0.061, 0.97, 1.45 };
  double TargetReducedScatteringCoefficient[3] = { 0.18, 0.07, 0.03 };
  int ChannelMask[3] = { 1, 1, 1 };
  bool LastExecutionReused = false;
  vtkIdType NumberOfPaintings = 0;

private:
  /// The arrays of the last painting and what they were computed from.
  struct KeptPaint
  {
    vtkWeakPointer<vtkDataArray> Inputs[4]; ///< mu_a, sigma_s', point coordinates, connectivity
    vtkMTimeType InputTimes[4] = { 0, 0, 0, 0 };
    vtkIdType Cells = -1;
    vtkMTimeType FilterTime = 0;
    vtkSmartPointer<vtkDataArray> Outputs[3]; ///< mu_a, sigma_s', PaintWeight
    vtkSmartPointer<vtkDataArray> ChangedIds;
    long long KeptChannels = 0;
  };
  KeptPaint Kept;
  /// Fill Kept's keys from `input` (nullptr entries for missing arrays).
  void KeyOf(vtkUnstructuredGrid* input, vtkDataArray* keys[4], vtkMTimeType times[4]) const;
  /// The output: `input` shallow-copied with the painted arrays.
  static void AttachPaint(vtkUnstructuredGrid* input, vtkUnstructuredGrid* output,
    vtkDataArray* const arrays[3], vtkDataArray* changedIds);

  /// Paint `input` (may be null or empty: an empty output with empty arrays)
  /// into `output`; returns the error ("" on success) and the channels kept.
  std::string Paint(vtkUnstructuredGrid* input, vtkUnstructuredGrid* output,
    long long& keptChannels);

  vtkPaintScatteringCoefficients(const vtkPaintScatteringCoefficients&) = delete;
  void operator=(const vtkPaintScatteringCoefficients&) = delete;
};

#endif
