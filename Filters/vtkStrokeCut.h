/**
 * @class   vtkStrokeCut
 * @brief   Cut away part of a tet mesh and relax the cross-section (TransCut Sec. 5.1).
 *
 * The cutter is either a stroke or any vtkImplicitFunction (plane, box,
 * sphere, cylinder: what ParaView's implicit widgets produce). A point x is
 * on the removed side where F(x) > 0, F the cut function (with InsideOut on,
 * where F(x) < 0: cut away the inside instead of the outside).
 *
 * A stroke is a polyline (vtkPolyData on input port 1: its first line, or
 * its points in order if it has no line; world coordinates, mm) which, swept
 * along ViewDirection, gives a ruled cutting surface; F is the signed
 * distance to it, > 0 on the left of the stroke as seen looking along
 * ViewDirection (see translucency::StrokeSurface). A connected stroke takes
 * precedence over the cut function. The filter
 *  1. deletes every tet whose four vertices are on the removed side,
 *  2. drops the points no remaining tet uses,
 *  3. moves the remaining points of the removed side toward the cross-section,
 *     x <- x + rho (mean of the one-ring - x), for NumberOfRelaxationIterations
 *     sweeps; a move is rejected if it would cross the cutting surface (the
 *     point must stay on the removed side or on the surface), make a tet
 *     around the point non-positive, or give it a minimum dihedral angle
 *     below MinimumDihedralAngle (see translucency::TetCut).
 *
 * All cell and point arrays of the input are carried over. The cell array
 * `vtkOriginalCellIds` and the point array `vtkOriginalPointIds` map the
 * output to the uncut mesh: if the input already has them (a cut of a cut),
 * they are composed, so the ids always point at the original mesh (as the
 * painting interaction needs, Sec. 5.2). Field data are passed.
 *
 * @warning Point arrays computed on the uncut mesh (Irradiance, Fluence) are
 * carried over as they are: re-run vtkSurfaceIrradiance and vtkSolveDiffusion
 * after the cut. A cut that removes everything gives an empty output and a
 * warning.
 *
 * @sa vtkTableBasedClipDataSet vtkSolveDiffusion vtkSurfaceIrradiance
 */
#ifndef vtkStrokeCut_h
#define vtkStrokeCut_h

#include "TranslucencyFiltersModule.h" // for export macro
#include "vtkUnstructuredGridAlgorithm.h"
#include <string> // for std::string
#include <vector> // for std::vector

class vtkAlgorithmOutput;
class vtkImplicitFunction;
class vtkPolyData;
class vtkUnstructuredGrid;

class vtkTranslucencyCommunicator;
struct vtkTranslucencyParallelPlan;

class TRANSLUCENCYFILTERS_EXPORT vtkStrokeCut : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkStrokeCut* New();
  vtkTypeMacro(vtkStrokeCut, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// The cutter; the filter holds a reference. Default none (an error at update).
  virtual void SetCutFunction(vtkImplicitFunction*);
  vtkGetObjectMacro(CutFunction, vtkImplicitFunction);
  ///@}

  ///@{
  /**
   * The stroke (optional input port 1, a vtkPolyData polyline, world
   * coordinates). With a stroke connected, the cut function is ignored.
   */
  void SetStrokeConnection(vtkAlgorithmOutput* output);
  void SetStrokeData(vtkPolyData* stroke);
  ///@}

  ///@{
  /// Direction the stroke is swept along (the camera's view direction, from
  /// the eye into the scene; any length > 0). Default (0, 0, -1).
  vtkSetVector3Macro(ViewDirection, double);
  vtkGetVector3Macro(ViewDirection, double);
  ///@}

  ///@{
  /// Remove where F < 0 instead of F > 0 (cut away the inside). Default off.
  vtkSetMacro(InsideOut, bool);
  vtkGetMacro(InsideOut, bool);
  vtkBooleanMacro(InsideOut, bool);
  ///@}

  ///@{
  /// Relaxation step rho in [0, 1]. Default 0.1 (the paper's value).
  vtkSetClampMacro(RelaxationFactor, double, 0.0, 1.0);
  vtkGetMacro(RelaxationFactor, double);
  ///@}

  ///@{
  /// Relaxation sweeps (0 = no relaxation). Default 10.
  vtkSetClampMacro(NumberOfRelaxationIterations, int, 0, VTK_INT_MAX);
  vtkGetMacro(NumberOfRelaxationIterations, int);
  ///@}

  ///@{
  /// Smallest dihedral angle (degrees) a relaxation move may create. Default 0.5.
  vtkSetClampMacro(MinimumDihedralAngle, double, 0.0, 60.0);
  vtkGetMacro(MinimumDihedralAngle, double);
  ///@}

  ///@{
  /// Statistics of the last cut: points of the removed side that remain
  /// (movable), points moved at least once, points whose move was rejected
  /// in the last sweep (blocked), and the wall time (ms).
  vtkGetMacro(NumberOfMovableVertices, vtkIdType);
  vtkGetMacro(NumberOfMovedVertices, vtkIdType);
  vtkGetMacro(NumberOfBlockedVertices, vtkIdType);
  vtkGetMacro(CutTime, double);
  ///@}

  /// Per piece the statistics above are those of the whole relaxation (the
  /// serial ones) when the relaxation is on, else this rank's.
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
  /// The cut front of the last per-piece relaxation (MPI, relaxation on):
  /// its tets and points (each once) and the bytes every rank received when
  /// it was all-gathered. 0 on the other paths.
  vtkGetMacro(NumberOfFrontTets, vtkIdType);
  vtkGetMacro(NumberOfFrontPoints, vtkIdType);
  vtkGetMacro(FrontBytes, vtkIdType);
  ///@}

  /// Modification time including the cut function's.
  vtkMTimeType GetMTime() override;

protected:
  vtkStrokeCut();
  ~vtkStrokeCut() override;

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
  /// The stroke every rank cuts with (set by PlanParallel; MPI only).
  std::vector<double> SharedStroke;
  bool HasSharedStroke = false;
  /// The MPI per-piece path (collective: every rank calls it). `strokePoints`:
  /// the stroke shared by every rank, or null to use CutFunction.
  int RequestPerPiece(vtkInformationVector** inputVector, vtkInformationVector* outputVector,
    const std::vector<double>* strokePoints,
    const vtkTranslucencyCommunicator& comm);
  /// Cut `input` (with the stroke `strokePoints`, 3 coordinates per point, or
  /// CutFunction when null) into `output`: 1 done, 0 failed (`error` says
  /// why), 2 aborted. Not collective.
  int CutPiece(vtkUnstructuredGrid* input, const std::vector<double>* strokePoints,
    vtkUnstructuredGrid* output, std::string& error);
  /// The points of a stroke: its first line, or its points in order.
  static std::vector<double> StrokePoints(vtkPolyData* stroke);
  struct PieceCut; // the state of one piece's cut (vtkStrokeCut.cxx)
  /// Set up F (piece.Side) from the stroke or CutFunction: 1 done, 0 failed.
  int MakeSide(const std::vector<double>* strokePoints, PieceCut& piece, std::string& error);
  /// Cut `input` with piece.Side, relaxing with `iterations` sweeps: 1 done,
  /// 0 failed, 2 aborted.
  int PrepareCut(vtkUnstructuredGrid* input, PieceCut& piece, int iterations, std::string& error);
  /// The output of a prepared cut (its points at piece.Positions).
  void WriteCut(vtkUnstructuredGrid* input, const PieceCut& piece, vtkUnstructuredGrid* output);

  vtkImplicitFunction* CutFunction = nullptr;
  bool InsideOut = false;
  double ViewDirection[3] = { 0.0, 0.0, -1.0 };
  double RelaxationFactor = 0.1;
  int NumberOfRelaxationIterations = 10;
  double MinimumDihedralAngle = 0.5;
  vtkIdType NumberOfMovableVertices = 0;
  vtkIdType NumberOfMovedVertices = 0;
  vtkIdType NumberOfBlockedVertices = 0;
  double CutTime = 0.0;
  vtkIdType NumberOfFrontTets = 0;
  vtkIdType NumberOfFrontPoints = 0;
  vtkIdType FrontBytes = 0;

private:
  vtkStrokeCut(const vtkStrokeCut&) = delete;
  void operator=(const vtkStrokeCut&) = delete;
};

#endif
