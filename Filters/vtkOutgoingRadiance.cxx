#include "vtkOutgoingRadiance.h"

#include "ResourceLimits.h"
#include "vtkTranslucencyParallel.h"

#include "Error.h"
#include "Radiance.h"
#include "ToneMap.h"
#include "TetMesh.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkFieldData.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSMPTools.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>

vtkStandardNewMacro(vtkOutgoingRadiance);

struct vtkOutgoingRadiance::Internals
{
  std::shared_ptr<const translucency::TetMesh> Mesh;
};

//------------------------------------------------------------------------------
vtkOutgoingRadiance::vtkOutgoingRadiance()
  : Internal(new Internals)
{
}

vtkOutgoingRadiance::~vtkOutgoingRadiance() = default;

//------------------------------------------------------------------------------
int vtkOutgoingRadiance::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
  return 1;
}

//------------------------------------------------------------------------------
int vtkOutgoingRadiance::RequestData(
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
  vtkPolyData* output = vtkPolyData::GetData(outputVector);
  std::string error;
  this->Internal->Mesh = vtkTranslucency::AcquireTetMesh(input, error);
  if (!this->Internal->Mesh)
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const translucency::TetMesh& mesh = *this->Internal->Mesh;
  std::vector<double> fluence, irradiance;
  if (!vtkTranslucency::ReadPointArray(input, vtkTranslucency::FluenceName, 3, fluence, error) ||
    !vtkTranslucency::ReadPointArray(
      input, vtkTranslucency::IrradianceName, 3, irradiance, error))
  {
    vtkErrorMacro(<< error << " (run vtkSurfaceIrradiance and vtkSolveDiffusion first)");
    return 0;
  }
  // The extended collimated model's Fluence includes the unscattered beam,
  // which does not leave as diffuse radiance: read phi_d.
  if (input->GetPointData()->GetArray("CollimatedFluence"))
  {
    std::vector<double> collimated;
    if (!vtkTranslucency::ReadPointArray(input, "CollimatedFluence", 3, collimated, error))
    {
      vtkErrorMacro(<< error);
      return 0;
    }
    for (std::size_t k = 0; k < fluence.size(); ++k)
    {
      fluence[k] -= collimated[k];
    }
  }
  std::vector<double> tetEta;
  if (!vtkTranslucency::ReadRefractiveIndex(input, tetEta, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const std::vector<double> pointEta = translucency::PointRefractiveIndex(mesh, tetEta);
  // Radiance at the boundary points (TransCut eq. 3), OpenMP-parallel in the core.
  std::vector<double> values;
  try
  {
    // The Robin rule the solve used (vtkSolveDiffusion writes
    // TranslucencyBoundaryRule = 1 for the Fresnel moments of the
    // "extended-moments" collimated model); absent: eq. 3's fit.
    vtkDataArray* ruleArray = input->GetFieldData()->GetArray("TranslucencyBoundaryRule");
    const translucency::Fresnel::BoundaryRule rule =
      ruleArray && ruleArray->GetNumberOfTuples() > 0 && ruleArray->GetComponent(0, 0) == 1.0
      ? translucency::Fresnel::BoundaryRule::Moments
      : translucency::Fresnel::BoundaryRule::Fit;
    values = translucency::BoundaryRadiance(mesh, fluence, irradiance, pointEta,
      this->UseViewPoint ? this->ViewPoint : nullptr, this->NSquaredLaw, rule);
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  {
    // Light enters but no radiance leaves anywhere: eq. 3 went negative (and
    // was clamped to 0) at every point. Seen when the tets are far larger than
    // the transport mean free path (a model in the wrong unit or scaled by
    // 1e6..1e9): the boundary fluence is not resolved. Say so, naming the scale.
    double maxIrradiance = 0.0, maxRadiance = 0.0;
    for (int i : mesh.GetBoundaryPoints())
      for (int c = 0; c < 3; ++c)
        maxIrradiance = std::max(maxIrradiance, irradiance[3 * static_cast<size_t>(i) + c]);
    for (double v : values)
      maxRadiance = std::max(maxRadiance, v);
    if (maxIrradiance > 0.0 && maxRadiance == 0.0)
    {
      double bounds[6];
      input->GetBounds(bounds);
      const double diagonal = std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
        (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) +
        (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
      const double spacing =
        diagonal / std::cbrt(std::max<double>(1.0, static_cast<double>(mesh.GetNumberOfTets())));
      vtkWarningMacro(<< "Radiance is 0 at every boundary point although light enters (irradiance "
                      << "up to " << maxIrradiance << " W/mm^2): the model is "
                      << translucency::FormatNumber(diagonal) << " mm across with tets of about "
                      << translucency::FormatNumber(spacing)
                      << " mm, far coarser than the light's mean free path (~1/sigma_s', about "
                         "1 mm for the measured materials), so the fluence at the surface is "
                         "not resolved: is the model in mm? (else use much smaller tets)");
    }
  }

  // Compact surface: boundary points only.
  const std::vector<int>& boundary = mesh.GetBoundaryPoints();
  const vtkIdType n = static_cast<vtkIdType>(boundary.size());
  std::vector<vtkIdType> surfaceId(static_cast<size_t>(mesh.GetNumberOfPoints()), -1);
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  vtkNew<vtkIdTypeArray> originalIds;
  originalIds->SetName(vtkTranslucency::OriginalPointIdsName);
  originalIds->SetNumberOfTuples(n);
  for (vtkIdType k = 0; k < n; ++k)
  {
    surfaceId[boundary[k]] = k;
    points->SetPoint(k, mesh.GetPoint(boundary[k]));
    originalIds->SetValue(k, boundary[k]);
  }
  const std::vector<int>& tris = mesh.GetBoundaryTriangles();
  vtkNew<vtkCellArray> polys;
  polys->AllocateExact(static_cast<vtkIdType>(tris.size() / 3), static_cast<vtkIdType>(tris.size()));
  for (size_t f = 0; f < tris.size() / 3; ++f)
  {
    const vtkIdType ids[3] = { surfaceId[tris[3 * f]], surfaceId[tris[3 * f + 1]],
      surfaceId[tris[3 * f + 2]] };
    polys->InsertNextCell(3, ids);
  }

  auto makeArray = [n](const char* name, bool rgb) {
    vtkDoubleArray* a = vtkDoubleArray::New();
    a->SetName(name);
    a->SetNumberOfComponents(3);
    a->SetNumberOfTuples(n);
    if (rgb)
    {
      vtkTranslucency::SetRGBComponentNames(a);
    }
    return a;
  };
  vtkDoubleArray* radiance = makeArray(vtkTranslucency::RadianceName, true);
  vtkDoubleArray* phiOut = makeArray(vtkTranslucency::FluenceName, true);
  vtkDoubleArray* qOut = makeArray(vtkTranslucency::IrradianceName, true);
  vtkDoubleArray* normalsOut = makeArray("Normals", false);
  const std::vector<double>& normals = mesh.GetPointNormals();
  vtkSMPTools::For(0, n, [&](vtkIdType begin, vtkIdType end) {
    for (vtkIdType k = begin; k < end; ++k)
    {
      const size_t i = static_cast<size_t>(boundary[k]);
      for (int c = 0; c < 3; ++c)
      {
        radiance->SetTypedComponent(k, c, values[3 * k + c]);
        phiOut->SetTypedComponent(k, c, fluence[3 * i + c]);
        qOut->SetTypedComponent(k, c, irradiance[3 * i + c]);
        normalsOut->SetTypedComponent(k, c, normals[3 * i + c]);
      }
    }
  });
  output->SetPoints(points);
  output->SetPolys(polys);
  output->GetPointData()->AddArray(radiance);
  output->GetPointData()->AddArray(phiOut);
  output->GetPointData()->AddArray(qOut);
  output->GetPointData()->SetNormals(normalsOut);
  output->GetPointData()->AddArray(originalIds);
  // The display colours (the CLI's PNG mapping): Map Scalars off in ParaView.
  this->ExposureUsed =
    this->Exposure > 0.0 ? this->Exposure : translucency::AutomaticExposure(values);
  const std::vector<unsigned char> bytes = translucency::ToneMap(values, this->ExposureUsed);
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetName("RadianceRGB");
  rgb->SetNumberOfComponents(3);
  rgb->SetNumberOfTuples(n);
  std::copy(bytes.begin(), bytes.end(), rgb->GetPointer(0));
  vtkTranslucency::SetRGBComponentNames(rgb);
  output->GetPointData()->AddArray(rgb);
  vtkNew<vtkDoubleArray> exposureArray;
  exposureArray->SetName("RadianceExposure");
  exposureArray->InsertNextValue(this->ExposureUsed);
  output->GetFieldData()->AddArray(exposureArray);
  output->GetPointData()->SetActiveScalars(vtkTranslucency::RadianceName);
  radiance->Delete();
  phiOut->Delete();
  qOut->Delete();
  normalsOut->Delete();
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
void vtkOutgoingRadiance::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "UseViewPoint: " << this->UseViewPoint << "\n";
  os << indent << "NSquaredLaw: " << this->NSquaredLaw << "\n";
  os << indent << "ViewPoint: " << this->ViewPoint[0] << ", " << this->ViewPoint[1] << ", "
     << this->ViewPoint[2] << "\n";
}
