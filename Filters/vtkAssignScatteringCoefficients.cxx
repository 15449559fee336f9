#include "vtkAssignScatteringCoefficients.h"

#include "vtkTranslucencyDispatch.h"
#include "Error.h"
#include "MaterialFields.h"
#include "vtkMaterialTableReader.h"
#include "vtkTranslucencyDistributedIrradiance.h"
#include "vtkTranslucencyGhosts.h"
#include "vtkTranslucencyMPI.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkGenericCell.h>
#include <vtkGeometryFilter.h>
#include <vtkIdTypeArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPerlinNoise.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStaticCellLocator.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>
#include <sstream>

vtkStandardNewMacro(vtkAssignScatteringCoefficients);

namespace
{
using translucency::MaterialCoefficients;
using translucency::MaterialField;
using translucency::Point3;

/// The centroids (mean of the points) of the cells, mm.
std::vector<Point3> Centroids(vtkUnstructuredGrid* grid)
{
  const vtkIdType n = grid->GetNumberOfCells();
  std::vector<Point3> centroids(static_cast<size_t>(n));
  for (vtkIdType i = 0; i < n; ++i)
  {
    vtkIdType npts;
    const vtkIdType* pts;
    grid->GetCellPoints(i, npts, pts);
    Point3& c = centroids[i];
    c = { 0.0, 0.0, 0.0 };
    for (vtkIdType k = 0; k < npts; ++k)
    {
      double x[3];
      grid->GetPoint(pts[k], x);
      for (int a = 0; a < 3; ++a)
      {
        c[a] += x[a] / static_cast<double>(npts);
      }
    }
  }
  return centroids;
}

/// The material table of the file (none for ""), in the core's types.
translucency::MaterialTable ReadTable(const std::string& fileName)
{
  translucency::MaterialTable table;
  table.FileName = fileName;
  if (fileName.empty())
  {
    return table;
  }
  for (const vtkMaterialTableReader::Material& m :
    vtkMaterialTableReader::ReadMaterialTable(fileName))
  {
    translucency::MaterialTableEntry e;
    e.Id = m.Id;
    e.Name = m.Name;
    std::copy(m.Absorption, m.Absorption + 3, e.Coefficients.Absorption.begin());
    std::copy(m.ReducedScattering, m.ReducedScattering + 3,
      e.Coefficients.ReducedScattering.begin());
    e.Coefficients.RefractiveIndex = m.RefractiveIndex;
    table.Entries.push_back(e);
  }
  return table;
}

/// The first component of a cell or point array, as doubles.
std::vector<double> Component0(vtkDataArray* array)
{
  std::vector<double> values(static_cast<size_t>(array->GetNumberOfTuples()));
  for (vtkIdType i = 0; i < array->GetNumberOfTuples(); ++i)
  {
    values[i] = array->GetComponent(i, 0);
  }
  return values;
}

/// The distance (mm) from each centroid to the closest boundary triangle of the mesh.
bool DepthsBelowSurface(vtkAlgorithm* self, vtkUnstructuredGrid* input,
  const std::vector<Point3>& centroids, vtkPolyData* wholeSurface, std::vector<double>& depths)
{
  // The boundary faces of the mesh, or, for a piece of a distributed mesh,
  // the whole object's (physical) boundary surface.
  vtkNew<vtkGeometryFilter> boundary;
  vtkPolyData* surface = wholeSurface;
  if (!surface)
  {
    boundary->SetInputData(input);
    boundary->Update();
    surface = boundary->GetOutput();
  }
  if (surface->GetNumberOfCells() == 0)
  {
    throw translucency::Error("the mesh has no boundary faces: cannot compute depths");
  }
  vtkNew<vtkStaticCellLocator> locator;
  locator->SetDataSet(surface);
  locator->BuildLocator();
  vtkNew<vtkGenericCell> cell;
  const size_t n = centroids.size();
  depths.resize(n);
  for (size_t i = 0; i < n; ++i)
  {
    if (i % 10000 == 0)
    {
      self->UpdateProgress(static_cast<double>(i) / static_cast<double>(n));
      if (self->GetAbortExecute())
      {
        return false;
      }
    }
    double c[3] = { centroids[i][0], centroids[i][1], centroids[i][2] }, closest[3], dist2;
    vtkIdType cellId;
    int subId;
    locator->FindClosestPoint(c, closest, cell, cellId, subId, dist2);
    depths[i] = std::sqrt(dist2);
  }
  return true;
}

/// VOLUME: a probed array, its name and whether it is a point array.
struct VolumeArray
{
  vtkDataArray* Array = nullptr;
  std::string Name;
  bool OnPoints = false;
};

/// The point array, else the cell array, `name` of the volume with `components` components.
VolumeArray FindVolumeArray(vtkImageData* volume, const std::string& name, int components,
  const char* what)
{
  VolumeArray a;
  a.Name = name;
  a.Array = volume->GetPointData()->GetArray(name.c_str());
  a.OnPoints = a.Array != nullptr;
  if (!a.Array)
  {
    a.Array = volume->GetCellData()->GetArray(name.c_str());
  }
  if (!a.Array)
  {
    throw translucency::Error(std::string("the volume mode needs the point or cell array '") +
      name + "' (" + what + ") on the volume, which it does not have");
  }
  if (a.Array->GetNumberOfComponents() != components)
  {
    std::ostringstream os;
    os << "the volume array '" << name << "' (" << what << ") has "
       << a.Array->GetNumberOfComponents() << " components, not " << components;
    throw translucency::Error(os.str());
  }
  return a;
}

/// The voxel of x: structured coordinates ijk and parametric coordinates pc (throws outside).
void LocateInVolume(vtkImageData* volume, vtkIdType tet, const Point3& c, int ijk[3], double pc[3])
{
  double x[3] = { c[0], c[1], c[2] };
  if (!volume->ComputeStructuredCoordinates(x, ijk, pc))
  {
    double b[6];
    volume->GetBounds(b);
    std::ostringstream os;
    os.precision(17);
    os << "tet " << tet << " has its centroid (" << x[0] << ", " << x[1] << ", " << x[2]
       << ") outside the volume (bounds [" << b[0] << ", " << b[1] << "] x [" << b[2] << ", "
       << b[3] << "] x [" << b[4] << ", " << b[5] << "])";
    throw translucency::Error(os.str());
  }
}

/**
 * Point array: trilinear interpolation; cell array: the voxel's value.
 * (vtkProbeFilter does this too, but interpolates image data in single
 * precision: errors of 1e-7, where this is exact for linear fields.)
 */
void ProbeVolume(vtkImageData* volume, const VolumeArray& a, const int ijk[3], const double pc[3],
  double* value)
{
  const int nc = a.Array->GetNumberOfComponents();
  if (!a.OnPoints)
  {
    const vtkIdType cell = volume->ComputeCellId(const_cast<int*>(ijk));
    for (int c = 0; c < nc; ++c)
    {
      value[c] = a.Array->GetComponent(cell, c);
    }
    return;
  }
  const int* extent = volume->GetExtent();
  std::fill(value, value + nc, 0.0);
  for (int corner = 0; corner < 8; ++corner)
  {
    int p[3];
    double w = 1.0;
    for (int axis = 0; axis < 3; ++axis)
    {
      const int d = (corner >> axis) & 1;
      p[axis] = std::min(ijk[axis] + d, extent[2 * axis + 1]);
      w *= d ? pc[axis] : 1.0 - pc[axis];
    }
    if (w == 0.0)
    {
      continue; // also skips the corners beyond a flat axis
    }
    const vtkIdType id = volume->ComputePointId(p);
    for (int c = 0; c < nc; ++c)
    {
      value[c] += w * a.Array->GetComponent(id, c);
    }
  }
}

/// Point array: the nearest grid point's value; cell array: the voxel's value.
double NearestInVolume(vtkImageData* volume, const VolumeArray& a, const int ijk[3],
  const double pc[3])
{
  if (!a.OnPoints)
  {
    return a.Array->GetComponent(volume->ComputeCellId(const_cast<int*>(ijk)), 0);
  }
  const int* extent = volume->GetExtent();
  int p[3];
  for (int axis = 0; axis < 3; ++axis)
  {
    p[axis] = std::min(ijk[axis] + (pc[axis] >= 0.5 ? 1 : 0), extent[2 * axis + 1]);
  }
  return a.Array->GetComponent(volume->ComputePointId(p), 0);
}

/// The image on `inputs` (the Volume port) spans its whole extent.
bool HasWholeImage(vtkInformationVector* inputs)
{
  vtkInformation* info =
    inputs && inputs->GetNumberOfInformationObjects() > 0 ? inputs->GetInformationObject(0) : nullptr;
  vtkImageData* image = info ? vtkImageData::SafeDownCast(info->Get(vtkDataObject::DATA_OBJECT()))
                             : nullptr;
  if (!image || !info->Has(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()) ||
    image->GetNumberOfPoints() == 0)
  {
    return false;
  }
  int whole[6], extent[6];
  info->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), whole);
  image->GetExtent(extent);
  return std::equal(whole, whole + 6, extent);
}

/// VOLUME: probed coefficients (one palette entry per tet) or table entries by id.
/// `firstTet`: the number errors give the first of `centroids`' tets (0, or
/// a piece's first tet in the whole mesh under MPI).
bool FieldFromVolume(vtkAlgorithm* self, vtkImageData* volume,
  const std::vector<Point3>& centroids, const std::string& absorptionName,
  const std::string& scatteringName, const std::string& idName, double eta,
  const translucency::MaterialTable& table, long long firstTet, MaterialField& field)
{
  if (!volume)
  {
    throw translucency::Error("the volume mode needs a vtkImageData on the second input port "
                              "(SetVolumeConnection or SetVolumeData)");
  }
  const size_t n = centroids.size();
  const bool byId = !idName.empty();
  VolumeArray ids, absorption, scattering;
  if (byId)
  {
    if (table.FileName.empty())
    {
      throw translucency::Error("the volume mode with a material-id array needs a material "
                                "table file (MaterialTableFileName)");
    }
    ids = FindVolumeArray(volume, idName, 1, "material ids");
  }
  else
  {
    absorption = FindVolumeArray(volume, absorptionName, 3, "mu_a, 1/mm");
    scattering = FindVolumeArray(volume, scatteringName, 3, "sigma_s', 1/mm");
    field.Palette.resize(n);
    field.Which.resize(n);
  }
  std::vector<double> idValues(byId ? n : 0);
  for (size_t i = 0; i < n; ++i)
  {
    if (i % 10000 == 0)
    {
      self->UpdateProgress(static_cast<double>(i) / static_cast<double>(n));
      if (self->GetAbortExecute())
      {
        return false;
      }
    }
    double pc[3];
    int ijk[3];
    LocateInVolume(volume, static_cast<vtkIdType>(i), centroids[i], ijk, pc);
    if (byId)
    {
      idValues[i] = NearestInVolume(volume, ids, ijk, pc);
    }
    else
    {
      MaterialCoefficients& m = field.Palette[i];
      const int tet = static_cast<int>(firstTet + static_cast<long long>(i));
      ProbeVolume(volume, absorption, ijk, pc, m.Absorption.data());
      translucency::CheckProbedValues(tet, centroids[i], absorption.Name, m.Absorption);
      ProbeVolume(volume, scattering, ijk, pc, m.ReducedScattering.data());
      translucency::CheckProbedValues(tet, centroids[i], scattering.Name, m.ReducedScattering);
      m.RefractiveIndex = eta;
      field.Which[i] = static_cast<int>(i);
    }
  }
  if (byId)
  {
    field = translucency::MaterialsFromIds(idValues, table, [&](int tet, double id) {
      const Point3& x = centroids[tet];
      std::ostringstream os;
      os.precision(17);
      os << "tet " << firstTet + tet << " has material id " << id << " (volume array '" << idName
         << "' at its centroid (" << x[0] << ", " << x[1] << ", " << x[2] << "))";
      return os.str();
    });
  }
  return true;
}
} // namespace

//------------------------------------------------------------------------------
vtkAssignScatteringCoefficients::vtkAssignScatteringCoefficients()
{
  this->SetNumberOfInputPorts(2);
}

//------------------------------------------------------------------------------
int vtkAssignScatteringCoefficients::FillInputPortInformation(int port, vtkInformation* info)
{
  if (port == 1)
  {
    info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
    return 1;
  }
  return this->Superclass::FillInputPortInformation(port, info);
}

//------------------------------------------------------------------------------
void vtkAssignScatteringCoefficients::AddLayer(double thickness, const char* material)
{
  this->LayerThicknesses.push_back(thickness);
  this->LayerMaterials.emplace_back(material ? material : "");
  this->Modified();
}

//------------------------------------------------------------------------------
void vtkAssignScatteringCoefficients::RemoveAllLayers()
{
  if (!this->LayerMaterials.empty())
  {
    this->LayerThicknesses.clear();
    this->LayerMaterials.clear();
    this->Modified();
  }
}

//------------------------------------------------------------------------------
bool vtkAssignScatteringCoefficients::ComputeMaterials(
  vtkUnstructuredGrid* input, vtkImageData* volume, translucency::MaterialField& field)
{
  const int n = static_cast<int>(input->GetNumberOfCells());
  if (this->MaterialMode == UNIFORM)
  {
    MaterialCoefficients m;
    if (!this->MaterialName.empty())
    {
      m = MaterialCoefficients::FromPreset(this->MaterialName);
    }
    else
    {
      std::copy(this->AbsorptionCoefficient, this->AbsorptionCoefficient + 3, m.Absorption.begin());
      std::copy(this->ReducedScatteringCoefficient, this->ReducedScatteringCoefficient + 3,
        m.ReducedScattering.begin());
      m.RefractiveIndex = this->RefractiveIndex;
    }
    field = MaterialField::Uniform(n, m);
    return true;
  }
  const translucency::MaterialTable table = ReadTable(this->MaterialTableFileName);
  if (this->MaterialMode == MATERIAL_IDS)
  {
    if (this->MaterialTableFileName.empty())
    {
      throw translucency::Error("the material-id mode needs a material table file "
                                "(MaterialTableFileName)");
    }
    vtkDataArray* ids = input->GetCellData()->GetArray(this->MaterialIdArrayName.c_str());
    if (!ids)
    {
      throw translucency::Error("the material-id mode needs the cell array '" +
        this->MaterialIdArrayName + "' of material ids, which the input does not have");
    }
    field = translucency::MaterialsFromIds(Component0(ids), table, [&](int tet, double id) {
      std::ostringstream os;
      os << "tet " << tet << " has material id " << id << " (array '"
         << this->MaterialIdArrayName << "')";
      return os.str();
    });
    return true;
  }
  const std::vector<Point3> centroids = Centroids(input);
  if (this->MaterialMode == SPHERICAL_INCLUSION)
  {
    const MaterialCoefficients outside = table.Resolve(this->OutsideMaterial);
    const MaterialCoefficients inside = table.Resolve(this->InsideMaterial);
    field = translucency::SphericalInclusion(centroids,
      { this->InclusionCenter[0], this->InclusionCenter[1], this->InclusionCenter[2] },
      this->InclusionRadius, inside, outside);
    return true;
  }
  if (this->MaterialMode == VOLUME)
  {
    return FieldFromVolume(this, volume, centroids, this->VolumeAbsorptionArrayName,
      this->VolumeScatteringArrayName, this->VolumeMaterialIdArrayName, this->RefractiveIndex,
      table, this->FirstTetNumber, field);
  }
  if (this->MaterialMode == VEINS)
  {
    translucency::VeinsField veins;
    const MaterialCoefficients base = table.Resolve(this->BaseMaterial);
    veins.SetMaterials(base, table.Resolve(this->VeinMaterial));
    veins.SetDirection({ this->VeinDirection[0], this->VeinDirection[1], this->VeinDirection[2] });
    veins.SetFrequency(this->VeinFrequency);
    veins.SetOctaves(this->VeinOctaves);
    veins.SetTurbulence(this->VeinTurbulence);
    veins.SetSharpness(this->VeinSharpness);
    veins.SetProgressCallback([this](double fraction) {
      this->UpdateProgress(fraction);
      return !this->GetAbortExecute();
    });
    vtkNew<vtkPerlinNoise> noise;
    noise->SetAmplitude(1.0);
    Point3 phase = translucency::VeinsField::Phase(this->VeinSeed);
    noise->SetPhase(phase.data());
    return veins.Evaluate(centroids,
      [&noise](const Point3& x, double frequency) {
        noise->SetFrequency(frequency, frequency, frequency);
        double p[3] = { x[0], x[1], x[2] };
        return noise->EvaluateFunction(p);
      },
      field);
  }
  // LAYERS
  if (this->LayerMaterials.empty())
  {
    throw translucency::Error("the layered mode needs at least one layer (AddLayer)");
  }
  std::vector<MaterialCoefficients> materials;
  for (const std::string& m : this->LayerMaterials)
  {
    materials.push_back(table.Resolve(m));
  }
  translucency::ValidateLayerThicknesses(this->LayerThicknesses);
  std::vector<double> depths;
  if (!DepthsBelowSurface(this, input, centroids, this->WholeSurface, depths))
  {
    return false;
  }
  field = translucency::Layers(depths, this->LayerThicknesses, materials);
  return true;
}

//------------------------------------------------------------------------------
int vtkAssignScatteringCoefficients::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector,
    [this](vtkInformationVector** i, vtkInformationVector* o, const vtkTranslucencyCommunicator& c)
    { return this->RequestPerPiece(i, o, c); });
}

//------------------------------------------------------------------------------
int vtkAssignScatteringCoefficients::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  const int result = vtkTranslucencyDispatch::UpdateExtent(this, request, inputVector, outputVector);
  // VOLUME: every rank asks for the whole image (not the extent ParaView
  // would give its piece), so that each rank probes its own tets, wherever
  // they lie, without a gather of the mesh (PlanParallel).
  vtkInformation* image = this->MaterialMode == VOLUME && inputVector[1] &&
      inputVector[1]->GetNumberOfInformationObjects() > 0
    ? inputVector[1]->GetInformationObject(0)
    : nullptr;
  if (result && image && image->Has(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()))
  {
    int whole[6];
    image->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), whole);
    image->Set(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER(), 0);
    image->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES(), 1);
    image->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_GHOST_LEVELS(), 0);
    image->Set(vtkStreamingDemandDrivenPipeline::UPDATE_EXTENT(), whole, 6);
  }
  return result;
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkAssignScatteringCoefficients::PlanParallel(
  vtkInformationVector** inputVector, const vtkTranslucencyCommunicator& comm)
{
  using Plan = vtkTranslucencyParallelPlan;
  const Plan::GatherMode mode = Plan::GatherMode::SameMesh;
  vtkUnstructuredGrid* piece = vtkUnstructuredGrid::GetData(inputVector[0]);
  const bool hasCells = piece && piece->GetNumberOfCells() > 0;
  if (this->MaterialMode == VOLUME && comm.Any(hasCells && !HasWholeImage(inputVector[1])))
  {
    // RequestUpdateExtent asked for the whole image: a source that ignored
    // the request (or no image: the serial path's error) is gathered.
    return Plan::Gathered(mode, "the Volume image is not whole on every rank with tets");
  }
  if (this->MaterialMode == LAYERS && !vtkTranslucency::CanDistribute(comm))
  {
    return Plan::Gathered(mode, "the Layers mode needs the distributed boundary surface "
                                "(a build with hypre and VTK's ParallelMPI)");
  }
  // vtkOriginalCellIds (added when missing) number the gathered mesh's
  // cells: the rank order unless ghost cells or cell GlobalIds reorder them.
  const bool reordered = comm.Any(hasCells &&
    !piece->GetCellData()->GetArray(vtkTranslucency::OriginalCellIdsName) &&
    (vtkTranslucency::HasGhostCells(piece) || piece->GetCellData()->GetGlobalIds()));
  if (reordered)
  {
    return Plan::Gathered(mode, "vtkOriginalCellIds are missing and ghost cells or cell "
                                "GlobalIds reorder the cells: numbered on the gathered mesh");
  }
  return Plan::PerPiece(mode, this->MaterialMode == LAYERS
      ? "the depths below the all-gathered physical boundary surface, per tet"
      : this->MaterialMode == VOLUME
      ? "each rank's tets probed in the whole image (every rank reads it), no mesh gather"
      : "per-tet values, no gather");
}

//------------------------------------------------------------------------------
int vtkAssignScatteringCoefficients::RequestSerial(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  if (!input || input->GetNumberOfCells() == 0)
  {
    vtkErrorMacro(<< "the input mesh is empty (no cells)");
    return 0;
  }
  // Each tet gets one entry of a small palette of materials.
  MaterialField field;
  try
  {
    if (!this->ComputeMaterials(input, vtkImageData::GetData(inputVector[1]), field))
    {
      return 0; // aborted
    }
    field.Scale(this->ScaleFactor);
    field.Validate();
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }

  this->AttachMaterials(input, output, field, 0);
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
int vtkAssignScatteringCoefficients::RequestPerPiece(vtkInformationVector** inputVector,
  vtkInformationVector* outputVector, const vtkTranslucencyCommunicator& comm)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  const long long cells = input ? input->GetNumberOfCells() : 0;
  // Every rank takes part in every collective below, an empty piece too.
  const long long total = comm.Sum(cells);
  const long long offset = comm.ExclusiveSum(cells);
  if (total == 0)
  {
    vtkErrorMacro(<< "the input mesh is empty (no cells)");
    return 0;
  }
  // Layers: every rank (an empty piece too) takes part in the surface gather.
  vtkNew<vtkPolyData> wholeSurface;
  if (this->MaterialMode == LAYERS)
  {
    std::string gatherError;
    translucency::BoundarySurface gathered;
    if (!vtkTranslucencyDistributedIrradiance::GatherSurface(input, gathered, gatherError))
    {
      vtkErrorMacro(<< gatherError);
      return 0;
    }
    vtkNew<vtkPoints> points;
    points->SetDataTypeToDouble();
    points->SetNumberOfPoints(static_cast<vtkIdType>(gathered.GetNumberOfPoints()));
    for (size_t i = 0; i < gathered.GetNumberOfPoints(); ++i)
    {
      points->SetPoint(static_cast<vtkIdType>(i), gathered.Points.data() + 3 * i);
    }
    vtkNew<vtkCellArray> polys;
    for (size_t f = 0; f < gathered.GetNumberOfTriangles(); ++f)
    {
      const vtkIdType ids[3] = { gathered.Triangles[3 * f], gathered.Triangles[3 * f + 1],
        gathered.Triangles[3 * f + 2] };
      polys->InsertNextCell(3, ids);
    }
    wholeSurface->SetPoints(points);
    wholeSurface->SetPolys(polys);
  }
  MaterialField field;
  std::string local;
  bool aborted = false;
  if (cells > 0)
  {
    try
    {
      this->WholeSurface = this->MaterialMode == LAYERS ? wholeSurface.Get() : nullptr;
      this->FirstTetNumber = offset;
      // Veins and Volume may abort.
      aborted = !this->ComputeMaterials(input,
        this->MaterialMode == VOLUME ? vtkImageData::GetData(inputVector[1]) : nullptr, field);
      this->WholeSurface = nullptr;
      this->FirstTetNumber = 0;
      if (!aborted)
      {
        field.Scale(this->ScaleFactor);
        field.Validate();
      }
    }
    catch (const std::exception& e)
    {
      this->WholeSurface = nullptr;
      this->FirstTetNumber = 0;
      local = e.what();
    }
  }
  const std::string error = comm.AgreeOnError(local);
  if (!error.empty())
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  if (comm.Any(aborted))
  {
    return 0; // aborted on some rank: every rank stops
  }
  if (input)
  {
    this->AttachMaterials(input, output, field, offset);
  }
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
void vtkAssignScatteringCoefficients::AttachMaterials(vtkUnstructuredGrid* input,
  vtkUnstructuredGrid* output, const translucency::MaterialField& field, long long firstId)
{
  const vtkIdType n = input->GetNumberOfCells();
  output->ShallowCopy(input);
  vtkNew<vtkDoubleArray> absorption;
  absorption->SetName(vtkTranslucency::AbsorptionName);
  absorption->SetNumberOfComponents(3);
  vtkTranslucency::SetRGBComponentNames(absorption);
  absorption->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> scattering;
  scattering->SetName(vtkTranslucency::ScatteringName);
  scattering->SetNumberOfComponents(3);
  vtkTranslucency::SetRGBComponentNames(scattering);
  scattering->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> index;
  index->SetName(vtkTranslucency::RefractiveIndexName);
  index->SetNumberOfComponents(1);
  index->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i)
  {
    const MaterialCoefficients& m = field.At(static_cast<int>(i));
    absorption->SetTypedTuple(i, m.Absorption.data());
    scattering->SetTypedTuple(i, m.ReducedScattering.data());
    index->SetValue(i, m.RefractiveIndex);
  }
  output->GetCellData()->AddArray(absorption);
  output->GetCellData()->AddArray(scattering);
  output->GetCellData()->AddArray(index);
  if (!output->GetCellData()->GetArray(vtkTranslucency::OriginalCellIdsName))
  {
    vtkNew<vtkIdTypeArray> ids;
    ids->SetName(vtkTranslucency::OriginalCellIdsName);
    ids->SetNumberOfTuples(n);
    for (vtkIdType i = 0; i < n; ++i)
    {
      ids->SetValue(i, static_cast<vtkIdType>(firstId) + i);
    }
    output->GetCellData()->AddArray(ids);
  }
}

//------------------------------------------------------------------------------
void vtkAssignScatteringCoefficients::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "MaterialName: " << this->MaterialName << "\n";
  os << indent << "AbsorptionCoefficient: " << this->AbsorptionCoefficient[0] << ", "
     << this->AbsorptionCoefficient[1] << ", " << this->AbsorptionCoefficient[2] << "\n";
  os << indent << "ReducedScatteringCoefficient: " << this->ReducedScatteringCoefficient[0]
     << ", " << this->ReducedScatteringCoefficient[1] << ", "
     << this->ReducedScatteringCoefficient[2] << "\n";
  os << indent << "RefractiveIndex: " << this->RefractiveIndex << "\n";
  os << indent << "ScaleFactor: " << this->ScaleFactor << "\n";
  os << indent << "MaterialMode: " << this->MaterialMode << "\n";
  os << indent << "MaterialTableFileName: " << this->MaterialTableFileName << "\n";
  os << indent << "MaterialIdArrayName: " << this->MaterialIdArrayName << "\n";
  os << indent << "InclusionCenter: " << this->InclusionCenter[0] << ", "
     << this->InclusionCenter[1] << ", " << this->InclusionCenter[2] << "\n";
  os << indent << "InclusionRadius: " << this->InclusionRadius << "\n";
  os << indent << "InsideMaterial: " << this->InsideMaterial << "\n";
  os << indent << "OutsideMaterial: " << this->OutsideMaterial << "\n";
  for (size_t k = 0; k < this->LayerMaterials.size(); ++k)
  {
    os << indent << "Layer " << k << ": " << this->LayerThicknesses[k] << " mm of "
       << this->LayerMaterials[k] << "\n";
  }
  os << indent << "BaseMaterial: " << this->BaseMaterial << "\n";
  os << indent << "VeinMaterial: " << this->VeinMaterial << "\n";
  os << indent << "VeinDirection: " << this->VeinDirection[0] << ", " << this->VeinDirection[1]
     << ", " << this->VeinDirection[2] << "\n";
  os << indent << "VeinFrequency: " << this->VeinFrequency << "\n";
  os << indent << "VeinOctaves: " << this->VeinOctaves << "\n";
  os << indent << "VeinTurbulence: " << this->VeinTurbulence << "\n";
  os << indent << "VeinSharpness: " << this->VeinSharpness << "\n";
  os << indent << "VeinSeed: " << this->VeinSeed << "\n";
  os << indent << "VolumeAbsorptionArrayName: " << this->VolumeAbsorptionArrayName << "\n";
  os << indent << "VolumeScatteringArrayName: " << this->VolumeScatteringArrayName << "\n";
  os << indent << "VolumeMaterialIdArrayName: " << this->VolumeMaterialIdArrayName << "\n";
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}
