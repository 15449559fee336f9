#include "vtkOutgoingRadiance.h"

#include "Sp3Solver.h"

#include "vtkTranslucencyDispatch.h"
#include "ResourceLimits.h"
#include "vtkTranslucencyMPI.h"
#include "vtkTranslucencyDistributedRadiance.h"

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
#include <vtkSmartPointer.h>
#include <vtkSMPTools.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkOutgoingRadiance);

namespace
{
/// The display colours of both paths (the CLI's PNG mapping: Map Scalars
/// off in ParaView): RadianceRGB at the exposure, the exposure as field
/// data, Radiance the active scalars.
void AttachDisplayColours(vtkPolyData* output, const std::vector<double>& values, double exposure)
{
  const std::vector<unsigned char> bytes = translucency::ToneMap(values, exposure);
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetName("RadianceRGB");
  rgb->SetNumberOfComponents(3);
  rgb->SetNumberOfTuples(static_cast<vtkIdType>(values.size() / 3));
  std::copy(bytes.begin(), bytes.end(), rgb->GetPointer(0));
  vtkTranslucency::SetRGBComponentNames(rgb);
  output->GetPointData()->AddArray(rgb);
  vtkNew<vtkDoubleArray> exposureArray;
  exposureArray->SetName("RadianceExposure");
  exposureArray->InsertNextValue(exposure);
  output->GetFieldData()->AddArray(exposureArray);
  output->GetPointData()->SetActiveScalars(vtkTranslucency::RadianceName);
}

/// The core's read-out for the filter's RadianceReadout property.
translucency::RadianceReadout ToReadout(int readout)
{
  return readout == vtkOutgoingRadiance::PAPER ? translucency::RadianceReadout::Paper
                                               : translucency::RadianceReadout::EnergyConserving;
}
}

/// The composite moments of an sp3 solve (point arrays SP3Phi1, SP3Phi2,
/// written by vtkSolveDiffusion): true when both are there and readable;
/// false with `error` empty when they are absent (another solver), with
/// `error` set when one is missing or malformed.
static bool ReadSp3Moments(vtkUnstructuredGrid* input, std::vector<double>& phi1,
  std::vector<double>& phi2, std::string& error)
{
  const bool has1 = input && input->GetPointData()->GetArray("SP3Phi1");
  const bool has2 = input && input->GetPointData()->GetArray("SP3Phi2");
  if (!has1 && !has2)
  {
    return false;
  }
  if (!has1 || !has2)
  {
    error = std::string("the sp3 moments need both point arrays SP3Phi1 and SP3Phi2 (") +
      (has1 ? "SP3Phi2" : "SP3Phi1") + " is missing)";
    return false;
  }
  return vtkTranslucency::ReadPointArray(input, "SP3Phi1", 3, phi1, error) &&
    vtkTranslucency::ReadPointArray(input, "SP3Phi2", 3, phi2, error);
}

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
  return vtkTranslucencyDispatch::Run(this, request, inputVector, outputVector,
    [this](vtkInformationVector** i, const vtkTranslucencyCommunicator& c)
    { return this->PlanParallel(i, c); },
    { [this](vtkInformation* r, vtkInformationVector** i, vtkInformationVector* o)
      { return this->RequestSerial(r, i, o); },
      [this](vtkInformationVector** i, vtkInformationVector* o, const vtkTranslucencyCommunicator& c)
      { return this->RequestPerPiece(i, o, c); }  },
    { this->ParallelPath, this->ParallelPlan });
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkOutgoingRadiance::PlanParallel(
  vtkInformationVector**, const vtkTranslucencyCommunicator& comm)
{
  using Plan = vtkTranslucencyParallelPlan;
  if (!vtkTranslucency::CanDistribute(comm))
  {
    return Plan::Gathered(Plan::GatherMode::RankZero,
      "the physical boundary needs the distributed numbering (a build with hypre and VTK's "
      "ParallelMPI)");
  }
  Plan plan = Plan::PerPiece(Plan::GatherMode::RankZero,
    "each rank outputs the physical boundary faces of its own tets; together the serial surface");
  plan.DeprecatedVariable = "TRANSLUCENCY_GATHERED_RADIANCE";
  return plan;
}

//------------------------------------------------------------------------------
int vtkOutgoingRadiance::RequestSerial(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
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
    std::vector<double> phi1, phi2;
    if (ReadSp3Moments(input, phi1, phi2, error))
    {
      // An sp3 solve: the outgoing P3 radiance of its moments.
      values = translucency::Sp3BoundaryRadiance(mesh, phi1, phi2, irradiance, pointEta,
        this->UseViewPoint ? this->ViewPoint : nullptr, ToReadout(this->RadianceReadout));
    }
    else if (!error.empty())
    {
      throw translucency::Error(error);
    }
    else
    {
      values = translucency::BoundaryRadiance(mesh, fluence, irradiance, pointEta,
        this->UseViewPoint ? this->ViewPoint : nullptr, ToReadout(this->RadianceReadout), rule);
    }
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
  AttachDisplayColours(output, values, this->ExposureUsed);
  radiance->Delete();
  phiOut->Delete();
  qOut->Delete();
  normalsOut->Delete();
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
int vtkOutgoingRadiance::RequestPerPiece(vtkInformationVector** inputVector,
  vtkInformationVector* outputVector, const vtkTranslucencyCommunicator& comm)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkPolyData* output = vtkPolyData::GetData(outputVector);
  this->Internal->Mesh.reset();
  // Every rank takes part in every collective below, an empty piece too.
  vtkTranslucencyDistributedRadiance::Surface surface;
  std::string error;
  if (!vtkTranslucencyDistributedRadiance::FindSurface(input, surface, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const vtkIdType numPoints = input ? input->GetNumberOfPoints() : 0;
  std::vector<double> fluence, irradiance;
  std::string local;
  if (numPoints > 0)
  {
    if (!vtkTranslucency::ReadPointArray(input, vtkTranslucency::FluenceName, 3, fluence, local) ||
      !vtkTranslucency::ReadPointArray(input, vtkTranslucency::IrradianceName, 3, irradiance, local))
    {
      local += " (run vtkSurfaceIrradiance and vtkSolveDiffusion first)";
    }
    // The extended collimated model's Fluence includes the unscattered beam,
    // which does not leave as diffuse radiance: read phi_d.
    else if (input->GetPointData()->GetArray("CollimatedFluence"))
    {
      std::vector<double> collimated;
      if (vtkTranslucency::ReadPointArray(input, "CollimatedFluence", 3, collimated, local))
      {
        for (std::size_t k = 0; k < fluence.size(); ++k)
        {
          fluence[k] -= collimated[k];
        }
      }
    }
  }
  // An sp3 solve: the P3 radiance of its moments (SP3Phi1, SP3Phi2).
  std::vector<double> phi1, phi2;
  bool sp3 = false;
  if (local.empty() && numPoints > 0)
  {
    sp3 = ReadSp3Moments(input, phi1, phi2, local);
  }
  translucency::Sp3BoundaryCoefficients sp3Coefficients;
  double sp3Eta = -1.0;
  // Radiance (TransCut eq. 3) at every local point on the physical boundary,
  // with the serial normal and eta (summed over every rank's faces).
  std::vector<double> values(3 * static_cast<size_t>(numPoints), 0.0);
  double extremes[8] = { 0.0, 0.0, -VTK_DOUBLE_MAX, -VTK_DOUBLE_MAX, -VTK_DOUBLE_MAX,
    -VTK_DOUBLE_MAX, -VTK_DOUBLE_MAX, -VTK_DOUBLE_MAX }; // max q, max L, -min x, max x, ...
  if (local.empty())
  {
    for (vtkIdType i = 0; i < numPoints; ++i)
    {
      double x[3];
      input->GetPoint(i, x);
      for (int k = 0; k < 3; ++k)
      {
        extremes[2 + 2 * k] = std::max(extremes[2 + 2 * k], -x[k]);
        extremes[3 + 2 * k] = std::max(extremes[3 + 2 * k], x[k]);
      }
      if (!surface.OnBoundary[i])
      {
        continue;
      }
      const double* nrm = &surface.Normals[3 * static_cast<size_t>(i)];
      double cosOut = 1.0;
      if (this->UseViewPoint)
      {
        const double d[3] = { this->ViewPoint[0] - x[0], this->ViewPoint[1] - x[1],
          this->ViewPoint[2] - x[2] };
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        cosOut = len > 0 ? (d[0] * nrm[0] + d[1] * nrm[1] + d[2] * nrm[2]) / len : 0.0;
      }
      if (sp3 && surface.Eta[i] != sp3Eta)
      {
        sp3Eta = surface.Eta[i];
        sp3Coefficients = translucency::Sp3BoundaryCoefficients::Compute(sp3Eta);
      }
      for (int c = 0; c < 3; ++c)
      {
        const size_t k = 3 * static_cast<size_t>(i) + c;
        values[k] = sp3
          ? translucency::Sp3OutgoingRadiance(sp3Coefficients, surface.Eta[i], phi1[k], phi2[k],
              irradiance[k], cosOut, ToReadout(this->RadianceReadout))
          : translucency::OutgoingRadiance(
              fluence[k], irradiance[k], surface.Eta[i], cosOut, ToReadout(this->RadianceReadout));
        extremes[0] = std::max(extremes[0], irradiance[k]);
        extremes[1] = std::max(extremes[1], values[k]);
      }
    }
    try
    {
      translucency::RequireFinite(values, "Radiance", translucency::OverflowCause());
    }
    catch (const translucency::Error& e)
    {
      local = e.what();
    }
  }
  error = comm.AgreeOnError(local);
  if (!error.empty())
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  std::vector<double> reduced(extremes, extremes + 8);
  vtkTranslucencyDistributedRadiance::AllMax(reduced);
  if (reduced[0] > 0.0 && reduced[1] == 0.0 && comm.GetRank() == 0)
  {
    // As the serial path: light enters but no radiance leaves anywhere.
    const double diagonal = std::sqrt((reduced[3] + reduced[2]) * (reduced[3] + reduced[2]) +
      (reduced[5] + reduced[4]) * (reduced[5] + reduced[4]) +
      (reduced[7] + reduced[6]) * (reduced[7] + reduced[6]));
    const double spacing =
      diagonal / std::cbrt(std::max<double>(1.0, static_cast<double>(surface.TotalTets)));
    vtkWarningMacro(<< "Radiance is 0 at every boundary point although light enters (irradiance "
                    << "up to " << reduced[0] << " W/mm^2): the model is "
                    << translucency::FormatNumber(diagonal) << " mm across with tets of about "
                    << translucency::FormatNumber(spacing)
                    << " mm, far coarser than the light's mean free path (~1/sigma_s', about "
                       "1 mm for the measured materials), so the fluence at the surface is "
                       "not resolved: is the model in mm? (else use much smaller tets)");
  }
  // The automatic exposure over every boundary point once (by its owner):
  // the serial percentile.
  if (this->Exposure > 0.0)
  {
    this->ExposureUsed = this->Exposure;
  }
  else
  {
    std::vector<double> owned;
    for (vtkIdType i = 0; i < numPoints; ++i)
    {
      if (surface.OnBoundary[i] && surface.Owned[i])
      {
        owned.insert(owned.end(), values.begin() + 3 * i, values.begin() + 3 * i + 3);
      }
    }
    this->ExposureUsed =
      translucency::AutomaticExposure(vtkTranslucencyDistributedRadiance::AllGather(owned));
  }

  // This rank's faces and their points, in local point order.
  std::vector<vtkIdType> surfaceId(static_cast<size_t>(numPoints), -1);
  for (long long v : surface.Triangles)
  {
    surfaceId[static_cast<size_t>(v)] = 0;
  }
  std::vector<vtkIdType> used;
  for (vtkIdType i = 0; i < numPoints; ++i)
  {
    if (surfaceId[i] == 0)
    {
      surfaceId[i] = static_cast<vtkIdType>(used.size());
      used.push_back(i);
    }
  }
  const vtkIdType n = static_cast<vtkIdType>(used.size());
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  vtkNew<vtkIdTypeArray> originalIds;
  originalIds->SetName(vtkTranslucency::OriginalPointIdsName);
  originalIds->SetNumberOfTuples(n);
  auto makeArray = [n](const char* name, bool rgb) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name);
    a->SetNumberOfComponents(3);
    a->SetNumberOfTuples(n);
    if (rgb)
    {
      vtkTranslucency::SetRGBComponentNames(a);
    }
    return vtkSmartPointer<vtkDoubleArray>(a.GetPointer());
  };
  vtkSmartPointer<vtkDoubleArray> radiance = makeArray(vtkTranslucency::RadianceName, true);
  vtkSmartPointer<vtkDoubleArray> phiOut = makeArray(vtkTranslucency::FluenceName, true);
  vtkSmartPointer<vtkDoubleArray> qOut = makeArray(vtkTranslucency::IrradianceName, true);
  vtkSmartPointer<vtkDoubleArray> normalsOut = makeArray("Normals", false);
  std::vector<double> surfaceValues(3 * static_cast<size_t>(n));
  for (vtkIdType k = 0; k < n; ++k)
  {
    const size_t i = static_cast<size_t>(used[k]);
    double x[3];
    input->GetPoint(used[k], x);
    points->SetPoint(k, x);
    originalIds->SetValue(k, used[k]);
    for (int c = 0; c < 3; ++c)
    {
      surfaceValues[3 * k + c] = values[3 * i + c];
      radiance->SetTypedComponent(k, c, values[3 * i + c]);
      phiOut->SetTypedComponent(k, c, fluence[3 * i + c]);
      qOut->SetTypedComponent(k, c, irradiance[3 * i + c]);
      normalsOut->SetTypedComponent(k, c, surface.Normals[3 * i + c]);
    }
  }
  vtkNew<vtkCellArray> polys;
  polys->AllocateExact(static_cast<vtkIdType>(surface.Triangles.size() / 3),
    static_cast<vtkIdType>(surface.Triangles.size()));
  for (size_t f = 0; f < surface.Triangles.size() / 3; ++f)
  {
    const vtkIdType ids[3] = { surfaceId[surface.Triangles[3 * f]],
      surfaceId[surface.Triangles[3 * f + 1]], surfaceId[surface.Triangles[3 * f + 2]] };
    polys->InsertNextCell(3, ids);
  }
  output->SetPoints(points);
  output->SetPolys(polys);
  output->GetPointData()->AddArray(radiance);
  output->GetPointData()->AddArray(phiOut);
  output->GetPointData()->AddArray(qOut);
  output->GetPointData()->SetNormals(normalsOut);
  output->GetPointData()->AddArray(originalIds);
  AttachDisplayColours(output, surfaceValues, this->ExposureUsed);
  // A point that other ranks hold too has the same values on each; every
  // rank's faces together are the serial surface.
  this->NumberOfSurfaceTriangles = surface.TotalTriangles;
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
void vtkOutgoingRadiance::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "UseViewPoint: " << this->UseViewPoint << "\n";
  os << indent << "RadianceReadout: " << translucency::RadianceReadoutName(ToReadout(this->RadianceReadout))
     << "\n";
  os << indent << "ViewPoint: " << this->ViewPoint[0] << ", " << this->ViewPoint[1] << ", "
     << this->ViewPoint[2] << "\n";
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}
