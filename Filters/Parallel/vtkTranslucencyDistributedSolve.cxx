#include "vtkTranslucencyDistributedSolve.h"


#ifdef TRANSLUCENCY_HAVE_DISTRIBUTED_SOLVE
#include "DistributedVertexSolver.h"
#include "Error.h"
#include "vtkTranslucencyMPI.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyPieceFaces.h"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDataSetAttributes.h>
#include <vtkMPI.h>
#include <vtkMPICommunicator.h>
#include <vtkMultiProcessController.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

struct vtkTranslucencyDistributedSolve::Impl
{
  std::unique_ptr<translucency::DistributedVertexSolver> Solver;
  std::string Discretization;
};

bool vtkTranslucencyDistributedSolve::Solve(vtkUnstructuredGrid* input,
  const std::string& discretization, double relTol, int maxIter, bool warmStart, int threads,
  const translucency::Sources* sources, const std::vector<translucency::Detector>& detectors,
  std::vector<double>& fluence, std::vector<translucency::DetectorReading>& readings,
  translucency::SolverReport& report, std::string& error)
{
  readings.clear();
  MPI_Comm comm = *vtkTranslucency::MPIHandle(vtkTranslucencyCommunicator::World());
  std::string local;
  std::vector<double> points;
  std::vector<int> cells;
  std::vector<int> tets;
  translucency::OpticalProperties material;
  std::vector<double> irradiance;
  std::vector<translucency::PointKey> keys;
  const vtkIdType numPoints = input ? input->GetNumberOfPoints() : 0;
  try
  {
    if (numPoints > 0 && !vtkTranslucency::ToTetArrays(input, points, cells, local))
    {
      throw translucency::Error(local);
    }
    // Owned cells only: a ghost copy is another rank's tet.
    const std::vector<vtkIdType> kept = vtkTranslucency::OwnedTets(input, cells, tets);
    cells = {};
    if (!kept.empty())
    {
      translucency::OpticalProperties all;
      if (!vtkTranslucency::ToOpticalProperties(input, all, local))
      {
        throw translucency::Error(local);
      }
      for (vtkIdType c : kept)
      {
        for (int k = 0; k < 3; ++k)
        {
          material.AbsorptionCoefficient.push_back(all.AbsorptionCoefficient[3 * c + k]);
          material.ReducedScatteringCoefficient.push_back(
            all.ReducedScatteringCoefficient[3 * c + k]);
        }
        material.RefractiveIndex.push_back(all.RefractiveIndex[c]);
      }
    }
    if (!kept.empty() &&
      !vtkTranslucency::ReadPointArray(input, vtkTranslucency::IrradianceName, 3, irradiance, local))
    {
      if (local.find("no point array") != std::string::npos)
      {
        local += ": compute it with vtkSurfaceIrradiance or supply your own";
      }
      throw translucency::Error(local);
    }
    if (kept.empty())
    {
      irradiance.assign(3 * static_cast<size_t>(numPoints), 0.0); // no tet reads it
    }
  }
  catch (const translucency::Error& e)
  {
    local = e.what();
  }
  catch (const std::exception& e)
  {
    local = e.what();
  }
  // Global ids when every rank with points has them, else coordinates.
  vtkTranslucency::MakePointKeys(comm, input, points, !local.empty(), keys);
  try
  {
    translucency::AgreeOnError(comm, local);
    if (!this->Internal->Solver || this->Internal->Discretization != discretization)
    {
      this->Internal->Solver =
        std::make_unique<translucency::DistributedVertexSolver>(comm, discretization);
      this->Internal->Discretization = discretization;
    }
    translucency::DistributedVertexSolver& solver = *this->Internal->Solver;
    solver.SetRelTol(relTol);
    solver.SetMaxIter(maxIter);
    solver.SetWarmStart(warmStart);
    solver.SetNumberOfThreads(threads);
    solver.SetInteriorSources(sources);
    solver.SetDetectors(detectors);
    solver.Solve(points, keys, tets, material, irradiance, fluence, report);
    solver.SetInteriorSources(nullptr); // not kept past this call
    readings = solver.GetDetectorReadings();
  }
  catch (const translucency::Error& e)
  {
    error = e.what(); // the same on every rank (AgreeOnError)
    this->Internal->Solver.reset();
    return false;
  }
  return true;
}

bool vtkTranslucencyDistributedSolve::GetPowerBalance(
  double injected[3], double absorbed[3], double escaped[3]) const
{
  if (!this->Internal->Solver)
  {
    return false;
  }
  const translucency::PowerBalance& balance = this->Internal->Solver->GetPowerBalance();
  const auto& sources = this->Internal->Solver->GetInjectedSourcePower();
  for (int c = 0; c < 3; ++c)
  {
    injected[c] = balance.BoundaryInjected[c] + sources[c];
    absorbed[c] = balance.Absorbed[c];
    escaped[c] = balance.Escaped[c];
  }
  return true;
}

#else // no distributed solve in this build

struct vtkTranslucencyDistributedSolve::Impl
{
};

bool vtkTranslucencyDistributedSolve::Solve(vtkUnstructuredGrid*, const std::string&, double,
  int, bool, int, const translucency::Sources*, const std::vector<translucency::Detector>&,
  std::vector<double>&, std::vector<translucency::DetectorReading>&, translucency::SolverReport&,
  std::string& error)
{
  error = "this build has no distributed solve (hypre or VTK's ParallelMPI missing)";
  return false;
}

bool vtkTranslucencyDistributedSolve::GetPowerBalance(double*, double*, double*) const
{
  return false;
}

#endif

vtkTranslucencyDistributedSolve::vtkTranslucencyDistributedSolve()
  : Internal(new Impl)
{
}

vtkTranslucencyDistributedSolve::~vtkTranslucencyDistributedSolve() = default;

