#include "vtkStrokeCut.h"

#include "Error.h"
#include "StrokeSurface.h"
#include "TetCut.h"
#include "TetMesh.h"
#include "Timer.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"
#include "vtkTranslucencyDistributedCut.h"
#include "vtkTranslucencyDispatch.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkImplicitFunction.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkStrokeCut);
vtkCxxSetObjectMacro(vtkStrokeCut, CutFunction, vtkImplicitFunction);

using vtkTranslucency::CopyAttributes;
using vtkTranslucency::OriginalPointIdsName;

//------------------------------------------------------------------------------
vtkStrokeCut::vtkStrokeCut()
{
  this->SetNumberOfInputPorts(2);
}

//------------------------------------------------------------------------------
void vtkStrokeCut::SetStrokeConnection(vtkAlgorithmOutput* output)
{
  this->SetInputConnection(1, output);
}

void vtkStrokeCut::SetStrokeData(vtkPolyData* stroke)
{
  this->SetInputData(1, stroke);
}

//------------------------------------------------------------------------------
int vtkStrokeCut::FillInputPortInformation(int port, vtkInformation* info)
{
  if (port == 1)
  {
    info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
    return 1;
  }
  return this->Superclass::FillInputPortInformation(port, info);
}

vtkStrokeCut::~vtkStrokeCut()
{
  this->SetCutFunction(nullptr);
}

//------------------------------------------------------------------------------
vtkMTimeType vtkStrokeCut::GetMTime()
{
  vtkMTimeType mTime = this->Superclass::GetMTime();
  if (this->CutFunction)
  {
    mTime = std::max(mTime, this->CutFunction->GetMTime());
  }
  return mTime;
}

//------------------------------------------------------------------------------
struct vtkStrokeCut::PieceCut
{
  std::shared_ptr<const translucency::TetMesh> Mesh;
  translucency::StrokeSurface Surface;
  translucency::TetCut::SideFunction Side; ///< F > 0 on the removed side
  std::vector<double> Values;              ///< F at the mesh points
  translucency::TetCut Cut;
  std::vector<double> Positions; ///< the kept points' coordinates (3 each, mm)
};

//------------------------------------------------------------------------------
std::vector<double> vtkStrokeCut::StrokePoints(vtkPolyData* stroke)
{
  // The first line of the stroke, or its points in order.
  std::vector<double> strokePoints;
  if (!stroke)
  {
    return strokePoints;
  }
  vtkCellArray* lines = stroke->GetLines();
  vtkIdType count = 0;
  const vtkIdType* ids = nullptr;
  if (lines && lines->GetNumberOfCells() > 0)
  {
    lines->GetCellAtId(0, count, ids);
  }
  else
  {
    count = stroke->GetNumberOfPoints();
  }
  for (vtkIdType k = 0; k < count; ++k)
  {
    double p[3];
    stroke->GetPoint(ids ? ids[k] : k, p);
    strokePoints.insert(strokePoints.end(), p, p + 3);
  }
  return strokePoints;
}

//------------------------------------------------------------------------------
int vtkStrokeCut::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  this->NumberOfFrontTets = this->NumberOfFrontPoints = this->FrontBytes = 0;
  return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector,
    [this](vtkInformationVector** i, vtkInformationVector* o, const vtkTranslucencyCommunicator& c)
    {
      return this->RequestPerPiece(
        i, o, this->HasSharedStroke ? &this->SharedStroke : nullptr, c);
    });
}

//------------------------------------------------------------------------------
int vtkStrokeCut::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::UpdateExtent(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkStrokeCut::PlanParallel(
  vtkInformationVector** inputVector, const vtkTranslucencyCommunicator& comm)
{
  using Plan = vtkTranslucencyParallelPlan;
  vtkPolyData* stroke = inputVector[1]->GetNumberOfInformationObjects() > 0
    ? vtkPolyData::GetData(inputVector[1], 0)
    : nullptr;
  // The same stroke on every rank (a source gives it to rank 0 or to all).
  this->HasSharedStroke = comm.Any(stroke != nullptr);
  this->SharedStroke.clear();
  if (this->HasSharedStroke &&
    !vtkTranslucencyDistributedCut::ShareStroke(StrokePoints(stroke), this->SharedStroke))
  {
    return Plan::Gathered(Plan::GatherMode::RankZero,
      "the stroke is split over the ranks: the pieces are cut on rank 0");
  }
  const bool relaxes = this->NumberOfRelaxationIterations > 0 && this->RelaxationFactor > 0.0;
  Plan plan = Plan::PerPiece(Plan::GatherMode::RankZero, relaxes
      ? "a tet is kept or removed by its own vertices; the relaxation runs on the all-gathered "
        "cut front"
      : "a tet is kept or removed by its own vertices");
  plan.DeprecatedVariable = "TRANSLUCENCY_GATHERED_CUT";
  return plan;
}

//------------------------------------------------------------------------------
int vtkStrokeCut::RequestSerial(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkPolyData* stroke = inputVector[1]->GetNumberOfInformationObjects() > 0
    ? vtkPolyData::GetData(inputVector[1], 0)
    : nullptr;
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  std::string error;
  const std::vector<double> strokePoints = StrokePoints(stroke);
  const int status = this->CutPiece(input, stroke ? &strokePoints : nullptr, output, error);
  if (status != 1)
  {
    if (status == 0)
    {
      vtkErrorMacro(<< error);
    }
    return status == 0 ? 0 : 1; // 2: aborted
  }
  if (output->GetNumberOfCells() == 0)
  {
    vtkWarningMacro(<< "the cut removed the whole mesh: the output is empty");
  }
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
int vtkStrokeCut::RequestPerPiece(vtkInformationVector** inputVector,
  vtkInformationVector* outputVector, const std::vector<double>* strokePoints,
  const vtkTranslucencyCommunicator& comm)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  this->NumberOfMovableVertices = this->NumberOfMovedVertices = 0;
  this->NumberOfBlockedVertices = 0;
  this->CutTime = 0.0;
  const translucency::Timer timer;
  const long long cells = input ? input->GetNumberOfCells() : 0;
  // Every rank takes part in every collective below, an empty piece too.
  if (comm.Sum(cells) == 0)
  {
    vtkErrorMacro(<< "input is not a tet mesh: the input mesh is empty (no points or no cells)");
    return 0;
  }
  const bool relaxes = this->NumberOfRelaxationIterations > 0 && this->RelaxationFactor > 0.0;
  std::string local;
  int status = 1;
  if (!relaxes)
  {
    // Nothing moves: each piece is cut on its own.
    if (cells > 0)
    {
      status = this->CutPiece(input, strokePoints, output, local);
    }
  }
  else
  {
    PieceCut piece;
    // Every rank sets F up (the relaxation evaluates it), cuts its piece
    // without relaxing, then all relax the gathered front together.
    status = this->MakeSide(strokePoints, piece, local);
    if (status == 1 && cells > 0)
    {
      status = this->PrepareCut(input, piece, 0, local);
    }
    const std::string error =
      comm.AgreeOnError(status == 0 ? local : std::string());
    if (!error.empty())
    {
      vtkErrorMacro(<< error);
      return 0;
    }
    if (comm.Any(status == 2))
    {
      return 1; // aborted on some rank: empty outputs on every rank
    }
    translucency::TetCut relax;
    relax.SetRelaxationFactor(this->RelaxationFactor);
    relax.SetNumberOfIterations(this->NumberOfRelaxationIterations);
    relax.SetMinimumDihedralAngle(this->MinimumDihedralAngle);
    vtkTranslucencyDistributedCut::FrontStatistics front;
    std::string relaxError;
    if (!vtkTranslucencyDistributedCut::RelaxFront(input, cells > 0 ? piece.Mesh.get() : nullptr,
          piece.Values, piece.Cut, relax, piece.Side, piece.Positions, front, relaxError))
    {
      vtkErrorMacro(<< relaxError);
      return 0;
    }
    this->NumberOfMovableVertices = relax.GetNumberOfMovableVertices();
    this->NumberOfMovedVertices = relax.GetNumberOfMovedVertices();
    this->NumberOfBlockedVertices = relax.GetNumberOfBlockedVertices();
    this->NumberOfFrontTets = static_cast<vtkIdType>(front.Tets);
    this->NumberOfFrontPoints = static_cast<vtkIdType>(front.Points);
    this->FrontBytes = static_cast<vtkIdType>(front.Bytes);
    if (cells > 0)
    {
      this->WriteCut(input, piece, output);
    }
    this->CutTime = timer.GetMilliseconds();
  }
  const std::string error =
    comm.AgreeOnError(status == 0 ? local : std::string());
  if (!error.empty())
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const long long kept = comm.Sum(
    status == 1 ? output->GetNumberOfCells() : 1);
  if (kept == 0 && comm.GetRank() == 0)
  {
    vtkWarningMacro(<< "the cut removed the whole mesh: the output is empty");
  }
  return status == 1 ? outputs.Succeed() : 1; // 2: aborted on this rank
}

//------------------------------------------------------------------------------
int vtkStrokeCut::MakeSide(
  const std::vector<double>* strokePoints, PieceCut& piece, std::string& error)
{
  if (!strokePoints && !this->CutFunction)
  {
    error = "no cut function: SetCutFunction or a stroke is required";
    return 0;
  }
  // F > 0 on the removed side.
  const double sign = this->InsideOut ? -1.0 : 1.0;
  if (strokePoints)
  {
    try
    {
      piece.Surface.SetStroke(*strokePoints, this->ViewDirection);
    }
    catch (const translucency::Error& e)
    {
      error = std::string("bad stroke: ") + e.what();
      return 0;
    }
    const translucency::StrokeSurface* surface = &piece.Surface;
    piece.Side = [surface, sign](const double* x) { return sign * surface->Evaluate(x); };
  }
  else
  {
    vtkImplicitFunction* function = this->CutFunction;
    piece.Side = [function, sign](const double* x) {
      double p[3] = { x[0], x[1], x[2] };
      return sign * function->FunctionValue(p);
    };
  }
  return 1;
}

//------------------------------------------------------------------------------
int vtkStrokeCut::PrepareCut(
  vtkUnstructuredGrid* input, PieceCut& piece, int iterations, std::string& error)
{
  piece.Mesh = vtkTranslucency::AcquireTetMesh(input, error);
  if (!piece.Mesh)
  {
    error = "input is not a tet mesh: " + error;
    return 0;
  }
  this->UpdateProgress(0.1);
  const std::vector<double>& points = piece.Mesh->GetPoints();
  piece.Values.resize(static_cast<size_t>(piece.Mesh->GetNumberOfPoints()));
  for (int i = 0; i < piece.Mesh->GetNumberOfPoints(); ++i)
  {
    piece.Values[i] = piece.Side(&points[3 * static_cast<std::size_t>(i)]);
  }
  if (this->CheckAbort())
  {
    return 2;
  }
  this->UpdateProgress(0.2);
  piece.Cut.SetRelaxationFactor(this->RelaxationFactor);
  piece.Cut.SetNumberOfIterations(iterations);
  piece.Cut.SetMinimumDihedralAngle(this->MinimumDihedralAngle);
  try
  {
    piece.Cut.Cut(points, piece.Mesh->GetTets(), piece.Values, piece.Side);
  }
  catch (const translucency::Error& e)
  {
    error = e.what();
    return 0;
  }
  piece.Positions = piece.Cut.GetPoints();
  this->UpdateProgress(0.8);
  return 1;
}

//------------------------------------------------------------------------------
void vtkStrokeCut::WriteCut(
  vtkUnstructuredGrid* input, const PieceCut& piece, vtkUnstructuredGrid* output)
{
  // Geometry.
  const std::vector<double>& outPoints = piece.Positions;
  const vtkIdType numPoints = static_cast<vtkIdType>(piece.Cut.GetKeptPoints().size());
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  pts->SetNumberOfPoints(numPoints);
  for (vtkIdType k = 0; k < numPoints; ++k)
  {
    pts->SetPoint(k, &outPoints[3 * k]);
  }
  output->SetPoints(pts);
  vtkTranslucency::SetTets(output, piece.Cut.GetTets());

  // Attributes, with the id maps to the original mesh. The kept points and
  // tets are a subset: their GlobalIds stay valid (VTK does not copy them by
  // default), so a distributed solve downstream matches the pieces by id.
  output->GetPointData()->CopyGlobalIdsOn();
  output->GetCellData()->CopyGlobalIdsOn();
  CopyAttributes(input->GetPointData(), output->GetPointData(), piece.Cut.GetKeptPoints(),
    OriginalPointIdsName);
  CopyAttributes(input->GetCellData(), output->GetCellData(), piece.Cut.GetKeptTets(),
    vtkTranslucency::OriginalCellIdsName);
  output->GetFieldData()->PassData(input->GetFieldData());
  this->UpdateProgress(1.0);
}

//------------------------------------------------------------------------------
int vtkStrokeCut::CutPiece(vtkUnstructuredGrid* input, const std::vector<double>* strokePoints,
  vtkUnstructuredGrid* output, std::string& error)
{
  this->NumberOfMovableVertices = this->NumberOfMovedVertices = 0;
  this->NumberOfBlockedVertices = 0;
  this->CutTime = 0.0;
  const translucency::Timer timer;
  PieceCut piece;
  int status = this->MakeSide(strokePoints, piece, error);
  if (status == 1)
  {
    status = this->PrepareCut(input, piece, this->NumberOfRelaxationIterations, error);
  }
  if (status != 1)
  {
    return status;
  }
  this->NumberOfMovableVertices = piece.Cut.GetNumberOfMovableVertices();
  this->NumberOfMovedVertices = piece.Cut.GetNumberOfMovedVertices();
  this->NumberOfBlockedVertices = piece.Cut.GetNumberOfBlockedVertices();
  this->WriteCut(input, piece, output);
  this->CutTime = timer.GetMilliseconds();
  return 1;
}

//------------------------------------------------------------------------------
void vtkStrokeCut::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "CutFunction: " << this->CutFunction << "\n";
  os << indent << "InsideOut: " << this->InsideOut << "\n";
  os << indent << "ViewDirection: (" << this->ViewDirection[0] << ", " << this->ViewDirection[1]
     << ", " << this->ViewDirection[2] << ")\n";
  os << indent << "RelaxationFactor: " << this->RelaxationFactor << "\n";
  os << indent << "NumberOfRelaxationIterations: " << this->NumberOfRelaxationIterations << "\n";
  os << indent << "MinimumDihedralAngle: " << this->MinimumDihedralAngle << "\n";
  os << indent << "NumberOfBlockedVertices: " << this->NumberOfBlockedVertices << "\n";
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}
