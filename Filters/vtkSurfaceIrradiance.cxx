#include "vtkSurfaceIrradiance.h"

#include "Error.h"
#include "Fresnel.h"
#include "LightSources.h"
#include "Radiance.h"
#include "TetMesh.h"
#include "vtkTranslucencyMeshConversion.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkGenericCell.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkCellLocator.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSMPThreadLocalObject.h>
#include <vtkSMPTools.h>
#include <vtkUnstructuredGrid.h>

#include <atomic>
#include <cmath>
#include <vector>

vtkStandardNewMacro(vtkSurfaceIrradiance);

struct vtkSurfaceIrradiance::Internals
{
  std::vector<translucency::LightSource> Directional;
  std::vector<translucency::LightSource> Point;
  translucency::TetMesh Mesh;
  std::string MeshKey;
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
  translucency::LightSource light;
  light.Type = translucency::LightSource::Kind::Directional;
  light.Direction = { dx, dy, dz };
  light.Power = { irradiance, irradiance, irradiance };
  this->Internal->Directional.push_back(light);
  this->Modified();
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
  translucency::LightSource light;
  light.Type = translucency::LightSource::Kind::Point;
  light.Position = { x, y, z };
  light.Power = { intensity, intensity, intensity };
  this->Internal->Point.push_back(light);
  this->Modified();
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

//------------------------------------------------------------------------------
int vtkSurfaceIrradiance::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);

  std::vector<translucency::LightSource> lights = this->Internal->Directional;
  lights.insert(lights.end(), this->Internal->Point.begin(), this->Internal->Point.end());
  for (const auto& light : lights)
  {
    const bool badDirection = light.Type == translucency::LightSource::Kind::Directional &&
      !(light.Direction[0] * light.Direction[0] + light.Direction[1] * light.Direction[1] +
          light.Direction[2] * light.Direction[2] >
        0.0);
    if (badDirection || !(light.Power[0] >= 0.0) || !std::isfinite(light.Power[0]))
    {
      vtkErrorMacro(<< (badDirection ? "a directional light has a zero or non-finite direction"
                                     : "a light has a negative or non-finite power"));
      return 0;
    }
  }

  std::string error;
  translucency::TetMesh& mesh = this->Internal->Mesh;
  const std::string key = input ? vtkTranslucency::GeometryKey(input) : std::string();
  if (key != this->Internal->MeshKey || key.empty())
  {
    this->Internal->MeshKey.clear();
    if (!vtkTranslucency::ToTetMesh(input, mesh, error))
    {
      vtkErrorMacro(<< error);
      return 0;
    }
    this->Internal->MeshKey = key;
  }
  vtkDataArray* etaArray = input->GetCellData()->GetArray(vtkTranslucency::RefractiveIndexName);
  if (!etaArray || etaArray->GetNumberOfComponents() != 1)
  {
    vtkErrorMacro(<< "the input has no 1-component cell array '"
                  << vtkTranslucency::RefractiveIndexName
                  << "': assign coefficients first (vtkAssignScatteringCoefficients)");
    return 0;
  }
  std::vector<double> tetEta(static_cast<size_t>(etaArray->GetNumberOfTuples()));
  for (vtkIdType t = 0; t < etaArray->GetNumberOfTuples(); ++t)
  {
    tetEta[t] = etaArray->GetComponent(t, 0);
    if (!(tetEta[t] > 0.0) || !std::isfinite(tetEta[t]))
    {
      vtkErrorMacro(<< "RefractiveIndex of tet " << t << " is " << tetEta[t]
                    << ": must be finite and > 0");
      return 0;
    }
  }
  const std::vector<double> pointEta = translucency::PointRefractiveIndex(mesh, tetEta);
  this->UpdateProgress(0.1);

  // Boundary surface and its ray-casting locator.
  const std::vector<int>& tris = mesh.GetBoundaryTriangles();
  vtkNew<vtkPolyData> surface;
  vtkNew<vtkPoints> surfacePoints;
  surfacePoints->SetDataTypeToDouble();
  surfacePoints->SetNumberOfPoints(mesh.GetNumberOfPoints());
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    surfacePoints->SetPoint(i, mesh.GetPoint(i));
  }
  vtkNew<vtkCellArray> polys;
  for (size_t f = 0; f < tris.size() / 3; ++f)
  {
    const vtkIdType ids[3] = { tris[3 * f], tris[3 * f + 1], tris[3 * f + 2] };
    polys->InsertNextCell(3, ids);
  }
  surface->SetPoints(surfacePoints);
  surface->SetPolys(polys);
  double bounds[6];
  surface->GetBounds(bounds);
  const double diag = std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
    (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) + (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
  vtkNew<vtkCellLocator> locator;
  locator->SetNumberOfCellsPerNode(4);
  const bool needRays = this->Shadows &&
    (!lights.empty() || (this->UniformLightIrradiance > 0 && this->UniformLightSamples > 0));
  if (needRays)
  {
    locator->SetDataSet(surface);
    locator->BuildLocator();
  }
  this->UpdateProgress(0.2);

  const std::vector<int>& boundary = mesh.GetBoundaryPoints();
  const std::vector<double>& normals = mesh.GetPointNormals();
  std::vector<double> q(3 * static_cast<size_t>(mesh.GetNumberOfPoints()), 0.0);
  const double offset = 1e-5 * diag;
  const double uniformE = this->UniformLightIrradiance;
  const int samples = this->UniformLightSamples;
  const bool shadows = this->Shadows;

  vtkSMPThreadLocalObject<vtkGenericCell> cells;
  std::atomic<bool> aborted(false);
  auto occluded = [&](vtkGenericCell* cell, const double* x, const double* n, const double* w,
                    double distance) {
    double p1[3], p2[3];
    const double reach = std::min(distance, 2.0 * diag);
    for (int k = 0; k < 3; ++k)
    {
      p1[k] = x[k] + offset * (n[k] + w[k]);
      p2[k] = x[k] + reach * w[k];
    }
    double t, hit[3], pcoords[3];
    int subId;
    vtkIdType cellId;
    return locator->IntersectWithLine(p1, p2, 0.0, t, hit, pcoords, subId, cellId, cell) != 0;
  };
  const vtkIdType numBoundary = static_cast<vtkIdType>(boundary.size());
  vtkSMPTools::For(0, numBoundary, [&](vtkIdType begin, vtkIdType end) {
    vtkGenericCell* cell = cells.Local();
    for (vtkIdType b = begin; b < end; ++b)
    {
      if (b % 1024 == 0 && this->GetAbortExecute())
      {
        aborted = true;
      }
      if (aborted)
      {
        return;
      }
      const int i = boundary[b];
      const double* x = mesh.GetPoint(i);
      const double* n = &normals[3 * static_cast<size_t>(i)];
      const double eta = pointEta[i];
      double* qi = &q[3 * static_cast<size_t>(i)];
      for (const auto& light : lights)
      {
        double ql[3], w[3], distance;
        if (translucency::DirectIrradiance(light, x, n, eta, ql, w, distance) &&
          !(shadows && occluded(cell, x, n, w, distance)))
        {
          for (int c = 0; c < 3; ++c)
          {
            qi[c] += ql[c];
          }
        }
      }
      if (uniformE > 0.0)
      {
        double qu = 0.0;
        if (!shadows || samples == 0)
        {
          // q = pi L * (1/pi) int F_t cos dw = E * UniformTransmittance.
          qu = uniformE * translucency::Fresnel::UniformTransmittance(eta);
        }
        else
        {
          // Cosine-weighted estimate of (1/pi) int V F_t cos dw.
          const double rotation = std::fmod(0.6180339887498949 * i, 1.0);
          for (int k = 0; k < samples; ++k)
          {
            double w[3];
            const double cosTheta = translucency::HemisphereDirection(n, k, samples, rotation, w);
            if (!occluded(cell, x, n, w, 2.0 * diag))
            {
              qu += translucency::Fresnel::Transmittance(cosTheta, eta);
            }
          }
          qu *= uniformE / samples;
        }
        for (int c = 0; c < 3; ++c)
        {
          qi[c] += qu;
        }
      }
    }
  });
  if (aborted)
  {
    return 0;
  }
  output->ShallowCopy(input);
  vtkDataArray* array = vtkTranslucency::NewTripleArray(vtkTranslucency::IrradianceName, q);
  output->GetPointData()->AddArray(array);
  array->Delete();
  this->UpdateProgress(1.0);
  return 1;
}

//------------------------------------------------------------------------------
void vtkSurfaceIrradiance::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "DirectionalLights: " << this->Internal->Directional.size() << "\n";
  os << indent << "PointLights: " << this->Internal->Point.size() << "\n";
  os << indent << "UniformLightIrradiance: " << this->UniformLightIrradiance << "\n";
  os << indent << "UniformLightSamples: " << this->UniformLightSamples << "\n";
  os << indent << "Shadows: " << this->Shadows << "\n";
}
