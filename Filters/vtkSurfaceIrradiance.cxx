#include "vtkSurfaceIrradiance.h"

#include "DefaultLights.h"
#include "Error.h"
#include "CollimatedModels.h"
#include "CollimatedSource.h"
#include "IrradianceCache.h"
#include "LightSources.h"
#include "Radiance.h"
#include "Strings.h"
#include "TetMesh.h"
#include "Timer.h"
#include "vtkTranslucencyDistributedIrradiance.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"
#include "vtkTranslucencyDispatch.h"
#include "vtkTranslucencyMPI.h"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkStringArray.h>
#include <vtkUnstructuredGrid.h>

#include <array>
#include <cmath>
#include <sstream>
#include <vector>

vtkStandardNewMacro(vtkSurfaceIrradiance);

struct vtkSurfaceIrradiance::Internals
{
  std::vector<translucency::LightSource> Directional;
  std::vector<translucency::LightSource> Point;
  std::vector<translucency::LightSource> Spot;
  /// The panel's coloured tables (cleared on their own).
  std::vector<translucency::LightSource> ColouredDirectional;
  std::vector<translucency::LightSource> ColouredPoint;
  std::shared_ptr<const translucency::TetMesh> Mesh;
  /// Each light's term and the uniform light's, kept across executions
  /// (a relight recomputes the changed light only).
  translucency::IrradianceCache Cache;
  /// The distributed path's: the gathered boundary surface and each
  /// light's terms, kept while every rank's piece is the same.
  vtkTranslucencyDistributedIrradiance::State Distributed;
};

//------------------------------------------------------------------------------
vtkSurfaceIrradiance::vtkSurfaceIrradiance()
  : Internal(new Internals)
{
}

//------------------------------------------------------------------------------
vtkSurfaceIrradiance::~vtkSurfaceIrradiance() = default;

//------------------------------------------------------------------------------
void vtkSurfaceIrradiance::AddDirectionalLight(double dx, double dy, double dz, double irradiance)
{
  this->AddDirectionalLightRGB(dx, dy, dz, irradiance, irradiance, irradiance);
}

void vtkSurfaceIrradiance::RemoveAllDirectionalLights()
{
  if (!this->Internal->Directional.empty())
  {
    this->Internal->Directional.clear();
    this->Modified();
  }
}

int vtkSurfaceIrradiance::GetNumberOfDirectionalLights() const
{
  return static_cast<int>(this->Internal->Directional.size());
}

void vtkSurfaceIrradiance::AddPointLight(double x, double y, double z, double intensity)
{
  this->AddPointLightRGB(x, y, z, intensity, intensity, intensity);
}

void vtkSurfaceIrradiance::RemoveAllPointLights()
{
  if (!this->Internal->Point.empty())
  {
    this->Internal->Point.clear();
    this->Modified();
  }
}

int vtkSurfaceIrradiance::GetNumberOfPointLights() const
{
  return static_cast<int>(this->Internal->Point.size());
}

void vtkSurfaceIrradiance::AddDirectionalLightRGB(
  double dx, double dy, double dz, double r, double g, double b)
{
  this->Internal->Directional.push_back(translucency::DirectionalLight({ dx, dy, dz }, { r, g, b }));
  this->Modified();
}

void vtkSurfaceIrradiance::AddPointLightRGB(
  double x, double y, double z, double r, double g, double b)
{
  this->Internal->Point.push_back(translucency::PointLight({ x, y, z }, { r, g, b }));
  this->Modified();
}

void vtkSurfaceIrradiance::AddColouredDirectionalLight(
  double dx, double dy, double dz, double r, double g, double b)
{
  this->Internal->ColouredDirectional.push_back(
    translucency::DirectionalLight({ dx, dy, dz }, { r, g, b }));
  this->Modified();
}

void vtkSurfaceIrradiance::RemoveAllColouredDirectionalLights()
{
  if (!this->Internal->ColouredDirectional.empty())
  {
    this->Internal->ColouredDirectional.clear();
    this->Modified();
  }
}

void vtkSurfaceIrradiance::AddColouredPointLight(
  double x, double y, double z, double r, double g, double b)
{
  this->Internal->ColouredPoint.push_back(translucency::PointLight({ x, y, z }, { r, g, b }));
  this->Modified();
}

void vtkSurfaceIrradiance::RemoveAllColouredPointLights()
{
  if (!this->Internal->ColouredPoint.empty())
  {
    this->Internal->ColouredPoint.clear();
    this->Modified();
  }
}

void vtkSurfaceIrradiance::AddSpotLight(double x, double y, double z, double dx, double dy,
  double dz, double cutoff, double exponent, double r, double g, double b)
{
  this->Internal->Spot.push_back(
    translucency::SpotLight({ x, y, z }, { dx, dy, dz }, cutoff, exponent, { r, g, b }));
  this->Modified();
}

void vtkSurfaceIrradiance::RemoveAllSpotLights()
{
  if (!this->Internal->Spot.empty())
  {
    this->Internal->Spot.clear();
    this->Modified();
  }
}

int vtkSurfaceIrradiance::GetNumberOfSpotLights() const
{
  return static_cast<int>(this->Internal->Spot.size());
}

//------------------------------------------------------------------------------
int vtkSurfaceIrradiance::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector, nullptr,
    [this](vtkInformationVector** i, vtkInformationVector* o, const vtkTranslucencyCommunicator&)
    { return this->RequestLights(i, o, true); });
}

//------------------------------------------------------------------------------
int vtkSurfaceIrradiance::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::UpdateExtent(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkSurfaceIrradiance::PlanParallel(
  vtkInformationVector**, const vtkTranslucencyCommunicator& comm)
{
  using Plan = vtkTranslucencyParallelPlan;
  if (!vtkTranslucency::CanDistribute(comm))
  {
    return Plan::Gathered(Plan::GatherMode::SameMesh,
      "the boundary surface needs the distributed numbering (a build with hypre and VTK's "
      "ParallelMPI)");
  }
  Plan plan = Plan::Distributed(Plan::GatherMode::SameMesh,
    "the physical boundary surface all-gathered (O(N^(2/3))), each rank lights its own points");
  plan.DeprecatedVariable = "TRANSLUCENCY_GATHERED_IRRADIANCE";
  return plan;
}

//------------------------------------------------------------------------------
int vtkSurfaceIrradiance::RequestSerial(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return this->RequestLights(inputVector, outputVector, false);
}

//------------------------------------------------------------------------------
int vtkSurfaceIrradiance::RequestLights(
  vtkInformationVector** inputVector, vtkInformationVector* outputVector, bool distributed)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);

  std::vector<translucency::LightSource> lights = this->Internal->Directional;
  lights.insert(lights.end(), this->Internal->ColouredDirectional.begin(),
    this->Internal->ColouredDirectional.end());
  lights.insert(lights.end(), this->Internal->Point.begin(), this->Internal->Point.end());
  lights.insert(
    lights.end(), this->Internal->ColouredPoint.begin(), this->Internal->ColouredPoint.end());
  lights.insert(lights.end(), this->Internal->Spot.begin(), this->Internal->Spot.end());
  if (this->InteractiveLight)
  {
    const double* p1 = this->InteractiveLightPoint1;
    const double* p2 = this->InteractiveLightPoint2;
    const double power = this->InteractiveLightPower;
    if (this->InteractiveLightType == 0)
    {
      const std::array<double, 3> direction = { p2[0] - p1[0], p2[1] - p1[1], p2[2] - p1[2] };
      if (direction[0] == 0.0 && direction[1] == 0.0 && direction[2] == 0.0)
      {
        vtkErrorMacro(<< "the interactive directional light has no direction: Point1 and Point2"
                      << " are the same point (" << this->InteractiveLightPoint1[0] << ", "
                      << this->InteractiveLightPoint1[1] << ", "
                      << this->InteractiveLightPoint1[2] << "); move one end of the line");
        return 0;
      }
      lights.push_back(translucency::DirectionalLight(direction, { power, power, power }));
    }
    else
    {
      lights.push_back(translucency::PointLight({ p1[0], p1[1], p1[2] }, { power, power, power }));
    }
  }
  // The lights are validated by the core (translucency::ValidateLight).
  double uniformIrradiance = this->UniformLightIrradiance;
  const bool useDefault = this->DefaultLights && lights.empty() && uniformIrradiance == 0.0;
  if (useDefault)
  {
    lights.push_back(translucency::DefaultKeyLight());
    uniformIrradiance = translucency::DefaultUniformIrradiance;
  }
  this->LightsDescription = vtkSurfaceIrradiance::DescribeLights(lights, uniformIrradiance);
  if (useDefault)
  {
    this->LightsDescription += " (the default: add a light to choose)";
  }

  // An explicit extended model leaves the directional lights to the solver;
  // the default keeps them in `Irradiance` (what the surface receives) and
  // vtkSolveDiffusion decides (translucency::DefaultCollimatedModel).
  const bool extended = this->CollimatedModel == COLLIMATED_EXTENDED ||
    this->CollimatedModel == COLLIMATED_EXTENDED_MOMENTS;

  std::string error;
  std::vector<double> q;
  const std::vector<translucency::LightSource>& computed =
    extended ? translucency::NonCollimatedLights(lights) : lights;
  this->LightsComputed = static_cast<int>(computed.size());
  this->UniformComputed = true;
  if (distributed)
  {
    this->TopologyTime = 0.0;
    vtkTranslucencyDistributedIrradiance::Report report;
    if (!vtkTranslucencyDistributedIrradiance::Compute(input, computed, uniformIrradiance,
          this->UniformLightSamples, this->Shadows,
          [this]() { return this->GetAbortExecute() != 0; }, q, report, error,
          &this->Internal->Distributed))
    {
      if (!error.empty())
      {
        vtkErrorMacro(<< error);
      }
      return 0;
    }
    this->LightsComputed = this->Internal->Distributed.GetNumberOfLightsComputed();
    this->UniformComputed = this->Internal->Distributed.GetUniformComputed();
    this->BoundarySurfaceTriangles = report.SurfaceTriangles;
    this->BoundarySurfaceBytes = report.GatheredBytes;
    this->BoundarySurfaceTime = report.GatherMilliseconds;
    return this->AttachOutputs(input, output, lights, uniformIrradiance, q) ? outputs.Succeed()
                                                                          : 0;
  }
  bool built = false;
  const translucency::Timer timer;
  std::string warning;
  this->Internal->Mesh = vtkTranslucency::AcquireTetMesh(input, error, &built, &warning);
  if (!warning.empty())
  {
    vtkWarningMacro(<< warning);
  }
  this->TopologyTime = built
    ? timer.GetMilliseconds()
    : 0.0;
  std::vector<double> tetEta;
  if (!this->Internal->Mesh || !vtkTranslucency::ReadRefractiveIndex(input, tetEta, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const translucency::TetMesh& mesh = *this->Internal->Mesh;
  this->UpdateProgress(0.1);

  // Direct and uniform light with self-shadowing, OpenMP-parallel in the core.
  try
  {
    // Per boundary triangle (each corner with the triangle's own normal),
    // projected to the points: the solvers' loads are triangle-integrated.
    // The extended model leaves the directional lights to the solver.
    // The terms of unchanged lights come from the cache (IrradianceCache.h).
    const bool completed = this->Internal->Cache.Compute(mesh, tetEta, computed,
      uniformIrradiance, this->UniformLightSamples, this->Shadows, q,
      [this]() { return this->GetAbortExecute() != 0; });
    this->LightsComputed = this->Internal->Cache.GetNumberOfLightsComputed();
    this->UniformComputed = this->Internal->Cache.GetUniformComputed();
    if (!completed)
    {
      return 0;
    }
  }
  catch (const translucency::Error& e)
  {
    this->Internal->Cache.Clear();
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return this->AttachOutputs(input, output, lights, uniformIrradiance, q) ? outputs.Succeed() : 0;
}

//------------------------------------------------------------------------------
bool vtkSurfaceIrradiance::AttachOutputs(vtkUnstructuredGrid* input, vtkUnstructuredGrid* output,
  const std::vector<translucency::LightSource>& lights, double uniformIrradiance,
  const std::vector<double>& q)
{
  output->ShallowCopy(input);
  // Record the lights for solvers that launch photons from them (Monte Carlo):
  // kind (0 directional, 1 point), direction or position, power R, G, B.
  vtkNew<vtkFieldData> fieldData;
  fieldData->ShallowCopy(input->GetFieldData());
  vtkNew<vtkDoubleArray> lightArray;
  lightArray->SetName("TranslucencyLights");
  lightArray->SetNumberOfComponents(12);
  for (const auto& light : lights)
  {
    using Kind = translucency::LightSource::Kind;
    const bool directional = light.Type == Kind::Directional;
    const bool spot = light.Type == Kind::Spot;
    const auto& v = directional ? light.Direction : light.Position;
    const double tuple[12] = { directional ? 0.0 : (spot ? 2.0 : 1.0), v[0], v[1], v[2],
      light.Power[0], light.Power[1], light.Power[2], spot ? light.Direction[0] : 0.0,
      spot ? light.Direction[1] : 0.0, spot ? light.Direction[2] : 0.0,
      spot ? light.SpotCutoff : 0.0, spot ? light.SpotExponent : 0.0 };
    lightArray->InsertNextTuple(tuple);
  }
  fieldData->AddArray(lightArray);
  vtkNew<vtkDoubleArray> uniformArray;
  uniformArray->SetName("TranslucencyUniformLight");
  uniformArray->InsertNextValue(uniformIrradiance);
  fieldData->AddArray(uniformArray);
  vtkNew<vtkStringArray> descriptionArray;
  descriptionArray->SetName("TranslucencyLightsDescription");
  descriptionArray->InsertNextValue(this->LightsDescription);
  fieldData->AddArray(descriptionArray);
  vtkNew<vtkDoubleArray> shadowArray;
  shadowArray->SetName("TranslucencyShadows");
  shadowArray->InsertNextValue(this->Shadows ? 1.0 : 0.0);
  fieldData->AddArray(shadowArray);
  vtkNew<vtkDoubleArray> collimatedArray;
  collimatedArray->SetName("TranslucencyCollimatedModel");
  collimatedArray->InsertNextValue(
    this->CollimatedModel == COLLIMATED_DEFAULT ? COLLIMATED_SURFACE : this->CollimatedModel);
  fieldData->AddArray(collimatedArray);
  // The default model is decided by vtkSolveDiffusion, which knows the
  // pencil beams and the solver (the irradiance holds every light).
  vtkNew<vtkIntArray> byDefaultArray;
  byDefaultArray->SetName("TranslucencyCollimatedModelByDefault");
  byDefaultArray->InsertNextValue(this->CollimatedModel == COLLIMATED_DEFAULT ? 1 : 0);
  fieldData->AddArray(byDefaultArray);
  output->SetFieldData(fieldData);
  vtkDataArray* array = vtkTranslucency::NewTripleArray(vtkTranslucency::IrradianceName, q);
  output->GetPointData()->AddArray(array);
  array->Delete();
  this->UpdateProgress(1.0);
  return true;
}

//------------------------------------------------------------------------------
std::string vtkSurfaceIrradiance::DescribeLights(
  const std::vector<translucency::LightSource>& lights, double uniformIrradiance)
{
  std::ostringstream text;
  const char* separator = "";
  for (const auto& light : lights)
  {
    using Kind = translucency::LightSource::Kind;
    const bool directional = light.Type == Kind::Directional;
    const auto& v = directional ? light.Direction : light.Position;
    text << separator
         << (directional ? "directional:" : (light.Type == Kind::Spot ? "spot:" : "point:"))
         << v[0] << "," << v[1] << "," << v[2] << ":";
    if (light.Type == Kind::Spot)
    {
      text << light.Direction[0] << "," << light.Direction[1] << "," << light.Direction[2] << ":"
           << light.SpotCutoff << "," << light.SpotExponent << ":";
    }
    text << light.Power[0];
    if (light.Power[1] != light.Power[0] || light.Power[2] != light.Power[0])
    {
      text << "," << light.Power[1] << "," << light.Power[2];
    }
    separator = " ";
  }
  if (uniformIrradiance > 0.0)
  {
    text << separator << "uniform:" << uniformIrradiance;
    separator = " ";
  }
  return *separator ? text.str() : std::string("none");
}

//------------------------------------------------------------------------------
void vtkSurfaceIrradiance::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "DirectionalLights: " << this->Internal->Directional.size() << "\n";
  os << indent << "PointLights: " << this->Internal->Point.size() << "\n";
  os << indent << "ColouredDirectionalLights: " << this->Internal->ColouredDirectional.size()
     << "\n";
  os << indent << "ColouredPointLights: " << this->Internal->ColouredPoint.size() << "\n";
  os << indent << "SpotLights: " << this->Internal->Spot.size() << "\n";
  os << indent << "UniformLightIrradiance: " << this->UniformLightIrradiance << "\n";
  os << indent << "UniformLightSamples: " << this->UniformLightSamples << "\n";
  os << indent << "DefaultLights: " << this->DefaultLights << "\n";
  os << indent << "InteractiveLight: " << this->InteractiveLight << " (type "
     << this->InteractiveLightType << ", power " << this->InteractiveLightPower << ")\n";
  os << indent << "Shadows: " << this->Shadows << "\n";
  os << indent << "CollimatedModel: "
     << (this->CollimatedModel == COLLIMATED_DEFAULT
            ? std::string("default")
            : GetCollimatedModelName(this->CollimatedModel))
     << "\n";
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}

//------------------------------------------------------------------------------
bool vtkSurfaceIrradiance::SetCollimatedModelByName(const char* name)
{
  const std::string text = name ? name : "";
  if (translucency::ToLower(text) == "default")
  {
    this->SetCollimatedModel(COLLIMATED_DEFAULT);
    return true;
  }
  try
  {
    this->SetCollimatedModel(static_cast<int>(translucency::GetCollimatedModel(text).Model));
    return true;
  }
  catch (const translucency::Error&)
  {
    std::string names = "default";
    for (const translucency::CollimatedModelEntry& entry : translucency::GetCollimatedModelTable())
    {
      names += ", " + entry.Name;
    }
    vtkErrorMacro(<< "unknown collimated model '" << text << "' (known: " << names << ")");
    return false;
  }
}

int vtkSurfaceIrradiance::GetNumberOfCollimatedModels()
{
  return static_cast<int>(translucency::GetCollimatedModelTable().size());
}

std::string vtkSurfaceIrradiance::GetCollimatedModelName(int i)
{
  const auto& table = translucency::GetCollimatedModelTable();
  return i >= 0 && i < static_cast<int>(table.size()) ? table[i].Name : std::string();
}

std::string vtkSurfaceIrradiance::GetCollimatedModelLabel(int i)
{
  const auto& table = translucency::GetCollimatedModelTable();
  return i >= 0 && i < static_cast<int>(table.size()) ? table[i].Label : std::string();
}

std::string vtkSurfaceIrradiance::GetDefaultCollimatedModelName(const char* kind)
{
  const std::string key = translucency::ToLower(kind ? kind : "");
  for (const translucency::CollimatedDefault& row : translucency::GetCollimatedDefaultTable())
  {
    if (row.KindName == key)
    {
      return translucency::GetCollimatedModel(row.Model).Name;
    }
  }
  return std::string();
}

std::string vtkSurfaceIrradiance::DescribeCollimatedDefaults()
{
  return translucency::DescribeCollimatedDefaults();
}
