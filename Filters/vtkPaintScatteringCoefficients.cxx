#include "vtkPaintScatteringCoefficients.h"

#include "vtkTranslucencyMeshConversion.h"

#include <vtkCellData.h>
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

#include <atomic>
#include <cmath>
#include <limits>
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
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
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
    vtkErrorMacro(<< "no stroke points: add at least one with AddStrokePoint");
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

  vtkNew<vtkDoubleArray> absorption;
  absorption->SetName(vtkTranslucency::AbsorptionName);
  absorption->SetNumberOfComponents(3);
  absorption->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> scattering;
  scattering->SetName(vtkTranslucency::ScatteringName);
  scattering->SetNumberOfComponents(3);
  scattering->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> weights;
  weights->SetName("PaintWeight");
  weights->SetNumberOfComponents(1);
  weights->SetNumberOfTuples(n);

  const bool paints = this->Width > 0.0 && this->Strength > 0.0;
  const double twoSigma2 = 2.0 * this->Width * this->Width;
  const double* stroke = this->StrokePoints.data();
  const size_t numStroke = this->StrokePoints.size() / 3;
  std::atomic<vtkIdType> kept(0);
  // Tet centroids (mean of the vertices), serially: the cell access of
  // vtkUnstructuredGrid may use shared scratch space.
  std::vector<double> centroids;
  if (paints)
  {
    centroids.assign(3 * static_cast<size_t>(n), 0.0);
    for (vtkIdType i = 0; i < n; ++i)
    {
      vtkIdType npts;
      const vtkIdType* pts;
      input->GetCellPoints(i, npts, pts);
      double* c = centroids.data() + 3 * i;
      for (vtkIdType k = 0; k < npts; ++k)
      {
        double x[3];
        input->GetPoint(pts[k], x);
        for (int a = 0; a < 3; ++a)
        {
          c[a] += x[a] / static_cast<double>(npts);
        }
      }
    }
  }
  vtkSMPTools::For(0, n, [&](vtkIdType begin, vtkIdType end) {
    double old[2][3], now[2][3];
    vtkIdType local = 0;
    for (vtkIdType i = begin; i < end; ++i)
    {
      oldArrays[0]->GetTuple(i, old[0]);
      oldArrays[1]->GetTuple(i, old[1]);
      double w = 0.0;
      if (paints)
      {
        const double* c = centroids.data() + 3 * i;
        double d2 = std::numeric_limits<double>::infinity();
        for (size_t s = 0; s < numStroke; ++s)
        {
          const double* p = stroke + 3 * s;
          const double dx = c[0] - p[0], dy = c[1] - p[1], dz = c[2] - p[2];
          const double e = dx * dx + dy * dy + dz * dz;
          d2 = e < d2 ? e : d2;
        }
        // TransCut Sec. 5.2: influence from the closest stroke point and a Gaussian.
        w = this->Strength * std::exp(-d2 / twoSigma2);
      }
      for (int k = 0; k < 2; ++k)
      {
        for (int c = 0; c < 3; ++c)
        {
          now[k][c] = old[k][c];
        }
      }
      if (w > 0.0)
      {
        const double* target[2] = { this->TargetAbsorptionCoefficient,
          this->TargetReducedScatteringCoefficient };
        for (int c = 0; c < 3; ++c)
        {
          if (!this->ChannelMask[c])
          {
            continue;
          }
          double v[2];
          for (int k = 0; k < 2; ++k)
          {
            const double t = target[k][c];
            switch (this->Mode)
            {
              case SET:
                v[k] = (1.0 - w) * old[k][c] + w * t;
                break;
              case MULTIPLY:
                v[k] = old[k][c] * (1.0 + w * (t - 1.0));
                break;
              default:
                v[k] = old[k][c] + w * t;
                break;
            }
            v[k] = v[k] > 0.0 ? v[k] : 0.0;
          }
          if (v[0] + v[1] > 0.0)
          {
            now[0][c] = v[0];
            now[1][c] = v[1];
          }
          else
          {
            ++local;
          }
        }
      }
      absorption->SetTypedTuple(i, now[0]);
      scattering->SetTypedTuple(i, now[1]);
      weights->SetValue(i, w);
    }
    kept += local;
  });

  output->ShallowCopy(input);
  output->GetCellData()->AddArray(absorption);
  output->GetCellData()->AddArray(scattering);
  output->GetCellData()->AddArray(weights);
  if (kept > 0)
  {
    vtkWarningMacro(<< kept.load() << " tet channel(s) would have had mu_a + sigma_s' = 0 "
                    << "and kept their old values");
  }
  return 1;
}

//------------------------------------------------------------------------------
void vtkPaintScatteringCoefficients::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "OriginalMesh: "
     << (this->GetNumberOfInputConnections(1) > 0 ? "connected" : "(none)") << "\n";
  os << indent << "NumberOfStrokePoints: " << this->GetNumberOfStrokePoints() << "\n";
  os << indent << "Width: " << this->Width << "\n";
  os << indent << "Strength: " << this->Strength << "\n";
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
