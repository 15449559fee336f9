/**
 * @class vtkTranslucencyOutputGuard
 * @brief Leaves clean, empty outputs when a Translucency algorithm fails.
 *
 * Created at the top of every RequestData of the project's filters and
 * readers. Unless Succeed() is called before RequestData returns, its
 * destructor makes every output a clean empty data set of its own type (as
 * an empty result of ParaView's Threshold): no stale arrays, no field data,
 * and for point sets an empty vtkPoints and empty cell arrays instead of the
 * null ones the pipeline leaves after vtkDataObject::Initialize(). So every
 * failure path (an error, an exception, an abort by the user) leaves the same
 * output, and downstream filters that do not check for null points (ParaView
 * 5.11's Plot Over Line: vtkProbeFilter crashed on a failed Solve Diffusion)
 * see an ordinary empty data set.
 *
 * After Succeed() the outputs are kept; a point set output that was left
 * without points or cells (e.g. an empty piece) gets empty ones.
 *
 * @code
 * int vtkMyFilter::RequestData(vtkInformation*, vtkInformationVector** in,
 *                              vtkInformationVector* out)
 * {
 *   vtkTranslucencyOutputGuard outputs(out); // empty outputs on every failure
 *   if (bad) { vtkErrorMacro(<< "..."); return 0; }
 *   ...
 *   return outputs.Succeed();
 * }
 * @endcode
 *
 * It lives in the Readers module, the lowest of the project's VTK modules,
 * so that the readers and the filters share it. Not wrapped (not a vtkObject).
 */
#ifndef vtkTranslucencyOutputGuard_h
#define vtkTranslucencyOutputGuard_h

#include "TranslucencyReadersModule.h" // for export macro

class vtkDataObject;
class vtkInformationVector;

class TRANSLUCENCYREADERS_EXPORT vtkTranslucencyOutputGuard
{
public:
  /// Guard the output data objects of `outputVector` (RequestData's third
  /// argument; not owned, must outlive the guard).
  explicit vtkTranslucencyOutputGuard(vtkInformationVector* outputVector);
  /// Empties every output unless Succeed() was called.
  ~vtkTranslucencyOutputGuard();
  vtkTranslucencyOutputGuard(const vtkTranslucencyOutputGuard&) = delete;
  vtkTranslucencyOutputGuard& operator=(const vtkTranslucencyOutputGuard&) = delete;

  /// Keep the outputs; returns 1, RequestData's success value.
  int Succeed();

  /// Make `output` a clean empty data set of its type: Initialize() (no
  /// arrays, no field data, no blocks), then for a vtkPointSet an empty
  /// vtkPoints and, for vtkUnstructuredGrid and vtkPolyData, empty cells.
  /// Null is ignored.
  static void MakeEmpty(vtkDataObject* output);

  /// Give a vtkPointSet `output` without points (or an unstructured grid
  /// without cells) empty ones; its arrays and other content are kept.
  static void FillMissingGeometry(vtkDataObject* output);

private:
  vtkInformationVector* Outputs;
  bool Succeeded = false;
};

#endif
