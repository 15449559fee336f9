#include "vtkAssignScatteringCoefficients.h"

#include "Error.h"
#include "OpticalProperties.h"
#include "vtkMaterialTableReader.h"
#include "vtkTranslucencyMeshConversion.h"

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
#include <vtkMath.h>
#include <vtkObjectFactory.h>
#include <vtkPerlinNoise.h>
#include <vtkPolyData.h>
#include <vtkStaticCellLocator.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>

vtkStandardNewMacro(vtkAssignScatteringCoefficients);

namespace
{
using Material = vtkMaterialTableReader::Material;

/// One material's coefficients: mu_a, sigma_s' (R, G, B, 1/mm) and eta.
struct Coefficients
{
  double MuA[3];
  double SigmaS[3];
  double Eta;
};

/// Centroid (mean of the points) of cell i, mm.
void Centroid(vtkUnstructuredGrid* grid, vtkIdType i, double c[3])
{
  vtkIdType npts;
  const vtkIdType* pts;
  grid->GetCellPoints(i, npts, pts);
  c[0] = c[1] = c[2] = 0.0;
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

Coefficients FromTable(const Material& m)
{
  Coefficients c;
  for (int k = 0; k < 3; ++k)
  {
    c.MuA[k] = m.Absorption[k];
    c.SigmaS[k] = m.ReducedScattering[k];
  }
  c.Eta = m.RefractiveIndex;
  return c;
}

/// A material reference: a table name, else a table id, else a preset.
Coefficients ResolveMaterial(const std::string& ref, const std::vector<Material>& table)
{
  for (const Material& m : table)
  {
    if (!m.Name.empty() && m.Name == ref)
    {
      return FromTable(m);
    }
  }
  char* end = nullptr;
  const long id = std::strtol(ref.c_str(), &end, 10);
  if (!ref.empty() && end && *end == '\0')
  {
    for (const Material& m : table)
    {
      if (m.Id == id)
      {
        return FromTable(m);
      }
    }
  }
  try
  {
    const translucency::MaterialPreset& p = translucency::FindMaterialPreset(ref);
    Coefficients c;
    for (int k = 0; k < 3; ++k)
    {
      c.MuA[k] = p.Absorption[k];
      c.SigmaS[k] = p.ReducedScattering[k];
    }
    c.Eta = p.RefractiveIndex;
    return c;
  }
  catch (const std::exception& e)
  {
    throw translucency::Error("unknown material '" + ref + "': " +
      (table.empty() ? std::string("no material table is set and ")
                     : std::string("not a name or id of the material table and ")) +
      e.what());
  }
}
/// The preset or explicit values of UNIFORM mode (throws on an unknown preset).
Coefficients UniformMaterial(const std::string& materialName, const double muA[3],
  const double sigmaS[3], double eta)
{
  Coefficients m;
  if (!materialName.empty())
  {
    const translucency::MaterialPreset& preset =
      translucency::FindMaterialPreset(materialName);
    for (int c = 0; c < 3; ++c)
    {
      m.MuA[c] = preset.Absorption[c];
      m.SigmaS[c] = preset.ReducedScattering[c];
    }
    m.Eta = preset.RefractiveIndex;
  }
  else
  {
    for (int c = 0; c < 3; ++c)
    {
      m.MuA[c] = muA[c];
      m.SigmaS[c] = sigmaS[c];
    }
    m.Eta = eta;
  }
  return m;
}

/// MATERIAL_IDS: one palette entry per table id, and each tet's palette index.
void AssignByIds(vtkUnstructuredGrid* input, const std::vector<Material>& table,
  const std::string& arrayName, const std::string& tableFileName,
  std::vector<Coefficients>& palette, std::vector<int>& which)
{
  vtkDataArray* ids = input->GetCellData()->GetArray(arrayName.c_str());
  if (!ids)
  {
    throw translucency::Error("the material-id mode needs the cell array '" +
      arrayName + "' of material ids, which the input does not have");
  }
  std::map<long long, int> slot; // table id -> palette index
  for (const Material& m : table)
  {
    if (m.Id >= 0)
    {
      slot[m.Id] = static_cast<int>(palette.size());
      palette.push_back(FromTable(m));
    }
  }
  const vtkIdType n = input->GetNumberOfCells();
  for (vtkIdType i = 0; i < n; ++i)
  {
    const double v = ids->GetComponent(i, 0);
    const double r = std::round(v);
    auto it = (v == r && std::abs(r) < 9e18) ? slot.find(static_cast<long long>(r)) : slot.end();
    if (it == slot.end())
    {
      std::ostringstream os;
      os << "tet " << i << " has material id " << v << " (array '" << arrayName
         << "'), which " << (v == r ? "is not an id of" : "is not an integer id of")
         << " the material table '" << tableFileName << "'";
      throw translucency::Error(os.str());
    }
    which[i] = it->second;
  }
}

/// LAYERS: each tet's layer index from its centroid depth; false if aborted.
bool AssignByDepth(vtkAlgorithm* self, vtkUnstructuredGrid* input,
  const std::vector<double>& thicknesses, std::vector<int>& which)
{
  for (double t : thicknesses)
  {
    if (!(t >= 0.0) || !std::isfinite(t))
    {
      std::ostringstream os;
      os << "layer thickness " << t << " mm must be finite and >= 0";
      throw translucency::Error(os.str());
    }
  }
  // The boundary triangles of the tet mesh and a locator on them.
  vtkNew<vtkGeometryFilter> boundary;
  boundary->SetInputData(input);
  boundary->Update();
  vtkPolyData* surface = boundary->GetOutput();
  if (surface->GetNumberOfCells() == 0)
  {
    throw translucency::Error("the mesh has no boundary faces: cannot compute depths");
  }
  vtkNew<vtkStaticCellLocator> locator;
  locator->SetDataSet(surface);
  locator->BuildLocator();
  vtkNew<vtkGenericCell> cell;
  const vtkIdType n = input->GetNumberOfCells();
  const int last = static_cast<int>(thicknesses.size()) - 1;
  for (vtkIdType i = 0; i < n; ++i)
  {
    if (i % 10000 == 0)
    {
      self->UpdateProgress(static_cast<double>(i) / static_cast<double>(n));
      if (self->GetAbortExecute())
      {
        return false;
      }
    }
    double c[3], closest[3], dist2;
    vtkIdType cellId;
    int subId;
    Centroid(input, i, c);
    locator->FindClosestPoint(c, closest, cell, cellId, subId, dist2);
    const double depth = std::sqrt(dist2);
    int k = 0;
    double bottom = thicknesses[0];
    while (k < last && depth >= bottom)
    {
      ++k;
      bottom += thicknesses[k];
    }
    which[i] = k;
  }
  return true;
}

/// The settings of VEINS mode (see the class documentation).
struct VeinSettings
{
  Coefficients Base, Vein;
  double Direction[3];
  double Frequency;
  int Octaves;
  double Turbulence;
  double Sharpness;
  int Seed;
};

/// VEINS: one palette entry per tet, the blend of the two materials.
bool AssignVeins(vtkAlgorithm* self, vtkUnstructuredGrid* input, const VeinSettings& v,
  std::vector<Coefficients>& palette, std::vector<int>& which)
{
  double d[3] = { v.Direction[0], v.Direction[1], v.Direction[2] };
  if (!(vtkMath::Normalize(d) > 0.0) || !std::isfinite(d[0] + d[1] + d[2]))
  {
    throw translucency::Error("the vein direction must be a non-zero vector");
  }
  if (!(v.Frequency > 0.0) || !std::isfinite(v.Frequency))
  {
    std::ostringstream os;
    os << "the vein frequency must be > 0 (1/mm), not " << v.Frequency;
    throw translucency::Error(os.str());
  }
  // Phase from the seed: the R3 low-discrepancy sequence, in [0, 1).
  const double golden[3] = { 0.7548776662466927, 0.5698402909980532, 0.4301597090019468 };
  vtkNew<vtkPerlinNoise> noise;
  noise->SetAmplitude(1.0);
  double phase[3];
  for (int a = 0; a < 3; ++a)
  {
    const double p = static_cast<double>(v.Seed) * golden[a];
    phase[a] = p - std::floor(p);
  }
  noise->SetPhase(phase);
  const vtkIdType n = input->GetNumberOfCells();
  palette.resize(static_cast<size_t>(n));
  for (vtkIdType i = 0; i < n; ++i)
  {
    if (i % 10000 == 0)
    {
      self->UpdateProgress(static_cast<double>(i) / static_cast<double>(n));
      if (self->GetAbortExecute())
      {
        return false;
      }
    }
    double x[3];
    Centroid(input, i, x);
    double turbulence = 0.0;
    if (v.Turbulence > 0.0)
    {
      double scale = 1.0;
      for (int o = 0; o < v.Octaves; ++o)
      {
        const double f = scale * v.Frequency;
        noise->SetFrequency(f, f, f);
        turbulence += std::abs(noise->EvaluateFunction(x)) / scale;
        scale *= 2.0;
      }
    }
    const double s =
      std::sin(2.0 * vtkMath::Pi() * (v.Frequency * vtkMath::Dot(d, x) + v.Turbulence * turbulence));
    const double w = std::pow(1.0 - std::abs(s), v.Sharpness);
    Coefficients& m = palette[i];
    for (int c = 0; c < 3; ++c)
    {
      m.MuA[c] = (1.0 - w) * v.Base.MuA[c] + w * v.Vein.MuA[c];
      m.SigmaS[c] = (1.0 - w) * v.Base.SigmaS[c] + w * v.Vein.SigmaS[c];
    }
    m.Eta = (1.0 - w) * v.Base.Eta + w * v.Vein.Eta;
    which[i] = static_cast<int>(i);
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
void LocateInVolume(vtkImageData* volume, vtkIdType tet, const double x[3], int ijk[3],
  double pc[3])
{
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

/// Point array: trilinear interpolation; cell array: the voxel's value.
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

/// Throws, naming the tet, the point and the array, unless all values are finite and >= 0.
void CheckProbed(vtkIdType tet, const double x[3], const std::string& name, const double v[3])
{
  for (int c = 0; c < 3; ++c)
  {
    if (!(v[c] >= 0.0) || !std::isfinite(v[c]))
    {
      std::ostringstream os;
      os.precision(17);
      os << "tet " << tet << " gets the value " << v[c] << " (component " << c
         << ") from the volume array '" << name << "' at its centroid (" << x[0] << ", " << x[1]
         << ", " << x[2] << "); it must be finite and >= 0";
      throw translucency::Error(os.str());
    }
  }
}

/// The settings of VOLUME mode.
struct VolumeSettings
{
  std::string AbsorptionName, ScatteringName, IdName, TableFileName;
  double Eta;
};

/// VOLUME: probed coefficients (one palette entry per tet) or table entries by id.
bool AssignFromVolume(vtkAlgorithm* self, vtkUnstructuredGrid* input, vtkImageData* volume,
  const VolumeSettings& v, const std::vector<Material>& table, std::vector<Coefficients>& palette,
  std::vector<int>& which)
{
  if (!volume)
  {
    throw translucency::Error("the volume mode needs a vtkImageData on the second input port "
                              "(SetVolumeConnection or SetVolumeData)");
  }
  const vtkIdType n = input->GetNumberOfCells();
  const bool byId = !v.IdName.empty();
  VolumeArray ids, absorption, scattering;
  std::map<long long, int> slot; // table id -> palette index
  if (byId)
  {
    if (v.TableFileName.empty())
    {
      throw translucency::Error("the volume mode with a material-id array needs a material "
                                "table file (MaterialTableFileName)");
    }
    ids = FindVolumeArray(volume, v.IdName, 1, "material ids");
    for (const Material& m : table)
    {
      if (m.Id >= 0)
      {
        slot[m.Id] = static_cast<int>(palette.size());
        palette.push_back(FromTable(m));
      }
    }
  }
  else
  {
    absorption = FindVolumeArray(volume, v.AbsorptionName, 3, "mu_a, 1/mm");
    scattering = FindVolumeArray(volume, v.ScatteringName, 3, "sigma_s', 1/mm");
    palette.resize(static_cast<size_t>(n));
  }
  for (vtkIdType i = 0; i < n; ++i)
  {
    if (i % 10000 == 0)
    {
      self->UpdateProgress(static_cast<double>(i) / static_cast<double>(n));
      if (self->GetAbortExecute())
      {
        return false;
      }
    }
    double x[3], pc[3];
    int ijk[3];
    Centroid(input, i, x);
    LocateInVolume(volume, i, x, ijk, pc);
    if (byId)
    {
      const double id = NearestInVolume(volume, ids, ijk, pc);
      const double r = std::round(id);
      auto it = (id == r && std::abs(r) < 9e18) ? slot.find(static_cast<long long>(r)) : slot.end();
      if (it == slot.end())
      {
        std::ostringstream os;
        os.precision(17);
        os << "tet " << i << " has material id " << id << " (volume array '" << v.IdName
           << "' at its centroid (" << x[0] << ", " << x[1] << ", " << x[2] << ")), which "
           << (id == r ? "is not an id of" : "is not an integer id of") << " the material table '"
           << v.TableFileName << "'";
        throw translucency::Error(os.str());
      }
      which[i] = it->second;
    }
    else
    {
      Coefficients& m = palette[i];
      ProbeVolume(volume, absorption, ijk, pc, m.MuA);
      CheckProbed(i, x, absorption.Name, m.MuA);
      ProbeVolume(volume, scattering, ijk, pc, m.SigmaS);
      CheckProbed(i, x, scattering.Name, m.SigmaS);
      m.Eta = v.Eta;
      which[i] = static_cast<int>(i);
    }
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
int vtkAssignScatteringCoefficients::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  if (!input || input->GetNumberOfCells() == 0)
  {
    vtkErrorMacro(<< "the input mesh is empty (no cells)");
    return 0;
  }
  const vtkIdType n = input->GetNumberOfCells();
  // Each tet gets one entry of a small palette of materials.
  std::vector<Coefficients> palette;
  std::vector<int> which(static_cast<size_t>(n), 0);
  try
  {
    if (this->MaterialMode == UNIFORM)
    {
      palette.push_back(UniformMaterial(this->MaterialName, this->AbsorptionCoefficient,
        this->ReducedScatteringCoefficient, this->RefractiveIndex));
    }
    else
    {
      std::vector<vtkMaterialTableReader::Material> table;
      if (!this->MaterialTableFileName.empty())
      {
        table = vtkMaterialTableReader::ReadMaterialTable(this->MaterialTableFileName);
      }
      else if (this->MaterialMode == MATERIAL_IDS)
      {
        throw translucency::Error("the material-id mode needs a material table file "
                                  "(MaterialTableFileName)");
      }
      if (this->MaterialMode == MATERIAL_IDS)
      {
        AssignByIds(input, table, this->MaterialIdArrayName, this->MaterialTableFileName, palette,
          which);
      }
      else if (this->MaterialMode == SPHERICAL_INCLUSION)
      {
        palette.push_back(ResolveMaterial(this->OutsideMaterial, table));
        palette.push_back(ResolveMaterial(this->InsideMaterial, table));
        const double r2 = this->InclusionRadius * this->InclusionRadius;
        for (vtkIdType i = 0; i < n; ++i)
        {
          double c[3];
          Centroid(input, i, c);
          which[i] = vtkMath::Distance2BetweenPoints(c, this->InclusionCenter) <= r2 ? 1 : 0;
        }
      }
      else if (this->MaterialMode == VOLUME)
      {
        VolumeSettings v;
        v.AbsorptionName = this->VolumeAbsorptionArrayName;
        v.ScatteringName = this->VolumeScatteringArrayName;
        v.IdName = this->VolumeMaterialIdArrayName;
        v.TableFileName = this->MaterialTableFileName;
        v.Eta = this->RefractiveIndex;
        if (!AssignFromVolume(this, input, vtkImageData::GetData(inputVector[1]), v, table,
              palette, which))
        {
          return 0;
        }
      }
      else if (this->MaterialMode == VEINS)
      {
        VeinSettings v;
        v.Base = ResolveMaterial(this->BaseMaterial, table);
        v.Vein = ResolveMaterial(this->VeinMaterial, table);
        std::copy(this->VeinDirection, this->VeinDirection + 3, v.Direction);
        v.Frequency = this->VeinFrequency;
        v.Octaves = this->VeinOctaves;
        v.Turbulence = this->VeinTurbulence;
        v.Sharpness = this->VeinSharpness;
        v.Seed = this->VeinSeed;
        if (!AssignVeins(this, input, v, palette, which))
        {
          return 0;
        }
      }
      else
      {
        if (this->LayerMaterials.empty())
        {
          throw translucency::Error("the layered mode needs at least one layer (AddLayer)");
        }
        for (const std::string& m : this->LayerMaterials)
        {
          palette.push_back(ResolveMaterial(m, table));
        }
        if (!AssignByDepth(this, input, this->LayerThicknesses, which))
        {
          return 0;
        }
      }
    }
    for (Coefficients& m : palette)
    {
      for (int c = 0; c < 3; ++c)
      {
        m.MuA[c] *= this->ScaleFactor;
        m.SigmaS[c] *= this->ScaleFactor;
      }
      // Validate with the core's rules on a one-tet material (names the value).
      translucency::OpticalProperties::Uniform(1, m.MuA, m.SigmaS, m.Eta).Validate(1);
    }
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }

  output->ShallowCopy(input);
  vtkNew<vtkDoubleArray> absorption;
  absorption->SetName(vtkTranslucency::AbsorptionName);
  absorption->SetNumberOfComponents(3);
  absorption->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> scattering;
  scattering->SetName(vtkTranslucency::ScatteringName);
  scattering->SetNumberOfComponents(3);
  scattering->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> index;
  index->SetName(vtkTranslucency::RefractiveIndexName);
  index->SetNumberOfComponents(1);
  index->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i)
  {
    const Coefficients& m = palette[which[i]];
    absorption->SetTypedTuple(i, m.MuA);
    scattering->SetTypedTuple(i, m.SigmaS);
    index->SetValue(i, m.Eta);
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
      ids->SetValue(i, i);
    }
    output->GetCellData()->AddArray(ids);
  }
  return 1;
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
}
