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
#include <vtkWeakPointer.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <sstream>
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

/// Fluence and Irradiance of `input` (3 components per point). The extended
/// collimated model's Fluence includes the unscattered beam, which does not
/// leave as diffuse radiance: with a CollimatedFluence array, phi_d is read.
bool ReadFluenceAndIrradiance(vtkUnstructuredGrid* input, std::vector<double>& fluence,
  std::vector<double>& irradiance, std::string& error)
{
  if (!vtkTranslucency::ReadPointArray(input, vtkTranslucency::FluenceName, 3, fluence, error) ||
    !vtkTranslucency::ReadPointArray(input, vtkTranslucency::IrradianceName, 3, irradiance, error))
  {
    error += " (run vtkSurfaceIrradiance and vtkSolveDiffusion first)";
    return false;
  }
  if (input->GetPointData()->GetArray("CollimatedFluence"))
  {
    std::vector<double> collimated;
    if (!vtkTranslucency::ReadPointArray(input, "CollimatedFluence", 3, collimated, error))
    {
      return false;
    }
    for (std::size_t k = 0; k < fluence.size(); ++k)
    {
      fluence[k] -= collimated[k];
    }
  }
  return true;
}

/// The warning when light enters but no radiance leaves anywhere: eq. 3 went
/// negative (and was clamped to 0) at every point. Seen when the tets are far
/// larger than the transport mean free path (a model in the wrong unit or
/// scaled by 1e6..1e9): the boundary fluence is not resolved. Names the scale.
std::string NoRadianceLeavesWarning(double maxIrradiance, double diagonal, double tets)
{
  const double spacing = diagonal / std::cbrt(std::max(1.0, tets));
  std::ostringstream msg;
  msg << "Radiance is 0 at every boundary point although light enters (irradiance "
      << "up to " << maxIrradiance << " W/mm^2): the model is "
      << translucency::FormatNumber(diagonal) << " mm across with tets of about "
      << translucency::FormatNumber(spacing)
      << " mm, far coarser than the light's mean free path (~1/sigma_s', about "
         "1 mm for the measured materials), so the fluence at the surface is "
         "not resolved: is the model in mm? (else use much smaller tets)";
  return msg.str();
}

/// The Robin rule the solve used (vtkSolveDiffusion writes
/// TranslucencyBoundaryRule = 1 for the Fresnel moments of the
/// "extended-moments" collimated model); absent: eq. 3's fit.
translucency::Fresnel::BoundaryRule BoundaryRuleOf(vtkUnstructuredGrid* input)
{
  vtkDataArray* ruleArray = input->GetFieldData()->GetArray("TranslucencyBoundaryRule");
  return ruleArray && ruleArray->GetNumberOfTuples() > 0 && ruleArray->GetComponent(0, 0) == 1.0
    ? translucency::Fresnel::BoundaryRule::Moments
    : translucency::Fresnel::BoundaryRule::Fit;
}

/// The surface output of both paths: its points, original point ids and the
/// Radiance, Fluence, Irradiance and Normals arrays (n points), filled by the
/// caller, then attached with the triangles by Attach().
struct SurfaceOutput
{
  explicit SurfaceOutput(vtkIdType n)
  {
    this->Points->SetDataTypeToDouble();
    this->Points->SetNumberOfPoints(n);
    this->OriginalIds->SetName(vtkTranslucency::OriginalPointIdsName);
    this->OriginalIds->SetNumberOfTuples(n);
    const char* names[4] = { vtkTranslucency::RadianceName, vtkTranslucency::FluenceName,
      vtkTranslucency::IrradianceName, "Normals" };
    vtkDoubleArray* arrays[4] = { this->Radiance, this->Fluence, this->Irradiance,
      this->Normals };
    for (int a = 0; a < 4; ++a)
    {
      arrays[a]->SetName(names[a]);
      arrays[a]->SetNumberOfComponents(3);
      arrays[a]->SetNumberOfTuples(n);
      if (a < 3)
      {
        vtkTranslucency::SetRGBComponentNames(arrays[a]);
      }
    }
  }

  void Attach(vtkPolyData* output, vtkCellArray* polys)
  {
    output->SetPoints(this->Points);
    output->SetPolys(polys);
    output->GetPointData()->AddArray(this->Radiance);
    output->GetPointData()->AddArray(this->Fluence);
    output->GetPointData()->AddArray(this->Irradiance);
    output->GetPointData()->SetNormals(this->Normals);
    output->GetPointData()->AddArray(this->OriginalIds);
  }

  vtkNew<vtkPoints> Points;
  vtkNew<vtkIdTypeArray> OriginalIds;
  vtkNew<vtkDoubleArray> Radiance;
  vtkNew<vtkDoubleArray> Fluence;
  vtkNew<vtkDoubleArray> Irradiance;
  vtkNew<vtkDoubleArray> Normals;
};

/// The geometry of the serial surface, which depends on the mesh only: the
/// boundary points (compact), their original ids and normals, the boundary
/// triangles. Built once per geometry and shared by the outputs of the
/// following executions (never modified after it is built), so that a
/// relight or a paint stroke rebuilds the three value arrays only.
struct SerialSurfaceGeometry
{
  vtkSmartPointer<vtkPoints> Points;
  vtkSmartPointer<vtkCellArray> Polys;
  vtkSmartPointer<vtkIdTypeArray> OriginalIds;
  vtkSmartPointer<vtkDoubleArray> Normals;

  void Build(const translucency::TetMesh& mesh)
  {
    const std::vector<int>& boundary = mesh.GetBoundaryPoints();
    const vtkIdType n = static_cast<vtkIdType>(boundary.size());
    std::vector<vtkIdType> surfaceId(static_cast<size_t>(mesh.GetNumberOfPoints()), -1);
    this->Points = vtkSmartPointer<vtkPoints>::New();
    this->Points->SetDataTypeToDouble();
    this->Points->SetNumberOfPoints(n);
    this->OriginalIds = vtkSmartPointer<vtkIdTypeArray>::New();
    this->OriginalIds->SetName(vtkTranslucency::OriginalPointIdsName);
    this->OriginalIds->SetNumberOfTuples(n);
    this->Normals = vtkSmartPointer<vtkDoubleArray>::New();
    this->Normals->SetName("Normals");
    this->Normals->SetNumberOfComponents(3);
    this->Normals->SetNumberOfTuples(n);
    const std::vector<double>& normals = mesh.GetPointNormals();
    for (vtkIdType k = 0; k < n; ++k)
    {
      const size_t i = static_cast<size_t>(boundary[k]);
      surfaceId[i] = k;
      this->Points->SetPoint(k, mesh.GetPoint(boundary[k]));
      this->OriginalIds->SetValue(k, boundary[k]);
      for (int c = 0; c < 3; ++c)
      {
        this->Normals->SetTypedComponent(k, c, normals[3 * i + c]);
      }
    }
    const std::vector<int>& tris = mesh.GetBoundaryTriangles();
    this->Polys = vtkSmartPointer<vtkCellArray>::New();
    this->Polys->AllocateExact(
      static_cast<vtkIdType>(tris.size() / 3), static_cast<vtkIdType>(tris.size()));
    for (size_t f = 0; f < tris.size() / 3; ++f)
    {
      const vtkIdType ids[3] = { surfaceId[tris[3 * f]], surfaceId[tris[3 * f + 1]],
        surfaceId[tris[3 * f + 2]] };
      this->Polys->InsertNextCell(3, ids);
    }
  }
};

/// A new point array of 3 components named `name` (R, G, B).
vtkSmartPointer<vtkDoubleArray> NewRGBArray(const char* name, vtkIdType n)
{
  auto array = vtkSmartPointer<vtkDoubleArray>::New();
  array->SetName(name);
  array->SetNumberOfComponents(3);
  array->SetNumberOfTuples(n);
  vtkTranslucency::SetRGBComponentNames(array);
  return array;
}

/// The serial surface: the geometry (built for this mesh) with the radiance
/// `values` (3 per boundary point, in boundary order) and the fluence and
/// irradiance of those points.
void AttachSerialSurface(const translucency::TetMesh& mesh, const SerialSurfaceGeometry& geometry,
  const std::vector<double>& values, const std::vector<double>& fluence,
  const std::vector<double>& irradiance, vtkPolyData* output)
{
  const std::vector<int>& boundary = mesh.GetBoundaryPoints();
  const vtkIdType n = static_cast<vtkIdType>(boundary.size());
  auto radiance = NewRGBArray(vtkTranslucency::RadianceName, n);
  auto surfaceFluence = NewRGBArray(vtkTranslucency::FluenceName, n);
  auto surfaceIrradiance = NewRGBArray(vtkTranslucency::IrradianceName, n);
  vtkSMPTools::For(0, n, [&](vtkIdType begin, vtkIdType end) {
    for (vtkIdType k = begin; k < end; ++k)
    {
      const size_t i = static_cast<size_t>(boundary[k]);
      for (int c = 0; c < 3; ++c)
      {
        radiance->SetTypedComponent(k, c, values[3 * k + c]);
        surfaceFluence->SetTypedComponent(k, c, fluence[3 * i + c]);
        surfaceIrradiance->SetTypedComponent(k, c, irradiance[3 * i + c]);
      }
    }
  });
  output->SetPoints(geometry.Points);
  output->SetPolys(geometry.Polys);
  output->GetPointData()->AddArray(radiance);
  output->GetPointData()->AddArray(surfaceFluence);
  output->GetPointData()->AddArray(surfaceIrradiance);
  output->GetPointData()->SetNormals(geometry.Normals);
  output->GetPointData()->AddArray(geometry.OriginalIds);
}

/// This rank's surface (per piece): its faces and their points, in local
/// point order, with the radiance `values`, fluence and irradiance (3 per
/// local point). Returns the radiance of the surface's points, in its order.
std::vector<double> AttachPieceSurface(vtkUnstructuredGrid* input,
  const vtkTranslucencyDistributedRadiance::Surface& surface, const std::vector<double>& values,
  const std::vector<double>& fluence, const std::vector<double>& irradiance,
  vtkPolyData* output)
{
  const vtkIdType numPoints = input ? input->GetNumberOfPoints() : 0;
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
  SurfaceOutput out(n);
  std::vector<double> surfaceValues(3 * static_cast<size_t>(n));
  for (vtkIdType k = 0; k < n; ++k)
  {
    const size_t i = static_cast<size_t>(used[k]);
    double x[3];
    input->GetPoint(used[k], x);
    out.Points->SetPoint(k, x);
    out.OriginalIds->SetValue(k, used[k]);
    for (int c = 0; c < 3; ++c)
    {
      surfaceValues[3 * k + c] = values[3 * i + c];
      out.Radiance->SetTypedComponent(k, c, values[3 * i + c]);
      out.Fluence->SetTypedComponent(k, c, fluence[3 * i + c]);
      out.Irradiance->SetTypedComponent(k, c, irradiance[3 * i + c]);
      out.Normals->SetTypedComponent(k, c, surface.Normals[3 * i + c]);
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
  out.Attach(output, polys);
  return surfaceValues;
}

/// Radiance (TransCut eq. 3) at every local point of `input` on the physical
/// boundary, with the serial normal and eta of `surface` (summed over every
/// rank's faces); `cosOut` of the view point if `viewPoint` is set, else 1.
/// `extremes`: max q, max L, then -min x, max x, -min y, ... of the points.
/// With `phi1`/`phi2` (an sp3 solve's moments, else null): the outgoing P3
/// radiance of the moments instead.
std::vector<double> PieceRadiance(vtkUnstructuredGrid* input,
  const vtkTranslucencyDistributedRadiance::Surface& surface, const std::vector<double>& fluence,
  const std::vector<double>& irradiance, const double* viewPoint,
  translucency::RadianceReadout readout, translucency::Fresnel::BoundaryRule rule,
  double extremes[8], const std::vector<double>* phi1 = nullptr,
  const std::vector<double>* phi2 = nullptr)
{
  const bool sp3 = phi1 && phi2;
  translucency::Sp3BoundaryCoefficients sp3Coefficients;
  double sp3Eta = -1.0;
  const vtkIdType numPoints = input ? input->GetNumberOfPoints() : 0;
  std::vector<double> values(3 * static_cast<size_t>(numPoints), 0.0);
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
    const double cosOut = translucency::ViewCosine(viewPoint, x, nrm);
    if (sp3 && surface.Eta[i] != sp3Eta)
    {
      sp3Eta = surface.Eta[i];
      sp3Coefficients = translucency::Sp3BoundaryCoefficients::Compute(sp3Eta);
    }
    for (int c = 0; c < 3; ++c)
    {
      const size_t k = 3 * static_cast<size_t>(i) + c;
      values[k] = sp3
        ? translucency::Sp3OutgoingRadiance(sp3Coefficients, surface.Eta[i], (*phi1)[k],
            (*phi2)[k], irradiance[k], cosOut, readout)
        : translucency::OutgoingRadiance(
            fluence[k], irradiance[k], surface.Eta[i], cosOut, readout, rule);
      extremes[0] = std::max(extremes[0], irradiance[k]);
      extremes[1] = std::max(extremes[1], values[k]);
    }
  }
  return values;
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
  /// The serial surface's geometry and the per-point refractive index, kept
  /// for the mesh (object and geometry revision) they were built for; the
  /// index also for the RefractiveIndex array (object and MTime) read.
  std::weak_ptr<const translucency::TetMesh> SurfaceMesh, EtaMesh;
  std::uint64_t SurfaceRevision = 0, EtaRevision = 0;
  SerialSurfaceGeometry Surface;
  vtkWeakPointer<vtkDataArray> EtaArray;
  vtkMTimeType EtaTime = 0;
  std::vector<double> PointEta;
  /// The per-piece path's physical boundary, kept while every rank's piece
  /// is the same (issue 32).
  vtkTranslucencyDistributedRadiance::SurfaceCache PieceSurface;

  const SerialSurfaceGeometry& SurfaceOf(const std::shared_ptr<const translucency::TetMesh>& mesh)
  {
    if (this->SurfaceMesh.lock() != mesh || this->SurfaceRevision != mesh->GetGeometryRevision() ||
      !this->Surface.Points)
    {
      this->Surface.Build(*mesh);
      this->SurfaceMesh = mesh;
      this->SurfaceRevision = mesh->GetGeometryRevision();
    }
    return this->Surface;
  }

  /// PointRefractiveIndex of the input's RefractiveIndex, recomputed when
  /// the mesh or the array changed; false (and `error`) if it cannot be read.
  bool PointEtaOf(const std::shared_ptr<const translucency::TetMesh>& mesh,
    vtkUnstructuredGrid* input, std::string& error)
  {
    vtkDataArray* eta = input->GetCellData()->GetArray(vtkTranslucency::RefractiveIndexName);
    if (eta && this->EtaMesh.lock() == mesh && this->EtaRevision == mesh->GetGeometryRevision() &&
      this->EtaArray == eta && this->EtaTime == eta->GetMTime() && !this->PointEta.empty())
    {
      return true;
    }
    this->PointEta.clear();
    this->EtaArray = nullptr;
    std::vector<double> tetEta;
    if (!vtkTranslucency::ReadRefractiveIndex(input, tetEta, error))
    {
      return false;
    }
    this->PointEta = translucency::PointRefractiveIndex(*mesh, tetEta);
    this->EtaMesh = mesh;
    this->EtaRevision = mesh->GetGeometryRevision();
    this->EtaArray = eta;
    this->EtaTime = eta ? eta->GetMTime() : 0;
    return true;
  }
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
  return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector,
    [this](vtkInformationVector** i, vtkInformationVector* o, const vtkTranslucencyCommunicator& c)
    { return this->RequestPerPiece(i, o, c); });
}

//------------------------------------------------------------------------------
int vtkOutgoingRadiance::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::UpdateExtent(this, request, inputVector, outputVector);
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
  // 1. The mesh and the arrays read.
  std::string error;
  this->Internal->Mesh = vtkTranslucency::AcquireTetMesh(input, error);
  if (!this->Internal->Mesh)
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const translucency::TetMesh& mesh = *this->Internal->Mesh;
  std::vector<double> fluence, irradiance;
  if (!ReadFluenceAndIrradiance(input, fluence, irradiance, error) ||
    !this->Internal->PointEtaOf(this->Internal->Mesh, input, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const std::vector<double>& pointEta = this->Internal->PointEta;
  // 2. Radiance at the boundary points (TransCut eq. 3), OpenMP-parallel in the core.
  std::vector<double> values;
  try
  {
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
        this->UseViewPoint ? this->ViewPoint : nullptr, ToReadout(this->RadianceReadout),
        BoundaryRuleOf(input));
    }
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  // 3. Light enters but no radiance leaves anywhere: say why.
  double maxIrradiance = 0.0, maxRadiance = 0.0;
  for (int i : mesh.GetBoundaryPoints())
    for (int c = 0; c < 3; ++c)
      maxIrradiance = std::max(maxIrradiance, irradiance[3 * static_cast<size_t>(i) + c]);
  for (double v : values)
    maxRadiance = std::max(maxRadiance, v);
  if (maxIrradiance > 0.0 && maxRadiance == 0.0)
  {
    vtkWarningMacro(<< NoRadianceLeavesWarning(maxIrradiance, input->GetLength(),
                      static_cast<double>(mesh.GetNumberOfTets())));
  }
  // 4. The compact surface (boundary points only) and the display colours
  // (the CLI's PNG mapping: Map Scalars off in ParaView).
  AttachSerialSurface(
    mesh, this->Internal->SurfaceOf(this->Internal->Mesh), values, fluence, irradiance, output);
  this->ExposureUsed =
    this->Exposure > 0.0 ? this->Exposure : translucency::AutomaticExposure(values);
  AttachDisplayColours(output, values, this->ExposureUsed);
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
  // 1. The piece's physical boundary (collective) and its arrays.
  const vtkTranslucencyDistributedRadiance::Surface* found = nullptr;
  std::string error;
  if (!this->Internal->PieceSurface.Find(input, found, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const vtkTranslucencyDistributedRadiance::Surface& surface = *found;
  const vtkIdType numPoints = input ? input->GetNumberOfPoints() : 0;
  std::vector<double> fluence, irradiance;
  std::string local;
  if (numPoints > 0)
  {
    ReadFluenceAndIrradiance(input, fluence, irradiance, local);
  }
  // An sp3 solve: the P3 radiance of its moments (SP3Phi1, SP3Phi2).
  std::vector<double> phi1, phi2;
  bool sp3 = false;
  if (local.empty() && numPoints > 0)
  {
    sp3 = ReadSp3Moments(input, phi1, phi2, local);
  }
  // 2. Radiance (TransCut eq. 3) at every local point on the physical boundary.
  std::vector<double> values(3 * static_cast<size_t>(numPoints), 0.0);
  double extremes[8] = { 0.0, 0.0, -VTK_DOUBLE_MAX, -VTK_DOUBLE_MAX, -VTK_DOUBLE_MAX,
    -VTK_DOUBLE_MAX, -VTK_DOUBLE_MAX, -VTK_DOUBLE_MAX }; // max q, max L, -min x, max x, ...
  if (local.empty())
  {
    // The solve's Robin rule, as the serial path (the Fresnel moments after
    // an extended-moments solve: the same field data on every rank).
    values = PieceRadiance(input, surface, fluence, irradiance,
      this->UseViewPoint ? this->ViewPoint : nullptr, ToReadout(this->RadianceReadout),
      BoundaryRuleOf(input), extremes, sp3 ? &phi1 : nullptr, sp3 ? &phi2 : nullptr);
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
  // 3. As the serial path: light enters but no radiance leaves anywhere.
  std::vector<double> reduced(extremes, extremes + 8);
  vtkTranslucencyDistributedRadiance::AllMax(reduced);
  if (reduced[0] > 0.0 && reduced[1] == 0.0 && comm.GetRank() == 0)
  {
    const double diagonal = std::sqrt((reduced[3] + reduced[2]) * (reduced[3] + reduced[2]) +
      (reduced[5] + reduced[4]) * (reduced[5] + reduced[4]) +
      (reduced[7] + reduced[6]) * (reduced[7] + reduced[6]));
    vtkWarningMacro(<< NoRadianceLeavesWarning(
                      reduced[0], diagonal, static_cast<double>(surface.TotalTets)));
  }
  // 4. The automatic exposure over every boundary point once (by its owner):
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
  // 5. This rank's faces and their points. A point that other ranks hold
  // too has the same values on each; every rank's faces together are the
  // serial surface.
  const std::vector<double> surfaceValues =
    AttachPieceSurface(input, surface, values, fluence, irradiance, output);
  AttachDisplayColours(output, surfaceValues, this->ExposureUsed);
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
