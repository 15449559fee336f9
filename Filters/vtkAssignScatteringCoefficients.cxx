#include "vtkAssignScatteringCoefficients.h"

#include "Error.h"
#include "OpticalProperties.h"
#include "vtkTranslucencyMeshConversion.h"

#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkUnstructuredGrid.h>

#include <cmath>
#include <sstream>

vtkStandardNewMacro(vtkAssignScatteringCoefficients);

//------------------------------------------------------------------------------
vtkAssignScatteringCoefficients::vtkAssignScatteringCoefficients() = default;

//------------------------------------------------------------------------------
int vtkAssignScatteringCoefficients::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  if (!input || input->GetNumberOfCells() == 0)
  {
    vtkErrorMacro(<< "the input mesh is empty (no cells)");
    return 0;
  }
  double muA[3], sigmaS[3], eta;
  if (!this->MaterialName.empty())
  {
    try
    {
      const translucency::MaterialPreset& preset =
        translucency::FindMaterialPreset(this->MaterialName);
      for (int c = 0; c < 3; ++c)
      {
        muA[c] = preset.Absorption[c];
        sigmaS[c] = preset.ReducedScattering[c];
      }
      eta = preset.RefractiveIndex;
    }
    catch (const translucency::Error& e)
    {
      vtkErrorMacro(<< e.what());
      return 0;
    }
  }
  else
  {
    for (int c = 0; c < 3; ++c)
    {
      muA[c] = this->AbsorptionCoefficient[c];
      sigmaS[c] = this->ReducedScatteringCoefficient[c];
    }
    eta = this->RefractiveIndex;
  }
  for (int c = 0; c < 3; ++c)
  {
    muA[c] *= this->ScaleFactor;
    sigmaS[c] *= this->ScaleFactor;
  }
  // Validate with the core's rules on a one-tet material (names the value).
  try
  {
    translucency::OpticalProperties::Uniform(1, muA, sigmaS, eta).Validate(1);
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }

  output->ShallowCopy(input);
  const vtkIdType n = input->GetNumberOfCells();
  vtkNew<vtkDoubleArray> absorption;
  absorption->SetName(vtkTranslucency::AbsorptionName);
  absorption->SetNumberOfComponents(3);
  absorption->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> scattering;
  scattering->SetName(vtkTranslucency::ScatteringName);
  scattering->SetNumberOfComponents(3);
  scattering->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> index;
  index->SetName(vtkTranslucency::RefractiveIndexName);
  index->SetNumberOfComponents(1);
  index->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i)
  {
    absorption->SetTypedTuple(i, muA);
    scattering->SetTypedTuple(i, sigmaS);
    index->SetValue(i, eta);
  }
  output->GetCellData()->AddArray(absorption);
  output->GetCellData()->AddArray(scattering);
  output->GetCellData()->AddArray(index);
  if (!output->GetCellData()->GetArray(vtkTranslucency::OriginalCellIdsName))
  {
    vtkNew<vtkIdTypeArray> ids;
    ids->SetName(vtkTranslucency::OriginalCellIdsName);
    ids->SetNumberOfTuples(n);
    for (vtkIdType i = 0; i < n; ++i)
    {
      ids->SetValue(i, i);
    }
    output->GetCellData()->AddArray(ids);
  }
  return 1;
}

//------------------------------------------------------------------------------
void vtkAssignScatteringCoefficients::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "MaterialName: " << this->MaterialName << "\n";
  os << indent << "AbsorptionCoefficient: " << this->AbsorptionCoefficient[0] << ", "
     << this->AbsorptionCoefficient[1] << ", " << this->AbsorptionCoefficient[2] << "\n";
  os << indent << "ReducedScatteringCoefficient: " << this->ReducedScatteringCoefficient[0]
     << ", " << this->ReducedScatteringCoefficient[1] << ", "
     << this->ReducedScatteringCoefficient[2] << "\n";
  os << indent << "RefractiveIndex: " << this->RefractiveIndex << "\n";
  os << indent << "ScaleFactor: " << this->ScaleFactor << "\n";
}
