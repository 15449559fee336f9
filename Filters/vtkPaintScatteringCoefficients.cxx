#include "vtkPaintScatteringCoefficients.h"

#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"
#include "vtkTranslucencyParallel.h"

#include "TetPaint.h"
#include "Error.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkTypeInt32Array.h>
#include <vtkTypeInt64Array.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkAlgorithm.h>
#include <vtkAlgorithmOutput.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkSMPTools.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

vtkStandardNewMacro(vtkPaintScatteringCoefficients);

//------------------------------------------------------------------------------
vtkPaintScatteringCoefficients::vtkPaintScatteringCoefficients()
{
  this->SetNumberOfInputPorts(2);
}

//------------------------------------------------------------------------------
int vtkPaintScatteringCoefficients::FillInputPortInformation(int port, vtkInformation* info)
{
  if (port == 1)
  {
    info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
    return 1;
  }
  return this->Superclass::FillInputPortInformation(port, info);
}

//------------------------------------------------------------------------------
void vtkPaintScatteringCoefficients::SetOriginalMeshConnection(vtkAlgorithmOutput* output)
{
  this->SetInputConnection(1, output);
}

//------------------------------------------------------------------------------
void vtkPaintScatteringCoefficients::SetOriginalMeshData(vtkUnstructuredGrid* mesh)
{
  this->SetInputData(1, mesh);
}

//------------------------------------------------------------------------------
void vtkPaintScatteringCoefficients::AddStrokePoint(double x, double y, double z)
{
  this->StrokePoints.push_back(x);
  this->StrokePoints.push_back(y);
  this->StrokePoints.push_back(z);
  this->Modified();
}

//------------------------------------------------------------------------------
void vtkPaintScatteringCoefficients::RemoveAllStrokePoints()
{
  if (!this->StrokePoints.empty())
  {
    this->StrokePoints.clear();
    this->Modified();
  }
}

//------------------------------------------------------------------------------
int vtkPaintScatteringCoefficients::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // Under MPI: gather to rank 0, run this serially there, hand the result back.
  int parallelResult = 0;
  if (vtkTranslucencyParallel::RunGathered(this, request, inputVector, outputVector,
        vtkTranslucencyParallel::GatherMode::SameMesh,
        [this](vtkInformation* r, vtkInformationVector** i, vtkInformationVector* o)
        { return this->RequestData(r, i, o); },
        parallelResult))
  {
    return parallelResult;
  }
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* cut = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* original =
    this->GetNumberOfInputConnections(1) > 0 ? vtkUnstructuredGrid::GetData(inputVector[1]) : nullptr;
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  // The mesh painted: the original uncut mesh when port 1 is connected
  // (TransCut Sec. 5.2 paints the tets of the original mesh), else port 0.
  vtkUnstructuredGrid* input = original ? original : cut;
  if (this->GetNumberOfInputConnections(1) > 0 && !original)
  {
    vtkErrorMacro(<< "the OriginalMesh (input port 1) is not a vtkUnstructuredGrid");
    return 0;
  }
  if (!input || input->GetNumberOfCells() == 0)
  {
    vtkErrorMacro(<< (original ? "the OriginalMesh (input port 1) is empty (no cells)"
                               : "the input mesh is empty (no cells)"));
    return 0;
  }
  if (original && cut && cut->GetNumberOfCells() > 0)
  {
    // Port 0 (the cut mesh the stroke was drawn on) must map into port 1.
    const vtkIdType numOriginal = original->GetNumberOfCells();
    const vtkIdType numCut = cut->GetNumberOfCells();
    vtkDataArray* ids = cut->GetCellData()->GetArray("vtkOriginalCellIds");
    if (!ids)
    {
      if (numCut != numOriginal)
      {
        vtkErrorMacro(<< "the cut mesh (input port 0) has no cell array 'vtkOriginalCellIds' "
                      << "and " << numCut << " cells, not the " << numOriginal
                      << " of the OriginalMesh (input port 1): it is not a cut of it");
        return 0;
      }
    }
    else if (ids->GetNumberOfComponents() != 1 || ids->GetNumberOfTuples() != numCut)
    {
      vtkErrorMacro(<< "the cell array 'vtkOriginalCellIds' of the cut mesh (input port 0) has "
                    << ids->GetNumberOfComponents() << " components and "
                    << ids->GetNumberOfTuples() << " tuples; 1 component and " << numCut
                    << " tuples expected");
      return 0;
    }
    else
    {
      for (vtkIdType i = 0; i < numCut; ++i)
      {
        const double id = ids->GetComponent(i, 0);
        if (!(id >= 0.0) || !(id < static_cast<double>(numOriginal)) || id != std::floor(id))
        {
          vtkErrorMacro(<< "bad vtkOriginalCellIds " << id << " at cell " << i
                        << " of the cut mesh (input port 0): the OriginalMesh (input port 1) has "
                        << numOriginal << " tets (valid ids 0.." << numOriginal - 1
                        << "); is port 1 the mesh that was cut?");
          return 0;
        }
      }
    }
  }
  const vtkIdType n = input->GetNumberOfCells();
  vtkDataArray* oldArrays[2] = { input->GetCellData()->GetArray(vtkTranslucency::AbsorptionName),
    input->GetCellData()->GetArray(vtkTranslucency::ScatteringName) };
  const char* names[2] = { vtkTranslucency::AbsorptionName, vtkTranslucency::ScatteringName };
  for (int k = 0; k < 2; ++k)
  {
    if (!oldArrays[k])
    {
      vtkErrorMacro(<< "the input has no cell array '" << names[k]
                    << "' (run vtkAssignScatteringCoefficients first)");
      return 0;
    }
    if (oldArrays[k]->GetNumberOfComponents() != 3 || oldArrays[k]->GetNumberOfTuples() != n)
    {
      vtkErrorMacro(<< "the cell array '" << names[k] << "' has "
                    << oldArrays[k]->GetNumberOfComponents() << " components and "
                    << oldArrays[k]->GetNumberOfTuples() << " tuples; 3 components and " << n
                    << " tuples (one per tet) expected");
      return 0;
    }
  }
  if (this->StrokePoints.empty())
  {
    vtkErrorMacro(<< "no stroke points: nothing to paint yet. In ParaView, draw the stroke with "
                     "the polyline widget of the Properties panel (Ctrl+click in the view adds "
                     "a handle), then Apply; from Python, call AddStrokePoint");
    return 0;
  }
  if (!(this->Width >= 0.0) || !std::isfinite(this->Width))
  {
    vtkErrorMacro(<< "the width " << this->Width << " mm must be finite and >= 0");
    return 0;
  }
  for (int c = 0; c < 3; ++c)
  {
    if (!std::isfinite(this->TargetAbsorptionCoefficient[c]) ||
      !std::isfinite(this->TargetReducedScatteringCoefficient[c]))
    {
      vtkErrorMacro(<< "the target of channel " << "RGB"[c] << " is not finite");
      return 0;
    }
  }

  // New double arrays, copies of the old ones (one memcpy for double input),
  // painted in place by the core.
  vtkNew<vtkDoubleArray> newArrays[2];
  for (int k = 0; k < 2; ++k)
  {
    newArrays[k]->SetName(names[k]);
    newArrays[k]->SetNumberOfComponents(3);
    vtkTranslucency::SetRGBComponentNames(newArrays[k]);
    newArrays[k]->SetNumberOfTuples(n);
    double* dst = newArrays[k]->GetPointer(0);
    if (vtkDoubleArray* src = vtkDoubleArray::FastDownCast(oldArrays[k]))
    {
      std::memcpy(dst, src->GetPointer(0), sizeof(double) * 3 * static_cast<size_t>(n));
    }
    else
    {
      vtkDataArray* from = oldArrays[k];
      vtkSMPTools::For(0, n, [from, dst](vtkIdType begin, vtkIdType end) {
        for (vtkIdType i = begin; i < end; ++i)
        {
          from->GetTuple(i, dst + 3 * i);
        }
      });
    }
  }
  vtkNew<vtkDoubleArray> weights;
  weights->SetName("PaintWeight");
  weights->SetNumberOfComponents(1);
  weights->SetNumberOfTuples(n);

  // The paint itself (TransCut Sec. 5.2) is in the core: translucency::TetPaint.
  translucency::TetPaint painter;
  try
  {
    painter.SetStrokePoints(this->StrokeIsPolyline && this->Width > 0.0
        ? translucency::TetPaint::SamplePolyline(this->StrokePoints, this->Width / 4.0)
        : this->StrokePoints);
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  painter.SetWidth(this->Width);
  painter.SetStrength(this->Strength);
  painter.SetCutoffWeight(this->CutoffWeight);
  painter.SetMode(static_cast<translucency::TetPaint::Mode>(this->Mode));
  painter.SetTargetAbsorption({ { this->TargetAbsorptionCoefficient[0],
    this->TargetAbsorptionCoefficient[1], this->TargetAbsorptionCoefficient[2] } });
  painter.SetTargetScattering({ { this->TargetReducedScatteringCoefficient[0],
    this->TargetReducedScatteringCoefficient[1], this->TargetReducedScatteringCoefficient[2] } });
  painter.SetChannelMask(
    { { this->ChannelMask[0] != 0, this->ChannelMask[1] != 0, this->ChannelMask[2] != 0 } });
  try
  {
    // Raw views of the points (float or double) and cells (32 or 64-bit ids).
    vtkSmartPointer<vtkDoubleArray> converted;
    vtkDataArray* pointData = input->GetPoints() ? input->GetPoints()->GetData() : nullptr;
    const vtkIdType numPoints = input->GetNumberOfPoints();
    vtkFloatArray* floatPoints = vtkFloatArray::FastDownCast(pointData);
    vtkDoubleArray* doublePoints = vtkDoubleArray::FastDownCast(pointData);
    if (pointData && !floatPoints && !doublePoints)
    {
      converted = vtkSmartPointer<vtkDoubleArray>::New();
      converted->DeepCopy(pointData);
      doublePoints = converted;
    }
    vtkCellArray* cells = input->GetCells();
    if (!cells || (!floatPoints && !doublePoints))
    {
      vtkErrorMacro(<< "the input mesh has no points or no cells");
      return 0;
    }
    double* a = newArrays[0]->GetPointer(0);
    double* s = newArrays[1]->GetPointer(0);
    double* w = weights->GetPointer(0);
    auto paint = [&](auto* offsets, auto* connectivity) {
      if (floatPoints)
      {
        painter.Paint(floatPoints->GetPointer(0), numPoints, offsets, connectivity, n, a, s, w);
      }
      else
      {
        painter.Paint(doublePoints->GetPointer(0), numPoints, offsets, connectivity, n, a, s, w);
      }
    };
    if (cells->IsStorage64Bit())
    {
      paint(reinterpret_cast<const long long*>(cells->GetOffsetsArray64()->GetPointer(0)),
        reinterpret_cast<const long long*>(cells->GetConnectivityArray64()->GetPointer(0)));
    }
    else
    {
      paint(reinterpret_cast<const int*>(cells->GetOffsetsArray32()->GetPointer(0)),
        reinterpret_cast<const int*>(cells->GetConnectivityArray32()->GetPointer(0)));
    }
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }

  // The ids of the cells whose coefficients changed (for incremental updates).
  const std::vector<int>& changed = painter.GetChangedCells();
  vtkNew<vtkIdTypeArray> changedIds;
  changedIds->SetName("PaintedCellIds");
  changedIds->SetNumberOfTuples(static_cast<vtkIdType>(changed.size()));
  std::copy(changed.begin(), changed.end(), changedIds->GetPointer(0));

  output->ShallowCopy(input);
  output->GetCellData()->AddArray(newArrays[0]);
  output->GetCellData()->AddArray(newArrays[1]);
  output->GetCellData()->AddArray(weights);
  vtkNew<vtkFieldData> fieldData;
  fieldData->ShallowCopy(input->GetFieldData());
  fieldData->AddArray(changedIds);
  output->SetFieldData(fieldData);
  if (painter.GetNumberOfKeptChannels() > 0)
  {
    vtkWarningMacro(<< painter.GetNumberOfKeptChannels()
                    << " tet channel(s) would have had mu_a + sigma_s' = 0 "
                    << "and kept their old values");
  }
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
void vtkPaintScatteringCoefficients::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "OriginalMesh: "
     << (this->GetNumberOfInputConnections(1) > 0 ? "connected" : "(none)") << "\n";
  os << indent << "NumberOfStrokePoints: " << this->GetNumberOfStrokePoints() << "\n";
  os << indent << "StrokeIsPolyline: " << this->StrokeIsPolyline << "\n";
  os << indent << "Width: " << this->Width << "\n";
  os << indent << "Strength: " << this->Strength << "\n";
  os << indent << "CutoffWeight: " << this->CutoffWeight << "\n";
  os << indent << "Mode: " << this->Mode << "\n";
  os << indent << "TargetAbsorptionCoefficient: " << this->TargetAbsorptionCoefficient[0] << ", "
     << this->TargetAbsorptionCoefficient[1] << ", " << this->TargetAbsorptionCoefficient[2]
     << "\n";
  os << indent << "TargetReducedScatteringCoefficient: "
     << this->TargetReducedScatteringCoefficient[0] << ", "
     << this->TargetReducedScatteringCoefficient[1] << ", "
     << this->TargetReducedScatteringCoefficient[2] << "\n";
  os << indent << "ChannelMask: " << this->ChannelMask[0] << ", " << this->ChannelMask[1] << ", "
     << this->ChannelMask[2] << "\n";
}
