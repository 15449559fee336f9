#include "vtkTranslucentRadiosity.h"

#include "vtkTranslucencyMeshConversion.h"

#include "Error.h"
#include "FormFactors.h"
#include "LinearSolver.h"
#include "RadiosityScene.h"
#include "TetMesh.h"
#include "TranslucentRadiosity.h"

#include <vtkCellArray.h>
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

#include <chrono>
#include <map>
#include <sstream>

vtkStandardNewMacro(vtkTranslucentRadiosity);

namespace
{
double MillisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
    .count();
}

/// One leaf of the input: what it is and where its patches go.
struct Leaf
{
  vtkSmartPointer<vtkCompositeDataIterator> Where;
  vtkSmartPointer<vtkPolyData> Output;
  int Object = -1;
};

bool SameMaterial(const translucency::OpticalProperties& a, const translucency::OpticalProperties& b)
{
  return a.AbsorptionCoefficient == b.AbsorptionCoefficient &&
    a.ReducedScatteringCoefficient == b.ReducedScatteringCoefficient &&
    a.RefractiveIndex == b.RefractiveIndex;
}
}

struct vtkTranslucentRadiosity::Internals
{
  std::vector<translucency::LightSource> Lights;
  // Kept while the geometry is unchanged: scene, form factors, solver (warm
  // starts, cached optical distances).
  std::unique_ptr<translucency::RadiosityScene> Scene;
  translucency::FormFactorMatrix F;
  std::unique_ptr<translucency::TranslucentRadiosity> Solver;
  std::vector<double> Points;
  std::vector<int> Triangles;
  int Rays = -1;
  double Threshold = -1.0;
  int Method = -1;
  std::string LinearSolver;
  double VoxelSize = -1.0, MaxDistance = -1.0;
  translucency::RadiosityResult Result;
  double FormFactorTime = 0.0, SetupTime = 0.0;
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
  translucency::LightSource light;
  light.Type = translucency::LightSource::Kind::Point;
  light.Position = { x, y, z };
  light.Power = { r, g, b };
  this->Internal->Lights.push_back(light);
  this->Modified();
}

void vtkTranslucentRadiosity::AddDirectionalLight(
  double dx, double dy, double dz, double r, double g, double b)
{
  translucency::LightSource light;
  light.Type = translucency::LightSource::Kind::Directional;
  light.Direction = { dx, dy, dz };
  light.Power = { r, g, b };
  this->Internal->Lights.push_back(light);
  this->Modified();
}

void vtkTranslucentRadiosity::AddSpotLight(double x, double y, double z, double dx, double dy,
  double dz, double cutoff, double exponent, double r, double g, double b)
{
  translucency::LightSource light;
  light.Type = translucency::LightSource::Kind::Spot;
  light.Position = { x, y, z };
  light.Direction = { dx, dy, dz };
  light.SpotCutoff = cutoff;
  light.SpotExponent = exponent;
  light.Power = { r, g, b };
  this->Internal->Lights.push_back(light);
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
  return this->Internal->Scene ? this->Internal->Scene->GetNumberOfPatches() : 0;
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
  return this->Internal->FormFactorTime;
}
double vtkTranslucentRadiosity::GetSetupTime() const
{
  return this->Internal->SetupTime;
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
  return static_cast<vtkTypeInt64>(this->Internal->F.MemoryBytes());
}
vtkTypeInt64 vtkTranslucentRadiosity::GetSubsurfaceMemory() const
{
  return this->Internal->Solver
    ? static_cast<vtkTypeInt64>(this->Internal->Solver->GetSubsurfaceMemoryBytes())
    : 0;
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

std::string LeafName(vtkCompositeDataIterator* it, int index)
{
  if (it->HasCurrentMetaData() && it->GetCurrentMetaData()->Has(vtkCompositeDataSet::NAME()))
  {
    return it->GetCurrentMetaData()->Get(vtkCompositeDataSet::NAME());
  }
  return "block " + std::to_string(index);
}

void AddTriple(vtkPolyData* poly, const char* name, const std::vector<double>& values, int begin,
  int count)
{
  std::vector<double> part(values.begin() + 3 * begin, values.begin() + 3 * (begin + count));
  vtkSmartPointer<vtkDataArray> array;
  array.TakeReference(vtkTranslucency::NewTripleArray(name, part));
  poly->GetCellData()->AddArray(array);
}
}

int vtkTranslucentRadiosity::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
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
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  output->CopyStructure(input);
  in.FormFactorTime = 0.0;
  in.SetupTime = 0.0;

  // The input's signature: is anything but the lights and settings new?
  std::vector<std::pair<vtkDataObject*, vtkMTimeType>> signature;
  signature.emplace_back(input, input->GetMTime());
  {
    vtkSmartPointer<vtkCompositeDataIterator> leafIt;
    leafIt.TakeReference(input->NewIterator());
    for (leafIt->InitTraversal(); !leafIt->IsDoneWithTraversal(); leafIt->GoToNextItem())
    {
      vtkDataObject* data = leafIt->GetCurrentDataObject();
      signature.emplace_back(data, data ? data->GetMTime() : 0);
    }
  }
  const bool sameInput = in.Scene && signature == in.Signature &&
    in.Rays == this->RaysPerPatch && in.Threshold == this->FormFactorThreshold;
  in.Signature.clear(); // set again on success
  std::vector<Leaf> leaves;
  if (sameInput)
  {
    leaves = in.Leaves;
  }
  else
  {
    // 1. Leaves -> scene objects.
    auto scene = std::make_unique<translucency::RadiosityScene>();
    std::vector<translucency::OpticalProperties> materials;
    std::vector<std::vector<double>> albedos;
    // Names: the NAME of each partitioned data set of a collection (a
    // collection's iterator does not carry them), else the iterator's metadata.
    std::map<vtkDataObject*, std::string> names;
    if (auto* pdc = vtkPartitionedDataSetCollection::SafeDownCast(input))
    {
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
    }
    vtkSmartPointer<vtkCompositeDataIterator> it;
    it.TakeReference(input->NewIterator());
    int index = 0;
    try
    {
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
          std::string error;
          auto mesh = vtkTranslucency::AcquireTetMesh(grid, error);
          if (!mesh)
          {
            vtkErrorMacro(<< name << ": " << error);
            return 0;
          }
          translucency::OpticalProperties material;
          if (!grid->GetCellData()->GetArray(vtkTranslucency::AbsorptionName) &&
            !grid->GetCellData()->GetArray(vtkTranslucency::ScatteringName))
          {
            vtkErrorMacro(<< name << ": translucent object without coefficients (cell arrays "
                          << vtkTranslucency::AbsorptionName << ", "
                          << vtkTranslucency::ScatteringName << ", "
                          << vtkTranslucency::RefractiveIndexName << ")");
            return 0;
          }
          if (!vtkTranslucency::ToOpticalProperties(grid, material, error))
          {
            vtkErrorMacro(<< name << ": " << error);
            return 0;
          }
          leaf.Object = scene->AddTranslucent(name, mesh, material);
          materials.push_back(material);
          albedos.emplace_back();
          // Output: the boundary surface (the patches).
          vtkNew<vtkPolyData> surface;
          vtkNew<vtkPoints> points;
          points->SetDataTypeToDouble();
          points->SetNumberOfPoints(mesh->GetNumberOfPoints());
          for (int p = 0; p < mesh->GetNumberOfPoints(); ++p)
          {
            points->SetPoint(p, mesh->GetPoint(p));
          }
          surface->SetPoints(points);
          vtkNew<vtkCellArray> polys;
          const std::vector<int>& tris = mesh->GetBoundaryTriangles();
          for (size_t t = 0; t < tris.size(); t += 3)
          {
            const vtkIdType ids[3] = { tris[t], tris[t + 1], tris[t + 2] };
            polys->InsertNextCell(3, ids);
          }
          surface->SetPolys(polys);
          vtkNew<vtkIdTypeArray> owners;
          owners->SetName(vtkTranslucency::OriginalCellIdsName);
          for (int tet : mesh->GetBoundaryTriangleTets())
          {
            owners->InsertNextValue(tet);
          }
          surface->GetCellData()->AddArray(owners);
          leaf.Output = surface;
        }
        else if (auto* poly = vtkPolyData::SafeDownCast(data))
        {
          vtkDataArray* albedoArray = poly->GetCellData()->GetArray("Albedo");
          if (!albedoArray || albedoArray->GetNumberOfComponents() != 3)
          {
            vtkErrorMacro(<< name << ": an opaque surface needs the cell array Albedo with 3 "
                                     "components (R, G, B in [0, 1])");
            return 0;
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
              vtkErrorMacro(<< name << ": cell " << c
                            << " is not a triangle (triangulate the surface first)");
              return 0;
            }
            triangles.insert(triangles.end(), { static_cast<int>(pts[0]), static_cast<int>(pts[1]),
                                                static_cast<int>(pts[2]) });
            for (int k = 0; k < 3; ++k)
            {
              albedo.push_back(albedoArray->GetComponent(c, k));
            }
          }
          albedos.push_back(albedo);
          materials.emplace_back();
          leaf.Object = scene->AddOpaque(name, points, triangles, albedo);
          vtkNew<vtkPolyData> copy;
          copy->ShallowCopy(poly);
          leaf.Output = copy;
        }
        else
        {
          vtkErrorMacro(<< name << ": a " << (data ? data->GetClassName() : "null")
                        << " is neither a tet mesh (vtkUnstructuredGrid) nor a surface "
                           "(vtkPolyData)");
          return 0;
        }
        leaves.push_back(leaf);
        if (this->CheckAbort())
        {
          return 1;
        }
      }
      scene->Build(false); // the BVH only if the geometry changed (below)
    }
    catch (const translucency::Error& e)
    {
      vtkErrorMacro(<< e.what());
      return 0;
    }
    this->UpdateProgress(0.05);

    // 2. Form factors, kept while the geometry and the ray settings are unchanged.
    const bool sameGeometry = in.Scene && in.Points == scene->GetPoints() &&
      in.Triangles == scene->GetTriangles() && in.Rays == this->RaysPerPatch &&
      in.Threshold == this->FormFactorThreshold;
    try
    {
      if (!sameGeometry)
      {
        scene->BuildRayCaster();
        translucency::FormFactorComputer computer;
        computer.SetRaysPerPatch(this->RaysPerPatch);
        computer.SetThreshold(this->FormFactorThreshold);
        computer.SetProgressCallback([this](double f) {
          this->UpdateProgress(0.05 + 0.6 * f);
          return !this->CheckAbort();
        });
        auto start = std::chrono::steady_clock::now();
        if (!computer.Compute(*scene, in.F))
        {
          in.Scene.reset();
          return 1; // aborted
        }
        in.FormFactorTime = MillisecondsSince(start);
        in.Points = scene->GetPoints();
        in.Triangles = scene->GetTriangles();
        in.Rays = this->RaysPerPatch;
        in.Threshold = this->FormFactorThreshold;
        in.Scene = std::move(scene);
        in.Solver.reset();
      }
      else
      {
        // Same geometry: update albedos and materials in the kept scene.
        for (int k = 0; k < in.Scene->GetNumberOfObjects(); ++k)
        {
          const auto& object = in.Scene->GetObject(k);
          if (!object.Translucent && object.Albedo != albedos[k])
          {
            in.Scene->SetAlbedo(k, albedos[k]);
          }
          else if (object.Translucent && !SameMaterial(object.Material, materials[k]))
          {
            in.Scene->SetMaterial(k, materials[k]);
            if (in.Solver)
            {
              auto start = std::chrono::steady_clock::now();
              in.Solver->UpdateMaterial(k);
              in.SetupTime += MillisecondsSince(start);
            }
          }
        }
      }
    }
    catch (const translucency::Error& e)
    {
      vtkErrorMacro(<< e.what());
      return 0;
    }
    in.Leaves = leaves;
  }
  try
  {
    this->UpdateProgress(0.65);

    // 3. Solve.
    if (!in.Solver || in.Method != this->SubsurfaceMethod || in.VoxelSize != this->VoxelSize ||
      in.MaxDistance != this->MaxDistance || in.LinearSolver != this->LinearSolver)
    {
      in.Solver = std::make_unique<translucency::TranslucentRadiosity>();
      in.Solver->SetScene(in.Scene.get());
      in.Solver->SetFormFactors(&in.F);
      in.Solver->SetSubsurfaceMethod(
        this->SubsurfaceMethod == SUBSURFACE_PROFILE ? "profile" : "diffusion");
      in.Solver->SetVoxelSize(this->VoxelSize);
      in.Solver->SetLinearSolver(this->LinearSolver);
      in.Solver->SetMaxDistance(this->MaxDistance);
      auto start = std::chrono::steady_clock::now();
      in.Solver->Setup();
      in.SetupTime += MillisecondsSince(start);
      in.Method = this->SubsurfaceMethod;
      in.VoxelSize = this->VoxelSize;
      in.MaxDistance = this->MaxDistance;
      in.LinearSolver = this->LinearSolver;
    }
    in.Solver->SetRelTol(this->RelTol);
    in.Solver->SetMaxIter(this->MaxIter);
    in.Solver->SetShadows(this->Shadows);
    in.Solver->SetIteration(this->Iteration == ITERATION_JACOBI
        ? translucency::TranslucentRadiosity::Iteration::Jacobi
        : translucency::TranslucentRadiosity::Iteration::GaussSeidel);
    std::vector<translucency::LightSource> lights = in.Lights;
    if (lights.empty())
    {
      translucency::LightSource light;
      light.Type = this->LightType == 1 ? translucency::LightSource::Kind::Directional
        : this->LightType == 2          ? translucency::LightSource::Kind::Spot
                                        : translucency::LightSource::Kind::Point;
      light.Position = { this->LightPosition[0], this->LightPosition[1], this->LightPosition[2] };
      light.Direction = { this->LightDirection[0], this->LightDirection[1],
        this->LightDirection[2] };
      light.Power = { this->LightPower[0], this->LightPower[1], this->LightPower[2] };
      light.SpotCutoff = this->LightCutoff;
      lights.push_back(light);
    }
    in.Solver->Solve(lights, in.Result);
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  if (!in.Result.Converged)
  {
    vtkWarningMacro(<< "radiosity did not converge in " << in.Result.Iterations
                    << " iterations (last relative change "
                    << (in.Result.ResidualHistory.empty() ? 0.0 : in.Result.ResidualHistory.back())
                    << ", RelTol " << this->RelTol << ")");
  }
  std::vector<double> h1, h2;
  if (this->ComputeHeuristics)
  {
    in.Solver->SolveHeuristics(h1, h2);
  }
  this->UpdateProgress(0.95);

  // 4. Per-patch cell arrays on the output leaves.
  const translucency::RadiosityResult& r = in.Result;
  for (const Leaf& cached : leaves)
  {
    // A new output object per execution (the cached leaf keeps no arrays).
    Leaf leaf = cached;
    leaf.Output = vtkSmartPointer<vtkPolyData>::New();
    leaf.Output->ShallowCopy(cached.Output);
    const int begin = in.Scene->GetPatchOffset(leaf.Object);
    const int count = in.Scene->GetPatchOffset(leaf.Object + 1) - begin;
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
  in.Signature = signature;
  this->UpdateProgress(1.0);
  return 1;
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
}
