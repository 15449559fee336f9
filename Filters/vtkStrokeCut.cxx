#include "vtkStrokeCut.h"

#include "Error.h"
#include "StrokeSurface.h"
#include "TetCut.h"
#include "TetMesh.h"
#include "Timer.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"
#include "vtkTranslucencyDistributedPieces.h"
#include "vtkTranslucencyParallel.h"

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
bool vtkStrokeCut::UseGatheredPath()
{
  const char* value = std::getenv("TRANSLUCENCY_GATHERED_CUT");
  return value && std::string(value) == "1";
}

//------------------------------------------------------------------------------
int vtkStrokeCut::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkPolyData* stroke = inputVector[1]->GetNumberOfInformationObjects() > 0
    ? vtkPolyData::GetData(inputVector[1], 0)
    : nullptr;
  // Under MPI: an implicit cutter without relaxation on each rank's own piece
  // (a tet is kept or removed by its own vertices; nothing moves); otherwise
  // gather to rank 0, run this serially there, hand the result back.
  if (!this->Gathering && vtkTranslucencyDistributedPieces::IsAvailable())
  {
    const bool relaxes = this->NumberOfRelaxationIterations > 0 && this->RelaxationFactor > 0.0;
    // Every rank decides alike (a stroke or the variable on any rank gathers).
    const bool gather = vtkTranslucencyDistributedPieces::Any(
      stroke != nullptr || !this->CutFunction || relaxes || UseGatheredPath());
    if (!gather)
    {
      this->ParallelPath = "per piece";
      return this->RequestPerPiece(inputVector, outputVector);
    }
  }
  this->ParallelPath = "serial";
  int parallelResult = 0;
  this->Gathering = true; // the serial run on rank 0 must not go per piece
  const bool gathered = vtkTranslucencyParallel::RunGathered(this, request, inputVector,
    outputVector, vtkTranslucencyParallel::GatherMode::RankZero,
    [this](vtkInformation* r, vtkInformationVector** i, vtkInformationVector* o)
    { return this->RequestData(r, i, o); },
    parallelResult);
  this->Gathering = false;
  if (gathered)
  {
    this->ParallelPath = "gathered";
    return parallelResult;
  }
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  std::string error;
  const int status = this->CutPiece(input, stroke, output, error);
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
int vtkStrokeCut::RequestPerPiece(
  vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  this->NumberOfMovableVertices = this->NumberOfMovedVertices = 0;
  this->NumberOfBlockedVertices = 0;
  this->CutTime = 0.0;
  const long long cells = input ? input->GetNumberOfCells() : 0;
  // Every rank takes part in every collective below, an empty piece too.
  if (vtkTranslucencyDistributedPieces::Sum(cells) == 0)
  {
    vtkErrorMacro(<< "input is not a tet mesh: the input mesh is empty (no points or no cells)");
    return 0;
  }
  std::string local;
  int status = 1;
  if (cells > 0)
  {
    status = this->CutPiece(input, nullptr, output, local);
  }
  const std::string error =
    vtkTranslucencyDistributedPieces::AgreeOnError(status == 0 ? local : std::string());
  if (!error.empty())
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const long long kept = vtkTranslucencyDistributedPieces::Sum(
    status == 1 ? output->GetNumberOfCells() : 1);
  if (kept == 0 && vtkTranslucencyDistributedPieces::GetRank() == 0)
  {
    vtkWarningMacro(<< "the cut removed the whole mesh: the output is empty");
  }
  return status == 1 ? outputs.Succeed() : 1; // 2: aborted on this rank
}

//------------------------------------------------------------------------------
int vtkStrokeCut::CutPiece(vtkUnstructuredGrid* input, vtkPolyData* stroke,
  vtkUnstructuredGrid* output, std::string& error)
{
  this->NumberOfMovableVertices = this->NumberOfMovedVertices = 0;
  this->NumberOfBlockedVertices = 0;
  this->CutTime = 0.0;
  const translucency::Timer timer;

  if (!stroke && !this->CutFunction)
  {
    error = "no cut function: SetCutFunction or a stroke is required";
    return 0;
  }
  auto mesh = vtkTranslucency::AcquireTetMesh(input, error);
  if (!mesh)
  {
    error = "input is not a tet mesh: " + error;
    return 0;
  }
  this->UpdateProgress(0.1);

  // F > 0 on the removed side.
  const double sign = this->InsideOut ? -1.0 : 1.0;
  translucency::StrokeSurface surface;
  translucency::TetCut::SideFunction side;
  if (stroke)
  {
    // The first line of the stroke, or its points in order.
    std::vector<double> strokePoints;
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
    try
    {
      surface.SetStroke(strokePoints, this->ViewDirection);
    }
    catch (const translucency::Error& e)
    {
      error = std::string("bad stroke: ") + e.what();
      return 0;
    }
    side = [&surface, sign](const double* x) { return sign * surface.Evaluate(x); };
  }
  else
  {
    vtkImplicitFunction* function = this->CutFunction;
    side = [function, sign](const double* x) {
      double p[3] = { x[0], x[1], x[2] };
      return sign * function->FunctionValue(p);
    };
  }
  const std::vector<double>& points = mesh->GetPoints();
  std::vector<double> values(mesh->GetNumberOfPoints());
  for (int i = 0; i < mesh->GetNumberOfPoints(); ++i)
  {
    values[i] = side(&points[3 * static_cast<std::size_t>(i)]);
  }
  if (this->CheckAbort())
  {
    return 2;
  }
  this->UpdateProgress(0.2);

  translucency::TetCut cut;
  cut.SetRelaxationFactor(this->RelaxationFactor);
  cut.SetNumberOfIterations(this->NumberOfRelaxationIterations);
  cut.SetMinimumDihedralAngle(this->MinimumDihedralAngle);
  try
  {
    cut.Cut(points, mesh->GetTets(), values, side);
  }
  catch (const translucency::Error& e)
  {
    error = e.what();
    return 0;
  }
  this->NumberOfMovableVertices = cut.GetNumberOfMovableVertices();
  this->NumberOfMovedVertices = cut.GetNumberOfMovedVertices();
  this->NumberOfBlockedVertices = cut.GetNumberOfBlockedVertices();
  this->UpdateProgress(0.8);

  // Geometry.
  const std::vector<double>& outPoints = cut.GetPoints();
  const vtkIdType numPoints = static_cast<vtkIdType>(cut.GetKeptPoints().size());
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  pts->SetNumberOfPoints(numPoints);
  for (vtkIdType k = 0; k < numPoints; ++k)
  {
    pts->SetPoint(k, &outPoints[3 * k]);
  }
  output->SetPoints(pts);
  vtkTranslucency::SetTets(output, cut.GetTets());

  // Attributes, with the id maps to the original mesh. The kept points and
  // tets are a subset: their GlobalIds stay valid (VTK does not copy them by
  // default), so a distributed solve downstream matches the pieces by id.
  output->GetPointData()->CopyGlobalIdsOn();
  output->GetCellData()->CopyGlobalIdsOn();
  CopyAttributes(input->GetPointData(), output->GetPointData(), cut.GetKeptPoints(),
    OriginalPointIdsName);
  CopyAttributes(input->GetCellData(), output->GetCellData(), cut.GetKeptTets(),
    vtkTranslucency::OriginalCellIdsName);
  output->GetFieldData()->PassData(input->GetFieldData());

  this->CutTime = timer.GetMilliseconds();
  this->UpdateProgress(1.0);
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
}
