#include "vtkTranslucencyRanges.h"

#include <vtkCellData.h>
#include <vtkDataSet.h>
#include <vtkDoubleArray.h>
#include <vtkExecutive.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkPointData.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace
{
/// Per component [min, max] then the magnitude's squared [min, max], of
/// `values` (n tuples of c components); false if a value is not finite.
bool Ranges(const double* values, vtkIdType n, int c, std::vector<double>& range)
{
  const double inf = std::numeric_limits<double>::infinity();
  range.assign(2 * static_cast<size_t>(c) + 2, 0.0);
  for (int k = 0; k <= c; ++k)
  {
    range[2 * k] = inf;
    range[2 * k + 1] = -inf;
  }
  bool finite = true;
#pragma omp parallel
  {
    std::vector<double> local(range);
    bool localFinite = true;
#pragma omp for schedule(static) nowait
    for (vtkIdType i = 0; i < n; ++i)
    {
      const double* tuple = values + i * c;
      double squared = 0.0;
      for (int k = 0; k < c; ++k)
      {
        const double v = tuple[k];
        localFinite = localFinite && std::isfinite(v);
        local[2 * k] = std::min(local[2 * k], v);
        local[2 * k + 1] = std::max(local[2 * k + 1], v);
        squared += v * v;
      }
      localFinite = localFinite && std::isfinite(squared);
      local[2 * c] = std::min(local[2 * c], squared);
      local[2 * c + 1] = std::max(local[2 * c + 1], squared);
    }
#pragma omp critical
    {
      finite = finite && localFinite;
      for (int k = 0; k <= c; ++k)
      {
        range[2 * k] = std::min(range[2 * k], local[2 * k]);
        range[2 * k + 1] = std::max(range[2 * k + 1], local[2 * k + 1]);
      }
    }
  }
  return finite;
}

/// One information object per component, each with its COMPONENT_RANGE.
void SetComponentRanges(vtkInformation* info, vtkInformationInformationVectorKey* key,
  const std::vector<double>& range, int c)
{
  vtkNew<vtkInformationVector> perComponent;
  perComponent->SetNumberOfInformationObjects(c);
  for (int k = 0; k < c; ++k)
  {
    perComponent->GetInformationObject(k)->Set(vtkDataArray::COMPONENT_RANGE(), &range[2 * k], 2);
  }
  info->Set(key, perComponent);
}
}

bool vtkTranslucency::CacheArrayRanges(vtkDataArray* array)
{
  vtkDoubleArray* doubles = vtkDoubleArray::SafeDownCast(array);
  if (!doubles || doubles->GetNumberOfTuples() == 0 || doubles->GetNumberOfComponents() < 1)
  {
    return false;
  }
  // A valid cache (VTK's test: the ranges set after the array's last
  // modification) is kept: an array passed through from upstream.
  if (doubles->HasInformation() &&
    doubles->GetInformation()->Has(vtkAbstractArray::PER_COMPONENT()) &&
    doubles->GetMTime() <= doubles->GetInformation()->GetMTime())
  {
    return false;
  }
  const int c = doubles->GetNumberOfComponents();
  std::vector<double> range;
  if (!Ranges(doubles->GetPointer(0), doubles->GetNumberOfTuples(), c, range))
  {
    return false;
  }
  vtkInformation* info = doubles->GetInformation();
  SetComponentRanges(info, vtkAbstractArray::PER_COMPONENT(), range, c);
  SetComponentRanges(info, vtkAbstractArray::PER_FINITE_COMPONENT(), range, c);
  if (c > 1)
  {
    const double norm[2] = { std::sqrt(range[2 * c]), std::sqrt(range[2 * c + 1]) };
    info->Set(vtkDataArray::L2_NORM_RANGE(), norm, 2);
    info->Set(vtkDataArray::L2_NORM_FINITE_RANGE(), norm, 2);
  }
  return true;
}

int vtkTranslucency::CacheDataSetRanges(vtkDataObject* data)
{
  vtkDataSet* dataSet = vtkDataSet::SafeDownCast(data);
  if (!dataSet)
  {
    return 0;
  }
  int cached = 0;
  for (vtkDataSetAttributes* attributes :
    { static_cast<vtkDataSetAttributes*>(dataSet->GetPointData()),
      static_cast<vtkDataSetAttributes*>(dataSet->GetCellData()) })
  {
    for (int a = 0; a < attributes->GetNumberOfArrays(); ++a)
    {
      cached += vtkTranslucency::CacheArrayRanges(attributes->GetArray(a)) ? 1 : 0;
    }
  }
  return cached;
}

int vtkTranslucency::CacheOutputRanges(vtkInformationVector* outputVector)
{
  int cached = 0;
  for (int port = 0; port < outputVector->GetNumberOfInformationObjects(); ++port)
  {
    cached += vtkTranslucency::CacheDataSetRanges(vtkDataObject::GetData(outputVector, port));
  }
  return cached;
}

bool vtkTranslucency::IsParaViewExecutive(vtkExecutive* executive)
{
  return executive && executive->IsA("vtkPVCompositeDataPipeline");
}
