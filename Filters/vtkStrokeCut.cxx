#include "vtkStrokeCut.h"

#include "Error.h"
#include "StrokeSurface.h"
#include "TetCut.h"
#include "TetMesh.h"
#include "Timer.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"
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
int vtkStrokeCut::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // Under MPI: gather to rank 0, run this serially there, hand the result back.
  int parallelResult = 0;
  if (vtkTranslucencyParallel::RunGathered(this, request, inputVector, outputVector,
        vtkTranslucencyParallel::GatherMode::RankZero,
        [this](vtkInformation* r, vtkInformationVector** i, vtkInformationVector* o)
        { return this->RequestData(r, i, o); },
        parallelResult))
  {
    return parallelResult;
  }
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  this->NumberOfMovableVertices = this->NumberOfMovedVertices = 0;
  this->NumberOfBlockedVertices = 0;
  this->CutTime = 0.0;
  const translucency::Timer timer;

  vtkPolyData* stroke = inputVector[1]->GetNumberOfInformationObjects() > 0
    ? vtkPolyData::GetData(inputVector[1], 0)
    : nullptr;
  if (!stroke && !this->CutFunction)
  {
    vtkErrorMacro(<< "no cut function: SetCutFunction or a stroke is required");
    return 0;
  }
  std::string error;
  auto mesh = vtkTranslucency::AcquireTetMesh(input, error);
  if (!mesh)
  {
    vtkErrorMacro(<< "input is not a tet mesh: " << error);
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
      vtkErrorMacro(<< "bad stroke: " << e.what());
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
    return 1;
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
    vtkErrorMacro(<< e.what());
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
  const vtkIdType numTets = static_cast<vtkIdType>(cut.GetTets().size() / 4);
  output->SetPoints(pts);
  vtkTranslucency::SetTets(output, cut.GetTets());

  // Attributes, with the id maps to the original mesh.
  CopyAttributes(input->GetPointData(), output->GetPointData(), cut.GetKeptPoints(),
    OriginalPointIdsName);
  CopyAttributes(input->GetCellData(), output->GetCellData(), cut.GetKeptTets(),
    vtkTranslucency::OriginalCellIdsName);
  output->GetFieldData()->PassData(input->GetFieldData());

  this->CutTime = timer.GetMilliseconds();
  if (numTets == 0)
  {
    vtkWarningMacro(<< "the cut removed the whole mesh: the output is empty");
  }
  this->UpdateProgress(1.0);
  return outputs.Succeed();
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
