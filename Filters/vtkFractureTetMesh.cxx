#include "vtkFractureTetMesh.h"

#include "vtkTranslucencyDispatch.h"
#include "Error.h"
#include "TetFracture.h"
#include "TetMesh.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>

#include <cstdint>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkFractureTetMesh);

namespace
{
using vtkTranslucency::CopyAttributes;
using vtkTranslucency::OriginalPointIdsName;


vtkNew<vtkIntArray> IntField(const char* name, int value)
{
  vtkNew<vtkIntArray> array;
  array->SetName(name);
  array->SetNumberOfTuples(1);
  array->SetValue(0, value);
  return array;
}
}

//------------------------------------------------------------------------------
vtkFractureTetMesh::vtkFractureTetMesh() = default;

//------------------------------------------------------------------------------
void vtkFractureTetMesh::AddSeedPoint(double x, double y, double z)
{
  this->SeedPoints.insert(this->SeedPoints.end(), { x, y, z });
  this->Modified();
}

void vtkFractureTetMesh::RemoveAllSeedPoints()
{
  if (!this->SeedPoints.empty())
  {
    this->SeedPoints.clear();
    this->Modified();
  }
}

void vtkFractureTetMesh::SetRandomSeeds(int count, int seed)
{
  count = count < 0 ? 0 : count;
  if (count != this->NumberOfRandomSeeds || seed != this->RandomSeed)
  {
    this->NumberOfRandomSeeds = count;
    this->RandomSeed = seed;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
int vtkFractureTetMesh::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
  return 1;
}

//------------------------------------------------------------------------------
int vtkFractureTetMesh::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
int vtkFractureTetMesh::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::UpdateExtent(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkFractureTetMesh::PlanParallel(
  vtkInformationVector**, const vtkTranslucencyCommunicator&)
{
  return vtkTranslucencyParallelPlan::Gathered(
    vtkTranslucencyParallelPlan::GatherMode::RankZero, "new topology: the pieces (a multiblock) are built from the whole mesh");
}

//------------------------------------------------------------------------------
int vtkFractureTetMesh::RequestSerial(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkMultiBlockDataSet* output = vtkMultiBlockDataSet::GetData(outputVector);
  this->NumberOfPieces = 0;
  if (this->SeedPoints.empty() && this->NumberOfRandomSeeds == 0)
  {
    vtkErrorMacro(<< "no seed points: AddSeedPoint or SetRandomSeeds(n > 0, seed) is required");
    return 0;
  }
  if (!input || input->GetNumberOfCells() == 0)
  {
    vtkErrorMacro(<< "empty input: nothing to fracture");
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

  // The core mesh keeps the tets in input order (as vtkStrokeCut relies on).
  const std::vector<double>& points = mesh->GetPoints();
  const std::vector<int>& tets = mesh->GetTets();
  translucency::TetFracture fracture;
  try
  {
    fracture.SetSeeds(this->NumberOfRandomSeeds > 0
        ? translucency::TetFracture::RandomSeeds(
            points, tets, this->NumberOfRandomSeeds, static_cast<std::uint32_t>(this->RandomSeed))
        : this->SeedPoints);
    fracture.Split(points, tets);
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  if (this->CheckAbort())
  {
    return 1;
  }
  this->UpdateProgress(0.3);

  const int numPieces = fracture.GetNumberOfPieces();
  output->SetNumberOfBlocks(numPieces);
  for (int k = 0; k < numPieces; ++k)
  {
    const std::vector<int>& piecePoints = fracture.GetPiecePoints(k);
    const std::vector<int>& connectivity = fracture.GetPieceConnectivity(k);
    const vtkIdType numPoints = static_cast<vtkIdType>(piecePoints.size());

    vtkNew<vtkPoints> pts;
    pts->SetDataType(input->GetPoints()->GetDataType());
    pts->SetNumberOfPoints(numPoints);
    for (vtkIdType j = 0; j < numPoints; ++j)
    {
      pts->SetPoint(j, input->GetPoint(piecePoints[j]));
    }
    vtkNew<vtkUnstructuredGrid> piece;
    piece->SetPoints(pts);
    vtkTranslucency::SetTets(piece, connectivity);
    CopyAttributes(input->GetPointData(), piece->GetPointData(), piecePoints, OriginalPointIdsName);
    CopyAttributes(input->GetCellData(), piece->GetCellData(), fracture.GetPieceTets(k),
      vtkTranslucency::OriginalCellIdsName);
    piece->GetFieldData()->PassData(input->GetFieldData());
    piece->GetFieldData()->AddArray(IntField("FracturePiece", k));
    piece->GetFieldData()->AddArray(IntField("FractureSeed", fracture.GetPieceSeed(k)));

    output->SetBlock(k, piece);
    output->GetMetaData(k)->Set(vtkCompositeDataSet::NAME(), "piece_" + std::to_string(k));
    this->UpdateProgress(0.3 + 0.7 * (k + 1) / numPieces);
    if (this->CheckAbort())
    {
      break;
    }
  }
  this->NumberOfPieces = numPieces;
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
void vtkFractureTetMesh::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfSeedPoints: " << this->GetNumberOfSeedPoints() << "\n";
  os << indent << "NumberOfRandomSeeds: " << this->NumberOfRandomSeeds << "\n";
  os << indent << "RandomSeed: " << this->RandomSeed << "\n";
  os << indent << "NumberOfPieces: " << this->NumberOfPieces << "\n";
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}
