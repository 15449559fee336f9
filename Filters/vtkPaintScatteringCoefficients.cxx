#include "vtkPaintScatteringCoefficients.h"

#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"
#include "vtkTranslucencyDispatch.h"
#include "vtkTranslucencyGhosts.h"

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
#include <vtkDataSetAttributes.h>
#include <vtkUnsignedCharArray.h>
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
#include <sstream>
#include <string>
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
namespace
{
/// "" if `cut` (port 0) maps into the original mesh (port 1) of
/// `numOriginal` tets, else the error. `numCut`: the cut mesh's tets (all
/// pieces' owned cells under MPI); `withoutIds`: some piece with cells has
/// no vtkOriginalCellIds (this one under MPI: any rank's). The ids are
/// checked on `cut` itself.
std::string CheckCutMapping(
  vtkUnstructuredGrid* cut, long long numCut, long long numOriginal, bool withoutIds)
{
  std::ostringstream msg;
  vtkDataArray* ids = cut ? cut->GetCellData()->GetArray("vtkOriginalCellIds") : nullptr;
  const vtkIdType localCut = cut ? cut->GetNumberOfCells() : 0;
  if (withoutIds)
  {
    if (numCut != numOriginal)
    {
      msg << "the cut mesh (input port 0) has no cell array 'vtkOriginalCellIds' "
          << "and " << numCut << " cells, not the " << numOriginal
          << " of the OriginalMesh (input port 1): it is not a cut of it";
    }
    return msg.str();
  }
  if (localCut == 0)
  {
    return std::string(); // an empty piece under MPI
  }
  if (ids->GetNumberOfComponents() != 1 || ids->GetNumberOfTuples() != localCut)
  {
    msg << "the cell array 'vtkOriginalCellIds' of the cut mesh (input port 0) has "
        << ids->GetNumberOfComponents() << " components and " << ids->GetNumberOfTuples()
        << " tuples; 1 component and " << localCut << " tuples expected";
    return msg.str();
  }
  for (vtkIdType i = 0; i < localCut; ++i)
  {
    const double id = ids->GetComponent(i, 0);
    if (!(id >= 0.0) || !(id < static_cast<double>(numOriginal)) || id != std::floor(id))
    {
      msg << "bad vtkOriginalCellIds " << id << " at cell " << i
          << " of the cut mesh (input port 0): the OriginalMesh (input port 1) has "
          << numOriginal << " tets (valid ids 0.." << numOriginal - 1
          << "); is port 1 the mesh that was cut?";
      return msg.str();
    }
  }
  return std::string();
}
}

//------------------------------------------------------------------------------
int vtkPaintScatteringCoefficients::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector,
    [this](vtkInformationVector** i, vtkInformationVector* o, const vtkTranslucencyCommunicator& c)
    { return this->RequestPerPiece(i, o, c); });
}

//------------------------------------------------------------------------------
int vtkPaintScatteringCoefficients::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::UpdateExtent(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkPaintScatteringCoefficients::PlanParallel(
  vtkInformationVector**, const vtkTranslucencyCommunicator&)
{
  return vtkTranslucencyParallelPlan::PerPiece(vtkTranslucencyParallelPlan::GatherMode::SameMesh,
    "per-tet weights; the cut/original check counts over the ranks");
}

//------------------------------------------------------------------------------
int vtkPaintScatteringCoefficients::RequestSerial(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return this->RequestPerPiece(inputVector, outputVector, vtkTranslucencyCommunicator::Self());
}

//------------------------------------------------------------------------------
int vtkPaintScatteringCoefficients::RequestPerPiece(vtkInformationVector** inputVector,
  vtkInformationVector* outputVector, const vtkTranslucencyCommunicator& comm)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* cut = vtkUnstructuredGrid::GetData(inputVector[0]);
  const bool hasOriginal = this->GetNumberOfInputConnections(1) > 0;
  vtkUnstructuredGrid* original = hasOriginal ? vtkUnstructuredGrid::GetData(inputVector[1]) : nullptr;
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  // The mesh painted: the original uncut mesh when port 1 is connected
  // (TransCut Sec. 5.2 paints the tets of the original mesh), else port 0.
  vtkUnstructuredGrid* input = original ? original : cut;

  // Under MPI each rank paints its own piece (the weight of a tet depends on
  // its centroid only; a ghost cell gets the same value as the tet it copies);
  // the checks that need the whole mesh use totals over the ranks, and every
  // rank reports the same error.
  const bool perPiece = comm.IsParallel();
  auto sum = [&comm](long long value) { return comm.Sum(value); };
  // Every rank takes part in every collective below, an empty piece too.
  const long long totalInput = sum(input ? input->GetNumberOfCells() : 0);
  long long numCut = 0, numOriginal = 0;
  bool cutWithoutIds = false;
  if (hasOriginal)
  {
    cutWithoutIds = cut && cut->GetNumberOfCells() > 0 &&
      !cut->GetCellData()->GetArray("vtkOriginalCellIds");
    cutWithoutIds = comm.Any(cutWithoutIds);
    numCut = sum(perPiece ? vtkTranslucency::OwnedCellCount(cut) : (cut ? cut->GetNumberOfCells() : 0));
    numOriginal = sum(perPiece ? vtkTranslucency::OwnedCellCount(original) : (original ? original->GetNumberOfCells() : 0));
  }
  std::string error;
  if (hasOriginal && !original)
  {
    error = "the OriginalMesh (input port 1) is not a vtkUnstructuredGrid";
  }
  else if (totalInput == 0)
  {
    error = hasOriginal ? "the OriginalMesh (input port 1) is empty (no cells)"
                        : "the input mesh is empty (no cells)";
  }
  else if (hasOriginal && numCut > 0)
  {
    // Port 0 (the cut mesh the stroke was drawn on) must map into port 1.
    error = CheckCutMapping(cut, numCut, numOriginal, cutWithoutIds);
  }
  long long keptChannels = 0;
  if (error.empty())
  {
    error = this->Paint(input, output, keptChannels);
  }
  if (perPiece)
  {
    error = comm.AgreeOnError(error);
    keptChannels = comm.Sum(keptChannels);
  }
  if (!error.empty())
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  if (keptChannels > 0 && comm.GetRank() == 0)
  {
    vtkWarningMacro(<< keptChannels << " tet channel(s) would have had mu_a + sigma_s' = 0 "
                    << "and kept their old values");
  }
  return outputs.Succeed();
}

namespace
{
/// Paint: the core's paint on raw views of the input's points (float or
/// double) and cells (32 or 64-bit ids), into a, s (3 per cell) and the
/// weights w; "" or the error.
std::string PaintCells(translucency::TetPaint& painter, vtkUnstructuredGrid* input, vtkIdType n,
  double* a, double* s, double* w)
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
    return "the input mesh has no points or no cells";
  }
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
  return std::string();
}

/// Paint: new double arrays `names`, copies of the old ones (one memcpy
/// for double input), to be painted in place by the core.
void CopyCoefficients(vtkDataArray* const oldArrays[2], const char* const names[2], vtkIdType n,
  vtkDoubleArray* const newArrays[2])
{
  for (int k = 0; k < 2; ++k)
  {
    newArrays[k]->SetName(names[k]);
    newArrays[k]->SetNumberOfComponents(3);
    vtkTranslucency::SetRGBComponentNames(newArrays[k]);
    newArrays[k]->SetNumberOfTuples(n);
    if (n == 0)
    {
      continue;
    }
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
}

} // namespace

//------------------------------------------------------------------------------
std::string vtkPaintScatteringCoefficients::Paint(
  vtkUnstructuredGrid* input, vtkUnstructuredGrid* output, long long& keptChannels)
{
  std::ostringstream msg;
  this->LastExecutionReused = false;
  const vtkIdType n = input ? input->GetNumberOfCells() : 0;
  vtkDataArray* oldArrays[2] = { nullptr, nullptr };
  const char* names[2] = { vtkTranslucency::AbsorptionName, vtkTranslucency::ScatteringName };
  for (int k = 0; k < 2 && n > 0; ++k)
  {
    // (An empty piece under MPI need not carry the arrays.)
    oldArrays[k] = input->GetCellData()->GetArray(names[k]);
    if (!oldArrays[k])
    {
      msg << "the input has no cell array '" << names[k]
          << "' (run vtkAssignScatteringCoefficients first)";
      return msg.str();
    }
    if (oldArrays[k]->GetNumberOfComponents() != 3 || oldArrays[k]->GetNumberOfTuples() != n)
    {
      msg << "the cell array '" << names[k] << "' has " << oldArrays[k]->GetNumberOfComponents()
          << " components and " << oldArrays[k]->GetNumberOfTuples()
          << " tuples; 3 components and " << n << " tuples (one per tet) expected";
      return msg.str();
    }
  }
  if (this->StrokePoints.empty())
  {
    return "no stroke points: nothing to paint yet. In ParaView, draw the stroke with "
           "the polyline widget of the Properties panel (Ctrl+click in the view adds "
           "a handle), then Apply; from Python, call AddStrokePoint";
  }
  if (!(this->Width >= 0.0) || !std::isfinite(this->Width))
  {
    msg << "the width " << this->Width << " mm must be finite and >= 0";
    return msg.str();
  }
  for (int c = 0; c < 3; ++c)
  {
    if (!std::isfinite(this->TargetAbsorptionCoefficient[c]) ||
      !std::isfinite(this->TargetReducedScatteringCoefficient[c]))
    {
      msg << "the target of channel " << "RGB"[c] << " is not finite";
      return msg.str();
    }
  }

  // Nothing this painting reads changed since the last one (a light turned
  // upstream): hand on the kept arrays, no per-tet work.
  vtkDataArray* keys[4];
  vtkMTimeType times[4];
  this->KeyOf(input, keys, times);
  bool same = this->Kept.Outputs[0] && this->Kept.FilterTime == this->GetMTime() &&
    this->Kept.Cells == n;
  for (int k = 0; k < 4 && same; ++k)
  {
    same = this->Kept.Inputs[k].GetPointer() == keys[k] && this->Kept.InputTimes[k] == times[k];
  }
  if (same)
  {
    vtkDataArray* const arrays[3] = { this->Kept.Outputs[0], this->Kept.Outputs[1],
      this->Kept.Outputs[2] };
    AttachPaint(input, output, arrays, this->Kept.ChangedIds);
    keptChannels = this->Kept.KeptChannels;
    this->LastExecutionReused = true;
    return std::string();
  }
  this->LastExecutionReused = false;
  this->Kept = KeptPaint();

  // New double arrays, copies of the old ones (one memcpy for double input),
  // painted in place by the core.
  vtkNew<vtkDoubleArray> newArrays[2];
  vtkDoubleArray* const newPointers[2] = { newArrays[0], newArrays[1] };
  CopyCoefficients(oldArrays, names, n, newPointers);
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
    return e.what();
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
  if (n > 0)
  {
    try
    {
      const std::string error = PaintCells(painter, input, n, newArrays[0]->GetPointer(0),
        newArrays[1]->GetPointer(0), weights->GetPointer(0));
      if (!error.empty())
      {
        return error;
      }
    }
    catch (const translucency::Error& e)
    {
      return e.what();
    }
  }

  // The ids of the cells whose coefficients changed (for incremental updates).
  const std::vector<int>& changed = painter.GetChangedCells();
  vtkNew<vtkIdTypeArray> changedIds;
  changedIds->SetName("PaintedCellIds");
  changedIds->SetNumberOfTuples(n > 0 ? static_cast<vtkIdType>(changed.size()) : 0);
  if (n > 0)
  {
    std::copy(changed.begin(), changed.end(), changedIds->GetPointer(0));
  }

  vtkDataArray* const arrays[3] = { newArrays[0], newArrays[1], weights };
  AttachPaint(input, output, arrays, changedIds);
  keptChannels = n > 0 ? painter.GetNumberOfKeptChannels() : 0;
  ++this->NumberOfPaintings;
  // Kept for the next execution (the arrays are shared with the output,
  // whose consumers never modify their inputs).
  for (int k = 0; k < 4; ++k)
  {
    this->Kept.Inputs[k] = keys[k];
    this->Kept.InputTimes[k] = times[k];
  }
  this->Kept.Cells = n;
  this->Kept.FilterTime = this->GetMTime();
  for (int k = 0; k < 3; ++k)
  {
    this->Kept.Outputs[k] = arrays[k];
  }
  this->Kept.ChangedIds = changedIds.GetPointer();
  this->Kept.KeptChannels = keptChannels;
  return std::string();
}

//------------------------------------------------------------------------------
void vtkPaintScatteringCoefficients::KeyOf(
  vtkUnstructuredGrid* input, vtkDataArray* keys[4], vtkMTimeType times[4]) const
{
  vtkCellArray* cells = input ? input->GetCells() : nullptr;
  keys[0] = input ? input->GetCellData()->GetArray(vtkTranslucency::AbsorptionName) : nullptr;
  keys[1] = input ? input->GetCellData()->GetArray(vtkTranslucency::ScatteringName) : nullptr;
  keys[2] = input && input->GetPoints() ? input->GetPoints()->GetData() : nullptr;
  keys[3] = cells ? cells->GetConnectivityArray() : nullptr;
  for (int k = 0; k < 4; ++k)
  {
    times[k] = keys[k] ? keys[k]->GetMTime() : 0;
  }
  // The offsets array changes with the connectivity's (vtkCellArray owns both).
  if (cells)
  {
    times[3] = std::max(times[3], cells->GetMTime());
  }
}

//------------------------------------------------------------------------------
void vtkPaintScatteringCoefficients::AttachPaint(vtkUnstructuredGrid* input,
  vtkUnstructuredGrid* output, vtkDataArray* const arrays[3], vtkDataArray* changedIds)
{
  if (input)
  {
    output->ShallowCopy(input);
  }
  for (int k = 0; k < 3; ++k)
  {
    output->GetCellData()->AddArray(arrays[k]);
  }
  vtkNew<vtkFieldData> fieldData;
  if (input)
  {
    fieldData->ShallowCopy(input->GetFieldData());
  }
  fieldData->AddArray(changedIds);
  output->SetFieldData(fieldData);
}

//------------------------------------------------------------------------------
void vtkPaintScatteringCoefficients::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "OriginalMesh: "
     << (this->GetNumberOfInputConnections(1) > 0 ? "connected" : "(none)") << "\n";
  os << indent << "LastExecutionReused: " << this->LastExecutionReused << "\n";
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
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}
