#include "vtkTranslucentRadiosity.h"

#include "vtkTranslucencyDispatch.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"

#include "Error.h"
#include "LightSources.h"
#include "LinearSolver.h"
#include "RadiosityScene.h"
#include "RadiositySession.h"
#include "TetMesh.h"
#include "TranslucentRadiosity.h"

#include <vtkCellArray.h>
#include <vtkStringArray.h>
#include <vtkCellData.h>
#include <vtkCompositeDataIterator.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationStringKey.h>
#include <vtkInformationVector.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPartitionedDataSetCollection.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include <map>
#include <sstream>

vtkStandardNewMacro(vtkTranslucentRadiosity);

/// One leaf of the input: where it is and its output (the patches).
struct vtkTranslucentRadiosity::Leaf
{
  vtkSmartPointer<vtkCompositeDataIterator> Where;
  vtkSmartPointer<vtkPolyData> Output;
  int Object = -1; ///< index in the radiosity scene
};

struct vtkTranslucentRadiosity::Internals
{
  vtkNew<vtkStringArray> LinearSolverNames; ///< GetAvailableLinearSolvers()'s array
  std::vector<translucency::LightSource> Lights;
  // Scene, form factors and solver (warm starts, cached optical distances),
  // kept while the geometry and the settings are unchanged.
  translucency::RadiositySession Session;
  translucency::RadiosityResult Result;
  // The input of the last successful execution: the composite and every leaf
  // with their modification times. Unchanged (only lights or solver settings
  // changed): the scene is not gathered again.
  std::vector<std::pair<vtkDataObject*, vtkMTimeType>> Signature;
  std::vector<Leaf> Leaves;
};

vtkTranslucentRadiosity::vtkTranslucentRadiosity()
  : Internal(new Internals)
{
}

vtkTranslucentRadiosity::~vtkTranslucentRadiosity() = default;

void vtkTranslucentRadiosity::AddPointLight(double x, double y, double z, double r, double g, double b)
{
  this->Internal->Lights.push_back(translucency::PointLight({ x, y, z }, { r, g, b }));
  this->Modified();
}

void vtkTranslucentRadiosity::AddDirectionalLight(
  double dx, double dy, double dz, double r, double g, double b)
{
  this->Internal->Lights.push_back(translucency::DirectionalLight({ dx, dy, dz }, { r, g, b }));
  this->Modified();
}

void vtkTranslucentRadiosity::AddSpotLight(double x, double y, double z, double dx, double dy,
  double dz, double cutoff, double exponent, double r, double g, double b)
{
  this->Internal->Lights.push_back(
    translucency::SpotLight({ x, y, z }, { dx, dy, dz }, cutoff, exponent, { r, g, b }));
  this->Modified();
}

void vtkTranslucentRadiosity::RemoveAllLights()
{
  if (!this->Internal->Lights.empty())
  {
    this->Internal->Lights.clear();
    this->Modified();
  }
}

int vtkTranslucentRadiosity::GetNumberOfLights() const
{
  return static_cast<int>(this->Internal->Lights.size());
}

int vtkTranslucentRadiosity::GetNumberOfPatches() const
{
  const translucency::RadiosityScene* scene = this->Internal->Session.GetScene();
  return scene ? scene->GetNumberOfPatches() : 0;
}
int vtkTranslucentRadiosity::GetNumberOfIterations() const
{
  return this->Internal->Result.Iterations;
}
bool vtkTranslucentRadiosity::GetConverged() const
{
  return this->Internal->Result.Converged;
}
double vtkTranslucentRadiosity::GetFormFactorTime() const
{
  return this->Internal->Session.GetFormFactorMilliseconds();
}
double vtkTranslucentRadiosity::GetSetupTime() const
{
  return this->Internal->Session.GetSetupMilliseconds();
}
double vtkTranslucentRadiosity::GetDirectTime() const
{
  return this->Internal->Result.DirectMilliseconds;
}
double vtkTranslucentRadiosity::GetSolveTime() const
{
  return this->Internal->Result.SolveMilliseconds;
}
vtkTypeInt64 vtkTranslucentRadiosity::GetFormFactorMemory() const
{
  return static_cast<vtkTypeInt64>(this->Internal->Session.GetFormFactors().MemoryBytes());
}
vtkTypeInt64 vtkTranslucentRadiosity::GetSubsurfaceMemory() const
{
  const translucency::TranslucentRadiosity* solver = this->Internal->Session.GetKeptSolver();
  return solver ? static_cast<vtkTypeInt64>(solver->GetSubsurfaceMemoryBytes()) : 0;
}

int vtkTranslucentRadiosity::FillInputPortInformation(int, vtkInformation* info)
{
  info->Remove(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE());
  info->Append(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPartitionedDataSetCollection");
  info->Append(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkMultiBlockDataSet");
  return 1;
}

int vtkTranslucentRadiosity::RequestDataObject(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0], 0);
  if (!input)
  {
    return 0;
  }
  vtkDataObject* output = vtkDataObject::GetData(outputVector, 0);
  if (!output || !output->IsA(input->GetClassName()))
  {
    vtkSmartPointer<vtkDataObject> newOutput;
    newOutput.TakeReference(input->NewInstance());
    outputVector->GetInformationObject(0)->Set(vtkDataObject::DATA_OBJECT(), newOutput);
  }
  return 1;
}

namespace
{

/// The input's signature: the composite and every leaf with their modification times.
std::vector<std::pair<vtkDataObject*, vtkMTimeType>> InputSignature(vtkCompositeDataSet* input)
{
  std::vector<std::pair<vtkDataObject*, vtkMTimeType>> signature;
  signature.emplace_back(input, input->GetMTime());
  vtkSmartPointer<vtkCompositeDataIterator> it;
  it.TakeReference(input->NewIterator());
  for (it->InitTraversal(); !it->IsDoneWithTraversal(); it->GoToNextItem())
  {
    vtkDataObject* data = it->GetCurrentDataObject();
    signature.emplace_back(data, data ? data->GetMTime() : 0);
  }
  return signature;
}

/// The NAME of each partitioned data set of a collection (a collection's
/// iterator does not carry them), with the partition number when it has several.
std::map<vtkDataObject*, std::string> CollectionNames(vtkCompositeDataSet* input)
{
  std::map<vtkDataObject*, std::string> names;
  auto* pdc = vtkPartitionedDataSetCollection::SafeDownCast(input);
  if (!pdc)
  {
    return names;
  }
  for (unsigned int i = 0; i < pdc->GetNumberOfPartitionedDataSets(); ++i)
  {
    if (!pdc->HasMetaData(i) || !pdc->GetMetaData(i)->Has(vtkCompositeDataSet::NAME()))
    {
      continue;
    }
    const unsigned int parts = pdc->GetNumberOfPartitions(i);
    for (unsigned int j = 0; j < parts; ++j)
    {
      std::string name = pdc->GetMetaData(i)->Get(vtkCompositeDataSet::NAME());
      if (parts > 1)
      {
        name += " " + std::to_string(j);
      }
      names[pdc->GetPartitionAsDataObject(i, j)] = name;
    }
  }
  return names;
}

/// The name of a leaf: the iterator's NAME metadata, else "block <index>".
std::string LeafName(vtkCompositeDataIterator* it, int index)
{
  if (it->HasCurrentMetaData() && it->GetCurrentMetaData()->Has(vtkCompositeDataSet::NAME()))
  {
    return it->GetCurrentMetaData()->Get(vtkCompositeDataSet::NAME());
  }
  return "block " + std::to_string(index);
}

/// The boundary surface of a tet mesh (its patches) with the owner tet of each triangle.
vtkSmartPointer<vtkPolyData> BoundarySurface(const translucency::TetMesh& mesh)
{
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(mesh.GetNumberOfPoints());
  for (int p = 0; p < mesh.GetNumberOfPoints(); ++p)
  {
    points->SetPoint(p, mesh.GetPoint(p));
  }
  surface->SetPoints(points);
  vtkNew<vtkCellArray> polys;
  const std::vector<int>& tris = mesh.GetBoundaryTriangles();
  for (size_t t = 0; t < tris.size(); t += 3)
  {
    const vtkIdType ids[3] = { tris[t], tris[t + 1], tris[t + 2] };
    polys->InsertNextCell(3, ids);
  }
  surface->SetPolys(polys);
  vtkNew<vtkIdTypeArray> owners;
  owners->SetName(vtkTranslucency::OriginalCellIdsName);
  for (int tet : mesh.GetBoundaryTriangleTets())
  {
    owners->InsertNextValue(tet);
  }
  surface->GetCellData()->AddArray(owners);
  return surface;
}

/// A tet mesh with coefficients -> a translucent object; returns its output surface.
vtkSmartPointer<vtkPolyData> AddTranslucentLeaf(translucency::RadiosityScene& scene,
  const std::string& name, vtkUnstructuredGrid* grid, int& object)
{
  std::string error;
  auto mesh = vtkTranslucency::AcquireTetMesh(grid, error);
  if (!mesh)
  {
    throw translucency::Error(name + ": " + error);
  }
  if (!grid->GetCellData()->GetArray(vtkTranslucency::AbsorptionName) &&
    !grid->GetCellData()->GetArray(vtkTranslucency::ScatteringName))
  {
    throw translucency::Error(name + ": translucent object without coefficients (cell arrays " +
      vtkTranslucency::AbsorptionName + ", " + vtkTranslucency::ScatteringName + ", " +
      vtkTranslucency::RefractiveIndexName + ")");
  }
  translucency::OpticalProperties material;
  if (!vtkTranslucency::ToOpticalProperties(grid, material, error))
  {
    throw translucency::Error(name + ": " + error);
  }
  object = scene.AddTranslucent(name, mesh, material);
  return BoundarySurface(*mesh);
}

/// A triangle surface with an Albedo cell array -> an opaque object; returns its output.
vtkSmartPointer<vtkPolyData> AddOpaqueLeaf(
  translucency::RadiosityScene& scene, const std::string& name, vtkPolyData* poly, int& object)
{
  vtkDataArray* albedoArray = poly->GetCellData()->GetArray("Albedo");
  if (!albedoArray || albedoArray->GetNumberOfComponents() != 3)
  {
    throw translucency::Error(name + ": an opaque surface needs the cell array Albedo with 3 "
                                     "components (R, G, B in [0, 1])");
  }
  std::vector<double> points(3 * poly->GetNumberOfPoints());
  for (vtkIdType p = 0; p < poly->GetNumberOfPoints(); ++p)
  {
    poly->GetPoint(p, &points[3 * p]);
  }
  std::vector<int> triangles;
  std::vector<double> albedo;
  for (vtkIdType c = 0; c < poly->GetNumberOfCells(); ++c)
  {
    vtkIdType npts;
    const vtkIdType* pts;
    poly->GetCellPoints(c, npts, pts);
    if (npts != 3 || poly->GetCellType(c) != VTK_TRIANGLE)
    {
      throw translucency::Error(name + ": cell " + std::to_string(c) +
        " is not a triangle (triangulate the surface first)");
    }
    triangles.insert(triangles.end(),
      { static_cast<int>(pts[0]), static_cast<int>(pts[1]), static_cast<int>(pts[2]) });
    for (int k = 0; k < 3; ++k)
    {
      albedo.push_back(albedoArray->GetComponent(c, k));
    }
  }
  object = scene.AddOpaque(name, points, triangles, albedo);
  auto copy = vtkSmartPointer<vtkPolyData>::New();
  copy->ShallowCopy(poly);
  return copy;
}

void AddTriple(vtkPolyData* poly, const char* name, const std::vector<double>& values, int begin,
  int count)
{
  std::vector<double> part(values.begin() + 3 * begin, values.begin() + 3 * (begin + count));
  vtkSmartPointer<vtkDataArray> array;
  array.TakeReference(vtkTranslucency::NewTripleArray(name, part));
  poly->GetCellData()->AddArray(array);
}
} // namespace

//------------------------------------------------------------------------------
bool vtkTranslucentRadiosity::GatherScene(
  vtkCompositeDataSet* input, translucency::RadiosityScene& scene, std::vector<Leaf>& leaves)
{
  const std::map<vtkDataObject*, std::string> names = CollectionNames(input);
  vtkSmartPointer<vtkCompositeDataIterator> it;
  it.TakeReference(input->NewIterator());
  int index = 0;
  for (it->InitTraversal(); !it->IsDoneWithTraversal(); it->GoToNextItem(), ++index)
  {
    vtkDataObject* data = it->GetCurrentDataObject();
    const auto named = names.find(data);
    const std::string name = named != names.end() ? named->second : LeafName(it, index);
    Leaf leaf;
    leaf.Where.TakeReference(input->NewIterator());
    leaf.Where->InitTraversal();
    while (leaf.Where->GetCurrentFlatIndex() != it->GetCurrentFlatIndex())
    {
      leaf.Where->GoToNextItem();
    }
    if (auto* grid = vtkUnstructuredGrid::SafeDownCast(data))
    {
      leaf.Output = AddTranslucentLeaf(scene, name, grid, leaf.Object);
    }
    else if (auto* poly = vtkPolyData::SafeDownCast(data))
    {
      leaf.Output = AddOpaqueLeaf(scene, name, poly, leaf.Object);
    }
    else
    {
      throw translucency::Error(name + ": a " + (data ? data->GetClassName() : "null") +
        " is neither a tet mesh (vtkUnstructuredGrid) nor a surface (vtkPolyData)");
    }
    leaves.push_back(leaf);
    if (this->CheckAbort())
    {
      return false;
    }
  }
  scene.Build(false); // the BVH only if the geometry changed (RadiositySession)
  return true;
}

//------------------------------------------------------------------------------
std::vector<translucency::LightSource> vtkTranslucentRadiosity::GetLights() const
{
  std::vector<translucency::LightSource> lights = this->Internal->Lights;
  if (lights.empty())
  {
    translucency::LightSource light;
    light.Type = this->LightType == 1 ? translucency::LightSource::Kind::Directional
      : this->LightType == 2          ? translucency::LightSource::Kind::Spot
                                      : translucency::LightSource::Kind::Point;
    light.Position = { this->LightPosition[0], this->LightPosition[1], this->LightPosition[2] };
    light.Direction = { this->LightDirection[0], this->LightDirection[1], this->LightDirection[2] };
    light.Power = { this->LightPower[0], this->LightPower[1], this->LightPower[2] };
    light.SpotCutoff = this->LightCutoff;
    lights.push_back(light);
  }
  return lights;
}

//------------------------------------------------------------------------------
translucency::TranslucentRadiosity& vtkTranslucentRadiosity::Solve()
{
  Internals& in = *this->Internal;
  translucency::SubsurfaceSettings settings;
  settings.Method = this->SubsurfaceMethod == SUBSURFACE_PROFILE ? "profile" : "diffusion";
  settings.VoxelSize = this->VoxelSize;
  settings.MaxDistance = this->MaxDistance;
  settings.LinearSolver = this->LinearSolver;
  translucency::TranslucentRadiosity& solver = in.Session.GetSolver(settings);
  solver.SetRelTol(this->RelTol);
  solver.SetMaxIter(this->MaxIter);
  solver.SetShadows(this->Shadows);
  solver.SetIteration(this->Iteration == ITERATION_JACOBI
      ? translucency::TranslucentRadiosity::Iteration::Jacobi
      : translucency::TranslucentRadiosity::Iteration::GaussSeidel);
  solver.Solve(this->GetLights(), in.Result);
  if (!in.Result.Converged)
  {
    vtkWarningMacro(<< "radiosity did not converge in " << in.Result.Iterations
                    << " iterations (last relative change "
                    << (in.Result.ResidualHistory.empty() ? 0.0 : in.Result.ResidualHistory.back())
                    << ", RelTol " << this->RelTol << ")");
  }
  return solver;
}

//------------------------------------------------------------------------------
void vtkTranslucentRadiosity::AttachOutputs(vtkCompositeDataSet* output,
  const std::vector<Leaf>& leaves, const std::vector<double>& h1, const std::vector<double>& h2)
{
  const translucency::RadiosityResult& r = this->Internal->Result;
  const translucency::RadiosityScene& scene = *this->Internal->Session.GetScene();
  for (const Leaf& cached : leaves)
  {
    // A new output object per execution (the cached leaf keeps no arrays).
    Leaf leaf = cached;
    leaf.Output = vtkSmartPointer<vtkPolyData>::New();
    leaf.Output->ShallowCopy(cached.Output);
    const int begin = scene.GetPatchOffset(leaf.Object);
    const int count = scene.GetPatchOffset(leaf.Object + 1) - begin;
    AddTriple(leaf.Output, "DirectIrradiance", r.DirectIrradiance, begin, count);
    AddTriple(leaf.Output, "DirectRadiosity", r.Direct, begin, count);
    AddTriple(leaf.Output, "SubsurfaceRadiosity", r.FirstBounce, begin, count);
    AddTriple(leaf.Output, "InterReflectionRadiosity", r.InterReflection, begin, count);
    AddTriple(leaf.Output, "Radiosity", r.Combined, begin, count);
    if (this->ComputeHeuristics)
    {
      AddTriple(leaf.Output, "HeuristicRadiosity1", h1, begin, count);
      AddTriple(leaf.Output, "HeuristicRadiosity2", h2, begin, count);
    }
    output->SetDataSet(leaf.Where, leaf.Output);
  }
}

//------------------------------------------------------------------------------
vtkStringArray* vtkTranslucentRadiosity::GetAvailableLinearSolvers()
{
  vtkStringArray* names = this->Internal->LinearSolverNames;
  names->Initialize();
  for (const std::string& name : translucency::GetLinearSolverNames())
  {
    names->InsertNextValue(name);
  }
  return names;
}

//------------------------------------------------------------------------------
int vtkTranslucentRadiosity::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
int vtkTranslucentRadiosity::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::UpdateExtent(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkTranslucentRadiosity::PlanParallel(
  vtkInformationVector**, const vtkTranslucencyCommunicator&)
{
  return vtkTranslucencyParallelPlan::Gathered(
    vtkTranslucencyParallelPlan::GatherMode::RankZero, "the form factors need the whole scene");
}

//------------------------------------------------------------------------------
int vtkTranslucentRadiosity::RequestSerial(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  auto* input = vtkCompositeDataSet::GetData(inputVector[0], 0);
  auto* output = vtkCompositeDataSet::GetData(outputVector, 0);
  if (!input || !output)
  {
    vtkErrorMacro(<< "input and output must be composite data sets");
    return 0;
  }
  Internals& in = *this->Internal;
  try
  {
    translucency::CreateLinearSolver(this->LinearSolver); // a bad name fails before the work
    output->CopyStructure(input);
    translucency::RadiositySession& session = in.Session;
    session.ResetTimes();
    session.SetRaysPerPatch(this->RaysPerPatch);
    session.SetFormFactorThreshold(this->FormFactorThreshold);
    session.SetProgressCallback([this](double f) {
      this->UpdateProgress(0.05 + 0.6 * f);
      return !this->CheckAbort();
    });

    // 1. Leaves -> scene objects, unless only the lights or solver settings changed.
    const auto signature = InputSignature(input);
    const bool sameInput = signature == in.Signature && session.HasValidFormFactors();
    in.Signature.clear(); // set again on success
    if (!sameInput)
    {
      auto scene = std::make_unique<translucency::RadiosityScene>();
      std::vector<Leaf> leaves;
      if (!this->GatherScene(input, *scene, leaves))
      {
        return 1; // aborted
      }
      this->UpdateProgress(0.05);
      // 2. Form factors, kept while the geometry and the ray settings are unchanged.
      if (!session.UpdateScene(std::move(scene)))
      {
        return 1; // aborted
      }
      in.Leaves = leaves;
    }
    this->UpdateProgress(0.65);

    // 3. Solve.
    translucency::TranslucentRadiosity& solver = this->Solve();
    std::vector<double> h1, h2;
    if (this->ComputeHeuristics)
    {
      solver.SolveHeuristics(h1, h2);
    }
    this->UpdateProgress(0.95);

    // 4. Per-patch cell arrays on the output leaves.
    this->AttachOutputs(output, in.Leaves, h1, h2);
    in.Signature = signature;
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  this->UpdateProgress(1.0);
  return outputs.Succeed();
}

void vtkTranslucentRadiosity::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SubsurfaceMethod: "
     << (this->SubsurfaceMethod == SUBSURFACE_PROFILE ? "profile" : "diffusion") << "\n";
  os << indent << "Iteration: "
     << (this->Iteration == ITERATION_JACOBI ? "Jacobi" : "Gauss-Seidel") << "\n";
  os << indent << "RelTol: " << this->RelTol << "\n";
  os << indent << "MaxIter: " << this->MaxIter << "\n";
  os << indent << "RaysPerPatch: " << this->RaysPerPatch << "\n";
  os << indent << "FormFactorThreshold: " << this->FormFactorThreshold << "\n";
  os << indent << "VoxelSize: " << this->VoxelSize << "\n";
  os << indent << "MaxDistance: " << this->MaxDistance << "\n";
  os << indent << "LinearSolver: " << this->LinearSolver << "\n";
  os << indent << "Shadows: " << this->Shadows << "\n";
  os << indent << "ComputeHeuristics: " << this->ComputeHeuristics << "\n";
  os << indent << "Lights: " << this->Internal->Lights.size() << "\n";
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}
