#include "vtkDetectorReadings.h"

#include "vtkTranslucencyDispatch.h"
#include "vtkTranslucencyOutputGuard.h"

#include <vtkDataArray.h>
#include <vtkDataObject.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkTable.h>

#include <string>

vtkStandardNewMacro(vtkDetectorReadings);

namespace
{
const char* const ChannelSuffix[3] = { "R", "G", "B" };

/// Add one column per component of `array` (3 components: name + R/G/B;
/// 1 component: name), one row per tuple.
void AddColumns(vtkTable* table, const std::string& name, vtkDataArray* array)
{
  const int components = array->GetNumberOfComponents();
  for (int c = 0; c < components; ++c)
  {
    vtkNew<vtkDoubleArray> column;
    column->SetName(components == 1 ? name.c_str() : (name + ChannelSuffix[c]).c_str());
    column->SetNumberOfTuples(array->GetNumberOfTuples());
    for (vtkIdType i = 0; i < array->GetNumberOfTuples(); ++i)
    {
      column->SetValue(i, array->GetComponent(i, c));
    }
    table->AddColumn(column);
  }
}

/// Columns X, Y, Z of a 3-component position array, prefixed by `name`.
void AddPositionColumns(vtkTable* table, const std::string& name, vtkDataArray* array)
{
  static const char* const axis[3] = { "X", "Y", "Z" };
  for (int c = 0; c < 3; ++c)
  {
    vtkNew<vtkDoubleArray> column;
    column->SetName((name + axis[c]).c_str());
    column->SetNumberOfTuples(array->GetNumberOfTuples());
    for (vtkIdType i = 0; i < array->GetNumberOfTuples(); ++i)
    {
      column->SetValue(i, array->GetComponent(i, c));
    }
    table->AddColumn(column);
  }
}
}

//------------------------------------------------------------------------------
vtkDetectorReadings::vtkDetectorReadings()
{
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(2);
}

//------------------------------------------------------------------------------
int vtkDetectorReadings::FillInputPortInformation(int, vtkInformation* info)
{
  // Any data object carrying Solve Diffusion's field arrays.
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkDataObject");
  return 1;
}

//------------------------------------------------------------------------------
int vtkDetectorReadings::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector,
    [this](vtkInformationVector** i, vtkInformationVector* o, const vtkTranslucencyCommunicator& c)
    {
      if (c.GetRank() > 0)
      {
        vtkTranslucencyOutputGuard empty(o); // empty tables on the other ranks
        return empty.Succeed();
      }
      return this->RequestSerial(nullptr, i, o);
    });
}

//------------------------------------------------------------------------------
int vtkDetectorReadings::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::UpdateExtent(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkDetectorReadings::PlanParallel(
  vtkInformationVector**, const vtkTranslucencyCommunicator&)
{
  return vtkTranslucencyParallelPlan::PerPiece(vtkTranslucencyParallelPlan::GatherMode::RankZero,
    "the readings are field data, the same on every rank: the tables come out on rank 0");
}

//------------------------------------------------------------------------------
int vtkDetectorReadings::RequestSerial(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // empty tables on every failure
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0]);
  vtkTable* readings = vtkTable::GetData(outputVector, 0);
  vtkTable* gates = vtkTable::GetData(outputVector, 1);
  if (!input || !readings || !gates)
  {
    vtkErrorMacro(<< "no input");
    return 0;
  }

  vtkFieldData* fd = input->GetFieldData();
  vtkDataArray* fluence = fd ? fd->GetArray("DetectorFluence") : nullptr;
  if (!fluence)
  {
    vtkErrorMacro(<< "the input has no detector readings (no DetectorFluence field array): "
                     "add detectors to Solve Diffusion (its Detectors property, x y z radius "
                     "per detector; vtkSolveDiffusion::AddDetector) and check that the solve "
                     "succeeded with the divergence or fem solver");
    return 0;
  }
  const vtkIdType count = fluence->GetNumberOfTuples();

  // Every per-detector array: present or not (optional ones), and if present
  // with the expected shape.
  struct Field
  {
    const char* Name;
    int Components;
    bool Required;
    vtkDataArray* Array;
  };
  Field fields[] = {
    { "DetectorRequestedPosition", 3, false, nullptr },
    { "DetectorPosition", 3, true, nullptr },
    { "DetectorRadius", 1, false, nullptr },
    { "DetectorFluence", 3, true, nullptr },
    { "DetectorExitance", 3, true, nullptr },
    { "DetectorFluencePhase", 3, false, nullptr },
    { "DetectorExitancePhase", 3, false, nullptr },
  };
  for (Field& field : fields)
  {
    field.Array = fd->GetArray(field.Name);
    if (!field.Array)
    {
      if (field.Required)
      {
        vtkErrorMacro(<< "the input has DetectorFluence but no " << field.Name
                      << " field array: it is not a Solve Diffusion output");
        return 0;
      }
      continue;
    }
    if (field.Array->GetNumberOfComponents() != field.Components ||
      field.Array->GetNumberOfTuples() != count)
    {
      vtkErrorMacro(<< "field array " << field.Name << " has "
                    << field.Array->GetNumberOfTuples() << " tuples of "
                    << field.Array->GetNumberOfComponents() << " components; expected "
                    << count << " (one per detector, as DetectorFluence) of "
                    << field.Components);
      return 0;
    }
  }

  vtkNew<vtkIdTypeArray> ids;
  ids->SetName("Detector");
  ids->SetNumberOfTuples(count);
  for (vtkIdType k = 0; k < count; ++k)
  {
    ids->SetValue(k, k);
  }
  readings->AddColumn(ids);
  if (fields[0].Array)
  {
    AddPositionColumns(readings, "Requested", fields[0].Array);
  }
  AddPositionColumns(readings, "Surface", fields[1].Array);
  if (fields[2].Array)
  {
    AddColumns(readings, "Radius", fields[2].Array);
  }
  AddColumns(readings, "Fluence", fields[3].Array);
  AddColumns(readings, "Exitance", fields[4].Array);
  if (fields[5].Array)
  {
    AddColumns(readings, "FluencePhase", fields[5].Array);
  }
  if (fields[6].Array)
  {
    AddColumns(readings, "ExitancePhase", fields[6].Array);
  }

  // Time gates: one row per gate, one column per detector, quantity and channel.
  if (vtkDataArray* centres = fd->GetArray("TimeGateCentres"))
  {
    const vtkIdType numGates = centres->GetNumberOfTuples();
    vtkNew<vtkDoubleArray> time;
    time->SetName(vtkDetectorReadings::GetTimeColumnName());
    time->SetNumberOfTuples(numGates);
    for (vtkIdType g = 0; g < numGates; ++g)
    {
      time->SetValue(g, centres->GetComponent(g, 0));
    }
    gates->AddColumn(time);
    for (vtkIdType k = 0; k < count; ++k)
    {
      for (const char* quantity : { "Fluence", "Exitance" })
      {
        const std::string arrayName =
          std::string("Detector") + quantity + "TPSF" + std::to_string(k);
        vtkDataArray* tpsf = fd->GetArray(arrayName.c_str());
        if (!tpsf || tpsf->GetNumberOfComponents() != 3 ||
          tpsf->GetNumberOfTuples() != numGates)
        {
          vtkErrorMacro(<< "field array " << arrayName << " is missing or not "
                        << numGates << " tuples (one per time gate) of 3 components");
          return 0;
        }
        AddColumns(gates, "Detector" + std::to_string(k) + "_" + quantity, tpsf);
      }
    }
  }
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
void vtkDetectorReadings::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}
