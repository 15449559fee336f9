#include "vtkTranslucencyOutputGuard.h"

#include "vtkCellArray.h"
#include "vtkDataObject.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

//------------------------------------------------------------------------------
vtkTranslucencyOutputGuard::vtkTranslucencyOutputGuard(vtkInformationVector* outputVector)
  : Outputs(outputVector)
{
}

//------------------------------------------------------------------------------
vtkTranslucencyOutputGuard::~vtkTranslucencyOutputGuard()
{
  if (!this->Outputs)
  {
    return;
  }
  for (int i = 0; i < this->Outputs->GetNumberOfInformationObjects(); ++i)
  {
    vtkInformation* info = this->Outputs->GetInformationObject(i);
    vtkDataObject* output = info ? info->Get(vtkDataObject::DATA_OBJECT()) : nullptr;
    if (this->Succeeded)
    {
      FillMissingGeometry(output);
    }
    else
    {
      MakeEmpty(output);
    }
  }
}

//------------------------------------------------------------------------------
int vtkTranslucencyOutputGuard::Succeed()
{
  this->Succeeded = true;
  return 1;
}

//------------------------------------------------------------------------------
void vtkTranslucencyOutputGuard::MakeEmpty(vtkDataObject* output)
{
  if (!output)
  {
    return;
  }
  output->Initialize();
  FillMissingGeometry(output);
}

//------------------------------------------------------------------------------
void vtkTranslucencyOutputGuard::FillMissingGeometry(vtkDataObject* output)
{
  auto* pointSet = vtkPointSet::SafeDownCast(output);
  if (!pointSet)
  {
    return;
  }
  if (!pointSet->GetPoints())
  {
    vtkNew<vtkPoints> points;
    points->SetDataTypeToDouble();
    pointSet->SetPoints(points);
  }
  if (auto* grid = vtkUnstructuredGrid::SafeDownCast(output))
  {
    if (!grid->GetCells() || !grid->GetCellTypesArray())
    {
      vtkNew<vtkUnsignedCharArray> types;
      vtkNew<vtkCellArray> cells;
      grid->SetCells(types, cells);
    }
  }
  else if (auto* poly = vtkPolyData::SafeDownCast(output))
  {
    if (poly->GetNumberOfCells() == 0)
    {
      vtkNew<vtkCellArray> polys;
      poly->SetPolys(polys);
    }
  }
}
