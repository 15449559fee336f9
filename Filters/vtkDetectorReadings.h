/**
 * @class   vtkDetectorReadings
 * @brief   The detectors of a Solve Diffusion output as tables (spreadsheet, line chart).
 *
 * Reads the detector field arrays that vtkSolveDiffusion attaches to its
 * output (Documentation/DiffuseOptics.md) and lays them out as two
 * vtkTable outputs:
 *
 * - **port 0, one row per detector**: `Detector` (0-based id, the order of
 *   AddDetector), `RequestedX/Y/Z` (the position asked for, mm),
 *   `SurfaceX/Y/Z` (the surface point read, mm), `Radius` (fibre radius, mm;
 *   0 = a point), `FluenceR/G/B` and `ExitanceR/G/B` (W/mm^2, the values of
 *   vtkSolveDiffusion::GetDetectorFluence/GetDetectorExitance: amplitudes in
 *   the frequency domain, time integrals in J/mm^2 with time gates) and, when
 *   a modulation frequency was set, `FluencePhaseR/G/B` and
 *   `ExitancePhaseR/G/B` (radians, negative = lagging the source);
 * - **port 1, one row per time gate** (time-resolved solves only; empty
 *   otherwise): `Time (ns)` (the gate centres) and, for every detector k,
 *   `Detector<k>_FluenceR/G/B` and `Detector<k>_ExitanceR/G/B` (the gate
 *   averages, J/(mm^2 ns) per J of pulse): ready for ParaView's Line Chart
 *   View with `Time (ns)` as the X array.
 *
 * Under MPI (pvbatch, pvserver) the field data of Solve Diffusion's output
 * are identical on every rank, so the tables are filled on rank 0 only (the
 * other ranks give empty tables): ParaView's spreadsheet and chart views
 * append the ranks' rows, and would otherwise show every detector N times.
 *
 * An input without detector readings (no `DetectorFluence` field array: no
 * detectors were added, or the solve failed) is an error naming what to do;
 * so are detector arrays of inconsistent sizes. The tables are then empty.
 *
 * @sa vtkSolveDiffusion
 */
#ifndef vtkDetectorReadings_h
#define vtkDetectorReadings_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkTableAlgorithm.h"
#include <string> // for the parallel path

class vtkTranslucencyCommunicator;
struct vtkTranslucencyParallelPlan;

class TRANSLUCENCYFILTERS_EXPORT vtkDetectorReadings : public vtkTableAlgorithm
{
public:
  static vtkDetectorReadings* New();
  vtkTypeMacro(vtkDetectorReadings, vtkTableAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Name of the time column of the time-gate table (port 1): "Time (ns)".
  static const char* GetTimeColumnName() { return "Time (ns)"; }

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
  vtkDetectorReadings();
  ~vtkDetectorReadings() override = default;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
    vtkInformationVector* outputVector) override;
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

private:
  vtkDetectorReadings(const vtkDetectorReadings&) = delete;
  void operator=(const vtkDetectorReadings&) = delete;
};

#endif
