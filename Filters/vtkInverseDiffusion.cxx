#include "vtkInverseDiffusion.h"

#include "vtkTranslucencyDispatch.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"

#include "DiffusionForwardModel.h"
#include "Error.h"
#include "InverseDiffusion.h"
#include "TetMesh.h"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkTable.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>
#include <sstream>

vtkStandardNewMacro(vtkInverseDiffusion);

vtkInverseDiffusion::vtkInverseDiffusion()
{
  this->SetNumberOfOutputPorts(2);
}

vtkInverseDiffusion::~vtkInverseDiffusion() = default;

void vtkInverseDiffusion::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Lambda: " << this->Lambda << "\n";
  os << indent << "MaxIterations: " << this->MaxIterations << "\n";
  os << indent << "RelativeThreshold: " << this->RelativeThreshold << "\n";
  os << indent << "InitialAbsorption: " << this->InitialAbsorption[0] << " "
     << this->InitialAbsorption[1] << " " << this->InitialAbsorption[2] << "\n";
  os << indent << "InitialReducedScattering: " << this->InitialReducedScattering[0] << " "
     << this->InitialReducedScattering[1] << " " << this->InitialReducedScattering[2] << "\n";
  os << indent << "HomogeneousFit: " << this->HomogeneousFit << "\n";
  os << indent << "HomogeneousMethod: "
     << (this->HomogeneousMethod == GAUSS_NEWTON ? "GaussNewton" : "ConjugateGradient") << "\n";
  os << indent << "GaussNewtonLineSearch: " << this->GaussNewtonLineSearch << "\n";
  os << indent << "ElementArrayName: " << this->ElementArrayName << "\n";
  os << indent << "DefaultRefractiveIndex: " << this->DefaultRefractiveIndex << "\n";
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}

int vtkInverseDiffusion::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
  return 1;
}

int vtkInverseDiffusion::FillOutputPortInformation(int port, vtkInformation* info)
{
  if (port == 1)
  {
    info->Set(vtkDataObject::DATA_TYPE_NAME(), "vtkTable");
    return 1;
  }
  return this->Superclass::FillOutputPortInformation(port, info);
}

namespace
{
std::string Indexed(const char* base, int k)
{
  return std::string(base) + "_" + std::to_string(k);
}

int CountIndexed(vtkPointData* pd, const char* base)
{
  int k = 0;
  while (pd->GetAbstractArray(Indexed(base, k).c_str()))
  {
    ++k;
  }
  return k;
}
} // namespace

namespace
{
/// RequestData: the measurements Irradiance_<k>, Radiance_<k> and
/// ObservedMask[_<k>] of the input (false: the error).
bool ReadMeasurements(vtkUnstructuredGrid* input, std::vector<std::vector<double>>& irradiance,
  std::vector<std::vector<double>>& radiance, std::vector<std::vector<unsigned char>>& observed,
  std::string& error)
{
  vtkPointData* pd = input->GetPointData();
  const int numIrradiance = CountIndexed(pd, vtkTranslucency::IrradianceName);
  const int numRadiance = CountIndexed(pd, vtkTranslucency::RadianceName);
  if (numIrradiance == 0)
  {
    error = "the input has no Irradiance_0 point array (one Irradiance_<k> and one "
            "Radiance_<k> per measurement, k = 0, 1, ...)";
    return false;
  }
  if (numIrradiance != numRadiance)
  {
    std::ostringstream os;
    os << "the input has " << numIrradiance << " illumination patterns (Irradiance_<k>) but "
       << numRadiance << " measurements (Radiance_<k>); one of each per pattern";
    error = os.str();
    return false;
  }
  irradiance.resize(numIrradiance);
  radiance.resize(numIrradiance);
  const bool sharedMask = pd->GetArray("ObservedMask") != nullptr;
  const bool perPatternMask = pd->GetArray("ObservedMask_0") != nullptr;
  for (int k = 0; k < numIrradiance; ++k)
  {
    if (!vtkTranslucency::ReadPointArray(
          input, Indexed(vtkTranslucency::IrradianceName, k).c_str(), 3, irradiance[k], error) ||
      !vtkTranslucency::ReadPointArray(
        input, Indexed(vtkTranslucency::RadianceName, k).c_str(), 3, radiance[k], error))
    {
      return false;
    }
    if (sharedMask || perPatternMask)
    {
      const std::string name = perPatternMask ? Indexed("ObservedMask", k) : "ObservedMask";
      std::vector<double> mask;
      if (!vtkTranslucency::ReadPointArray(input, name.c_str(), 1, mask, error))
      {
        return false;
      }
      std::vector<unsigned char> m(mask.size());
      for (size_t i = 0; i < mask.size(); ++i)
      {
        m[i] = mask[i] != 0.0 ? 1 : 0;
      }
      observed.push_back(std::move(m));
    }
  }
  return true;
}

/// RequestData: the element of each tet, numbered densely from the cell
/// array `elementArrayName` ("" : one element per tet).
bool ReadElements(vtkUnstructuredGrid* input, const std::string& elementArrayName, int numTets,
  std::vector<int>& tetElement, int& numElements, std::string& error)
{
  tetElement.assign(numTets, 0);
  numElements = numTets;
  if (!elementArrayName.empty())
  {
    vtkDataArray* ids = input->GetCellData()->GetArray(elementArrayName.c_str());
    if (!ids || ids->GetNumberOfComponents() != 1)
    {
      error = "ElementArrayName '" + elementArrayName + "' is not a 1-component cell array of the input";
      return false;
    }
    std::vector<long long> labels(numTets);
    for (int t = 0; t < numTets; ++t)
    {
      labels[t] = static_cast<long long>(ids->GetTuple1(t));
    }
    tetElement = translucency::DiffusionForwardModel::DenseElements(labels, numElements);
  }
  else
  {
    for (int t = 0; t < numTets; ++t)
    {
      tetElement[t] = t;
    }
  }
  return true;
}

/// RequestData, output mesh: the input with the fitted coefficients per tet
/// (sigma_s' clamped at 0 where 1/(3 kappa) < mu_a: returns how many), eta
/// if the input had none, and the fitted radiance per pattern.
long long AttachFit(vtkUnstructuredGrid* input, const translucency::InverseDiffusionResult& result,
  const std::vector<int>& tetElement, const std::vector<double>& eta,
  const std::vector<std::vector<double>>& fitted, vtkUnstructuredGrid* output)
{
  const int numTets = static_cast<int>(tetElement.size());
  output->ShallowCopy(input);
  std::vector<double> mu(3 * static_cast<size_t>(numTets)), kappa(mu.size()), sigma(mu.size());
  long long clamped = 0;
  for (int t = 0; t < numTets; ++t)
  {
    const int e = tetElement[t];
    for (int c = 0; c < 3; ++c)
    {
      const double k = result.Kappa[3 * e + c], m = result.Absorption[3 * e + c];
      kappa[3 * t + c] = k;
      mu[3 * t + c] = m;
      const double s = 1.0 / (3.0 * k) - m; // kappa = 1 / (3 (mu_a + sigma_s'))
      if (s < 0.0)
      {
        ++clamped;
      }
      sigma[3 * t + c] = std::max(0.0, s);
    }
  }
  vtkCellData* cd = output->GetCellData();
  auto add = [](vtkDataSetAttributes* attributes, vtkDataArray* array) {
    attributes->AddArray(array);
    array->Delete();
  };
  add(cd, vtkTranslucency::NewTripleArray(vtkTranslucency::AbsorptionName, mu));
  add(cd, vtkTranslucency::NewTripleArray(vtkTranslucency::ScatteringName, sigma));
  add(cd, vtkTranslucency::NewTripleArray("DiffusionCoefficient", kappa));
  if (!cd->GetArray(vtkTranslucency::RefractiveIndexName))
  {
    vtkNew<vtkDoubleArray> etaArray;
    etaArray->SetName(vtkTranslucency::RefractiveIndexName);
    etaArray->SetNumberOfValues(numTets);
    for (int t = 0; t < numTets; ++t)
    {
      etaArray->SetValue(t, eta[t]);
    }
    cd->AddArray(etaArray);
  }
  vtkPointData* outPd = output->GetPointData();
  for (size_t k = 0; k < fitted.size(); ++k)
  {
    add(outPd,
      vtkTranslucency::NewTripleArray(Indexed("FittedRadiance", static_cast<int>(k)).c_str(),
        fitted[k]));
  }
  return clamped;
}

/// RequestData: the history table (one row per iteration and channel).
void WriteHistory(const translucency::InverseDiffusionResult& result, vtkTable* history)
{
  const char* names[] = { "Channel", "Stage", "Iteration", "Objective", "DataTerm", "GradientNorm",
    "Step", "Evaluations" };
  std::vector<vtkSmartPointer<vtkDoubleArray>> columns;
  for (const char* name : names)
  {
    auto column = vtkSmartPointer<vtkDoubleArray>::New();
    column->SetName(name);
    column->SetNumberOfValues(static_cast<vtkIdType>(result.History.size()));
    columns.push_back(column);
  }
  for (size_t r = 0; r < result.History.size(); ++r)
  {
    const translucency::InverseDiffusionIteration& h = result.History[r];
    const double row[] = { double(h.Channel), h.Stage == "homogeneous" ? 0.0 : 1.0,
      double(h.Iteration), h.Objective, h.DataTerm, h.GradientNorm, h.Step, double(h.Evaluations) };
    for (size_t k = 0; k < columns.size(); ++k)
    {
      columns[k]->SetValue(static_cast<vtkIdType>(r), row[k]);
    }
  }
  for (auto& column : columns)
  {
    history->AddColumn(column);
  }
}
} // namespace

int vtkInverseDiffusion::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
int vtkInverseDiffusion::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::UpdateExtent(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkInverseDiffusion::PlanParallel(
  vtkInformationVector**, const vtkTranslucencyCommunicator&)
{
  return vtkTranslucencyParallelPlan::Gathered(
    vtkTranslucencyParallelPlan::GatherMode::SameMesh, "the adjoint optimisation needs every tet and every pattern; the history is one table");
}

//------------------------------------------------------------------------------
int vtkInverseDiffusion::RequestSerial(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector, 0);
  vtkTable* history = vtkTable::GetData(outputVector, 1);
  if (!input || !output || !history)
  {
    vtkErrorMacro(<< "missing input or output");
    return 0;
  }
  std::string error;
  std::shared_ptr<const translucency::TetMesh> mesh = vtkTranslucency::AcquireTetMesh(input, error);
  if (!mesh)
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const int numTets = mesh->GetNumberOfTets();

  // Measurements: Irradiance_<k>, Radiance_<k>, ObservedMask[_<k>].
  std::vector<std::vector<double>> irradiance, radiance;
  std::vector<std::vector<unsigned char>> observed;
  if (!ReadMeasurements(input, irradiance, radiance, observed, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }

  // Refractive index and elements.
  std::vector<double> eta;
  if (input->GetCellData()->GetArray(vtkTranslucency::RefractiveIndexName))
  {
    if (!vtkTranslucency::ReadRefractiveIndex(input, eta, error))
    {
      vtkErrorMacro(<< error);
      return 0;
    }
  }
  else
  {
    eta.assign(numTets, this->DefaultRefractiveIndex);
  }
  std::vector<int> tetElement;
  int numElements = 0;
  if (!ReadElements(input, this->ElementArrayName, numTets, tetElement, numElements, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  this->UpdateProgress(0.02);

  translucency::InverseDiffusionResult result;
  std::vector<std::vector<double>> fitted;
  try
  {
    translucency::DiffusionForwardModel model(*mesh, tetElement, numElements, eta);
    translucency::InverseDiffusion inverse(model);
    inverse.SetMeasurements(irradiance, radiance, observed);
    inverse.SetLambda(this->Lambda);
    inverse.SetMaxIter(this->MaxIterations);
    inverse.SetRelativeThreshold(this->RelativeThreshold);
    inverse.SetInitialAbsorption(
      { this->InitialAbsorption[0], this->InitialAbsorption[1], this->InitialAbsorption[2] });
    inverse.SetInitialReducedScattering({ this->InitialReducedScattering[0],
      this->InitialReducedScattering[1], this->InitialReducedScattering[2] });
    inverse.SetHomogeneousFit(this->HomogeneousFit);
    inverse.SetHomogeneousMethod(this->HomogeneousMethod == GAUSS_NEWTON
        ? translucency::InverseDiffusion::HomogeneousMethod::GaussNewton
        : translucency::InverseDiffusion::HomogeneousMethod::ConjugateGradient);
    inverse.SetGaussNewtonLineSearch(this->GaussNewtonLineSearch);
    // Called from one worker thread (OpenMP thread 0, which is this thread).
    inverse.SetProgressCallback([this](double f) {
      this->UpdateProgress(0.02 + 0.9 * f);
      return !this->CheckAbort();
    });
    result = inverse.Run();
    if (result.Aborted)
    {
      vtkWarningMacro(<< "aborted: the output holds the parameters reached so far");
    }
    fitted = translucency::InverseDiffusion::PredictRadiance(
      model, result.Kappa, result.Absorption, irradiance);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  this->NumberOfEvaluations = result.Evaluations;
  this->NumberOfGradients = result.Gradients;
  this->EvaluationSeconds = result.EvaluationSeconds;
  this->GradientSeconds = result.GradientSeconds;
  this->NumberOfTangents = result.Tangents;
  this->TangentSeconds = result.TangentSeconds;

  // Output mesh.
  const long long clamped = AttachFit(input, result, tetElement, eta, fitted, output);
  if (clamped > 0)
  {
    vtkWarningMacro(<< clamped << " tet/channel values have 1/(3 kappa) < mu_a: their "
                    << "ReducedScatteringCoefficient is clamped at 0 (DiffusionCoefficient holds "
                    << "the fitted kappa)");
  }

  // History table.
  WriteHistory(result, history);
  this->UpdateProgress(1.0);
  return outputs.Succeed();
}
