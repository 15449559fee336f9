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

class vtkAlgorithmOutput;
class vtkImplicitFunction;
class vtkPolyData;
class vtkUnstructuredGrid;

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

  /**
   * The path of the last execution: "serial" (one process), "per piece" (MPI:
   * an implicit cutter with the relaxation off, NumberOfRelaxationIterations 0
   * or RelaxationFactor 0, cut on each rank's own piece, no gather; the
   * statistics above are then this rank's) or "gathered" (MPI: a stroke, the
   * relaxation on, or TRANSLUCENCY_GATHERED_CUT=1 on some rank: the pieces
   * are cut on rank 0, the output is there). Documentation/Parallel.md.
   */
  const char* GetParallelPath() const { return this->ParallelPath.c_str(); }

  /// Modification time including the cut function's.
  vtkMTimeType GetMTime() override;

protected:
  vtkStrokeCut();
  ~vtkStrokeCut() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  /// The MPI per-piece path (collective: every rank calls it).
  int RequestPerPiece(vtkInformationVector** inputVector, vtkInformationVector* outputVector);
  /// Cut `input` (a stroke, or CutFunction when `stroke` is null) into
  /// `output`: 1 done, 0 failed (`error` says why), 2 aborted. Not collective.
  int CutPiece(vtkUnstructuredGrid* input, vtkPolyData* stroke, vtkUnstructuredGrid* output,
    std::string& error);
  /// True if TRANSLUCENCY_GATHERED_CUT is "1" in this process.
  static bool UseGatheredPath();

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
  std::string ParallelPath = "serial";
  bool Gathering = false; // true while the gathered serial run executes

private:
  vtkStrokeCut(const vtkStrokeCut&) = delete;
  void operator=(const vtkStrokeCut&) = delete;
};

#endif
