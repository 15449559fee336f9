#include "vtkTranslucencyDispatch.h"

#include "vtkTranslucencyOutputGuard.h"
#include "vtkTranslucencyParallel.h"
#include "vtkTranslucencyRanges.h"
#include "vtkTranslucencyThreads.h"

#include <vtkAlgorithm.h>
#include <vtkDataObject.h>
#include <vtkExecutive.h>
#include <vtkInformationVector.h>
#include <vtkObject.h>

#include <exception>

namespace
{
/// A number for the plan, equal on ranks that planned alike.
int PlanCode(const vtkTranslucencyParallelPlan& plan)
{
  return 2 * static_cast<int>(plan.Kind) + static_cast<int>(plan.Mode);
}

int Fail(vtkAlgorithm* self, vtkInformationVector* outputVector, const std::string& message)
{
  vtkErrorWithObjectMacro(self, << message);
  vtkTranslucencyDispatch::EmptyOutputs(outputVector);
  return 0;
}
}

void vtkTranslucencyDispatch::EmptyOutputs(vtkInformationVector* outputVector)
{
  for (int port = 0; port < outputVector->GetNumberOfInformationObjects(); ++port)
  {
    vtkTranslucencyOutputGuard::MakeEmpty(vtkDataObject::GetData(outputVector, port));
  }
}

namespace
{
/// Run(): plan, agree, run the path.
int RunPath(vtkAlgorithm* self, vtkInformation* request, vtkInformationVector** inputVector,
  vtkInformationVector* outputVector, const vtkTranslucencyDispatch::Planner& planner,
  const vtkTranslucencyDispatch::Paths& paths, vtkTranslucencyDispatch::Record record)
{
  const vtkTranslucencyCommunicator comm = vtkTranslucencyCommunicator::World();
  // 1. The override (local: the environment may differ per rank) and the plan (collective).
  std::string error;
  bool forced = false;
  try
  {
    forced = vtkTranslucencyParallelPlan::ReadOverride();
  }
  catch (const std::exception& e)
  {
    error = e.what();
  }
  vtkTranslucencyParallelPlan plan = planner(inputVector, comm);
  const bool deprecated = vtkTranslucencyParallelPlan::IsSet(plan.DeprecatedVariable);
  // 2. Agree: the override's error, then the override (any rank) and the plan.
  error = comm.AgreeOnError(error);
  if (!error.empty())
  {
    record.Path = "serial";
    record.Plan.clear();
    return Fail(self, outputVector, error);
  }
  if (comm.Any(forced || deprecated) && plan.Kind != vtkTranslucencyParallelPlan::Kinds::Gathered)
  {
    plan.Kind = vtkTranslucencyParallelPlan::Kinds::Gathered;
    plan.Reason = forced || !plan.DeprecatedVariable
      ? std::string("TRANSLUCENCY_PARALLEL=gathered")
      : std::string(plan.DeprecatedVariable) + " (deprecated: use TRANSLUCENCY_PARALLEL=gathered)";
  }
  record.Plan = plan.Describe();
  const int code = PlanCode(plan);
  if (comm.Min(code) != comm.Max(code))
  {
    record.Path = "serial";
    return Fail(self, outputVector,
      "the ranks planned different parallel paths (this rank: " + record.Plan +
        "): every rank must see the same filter settings and environment");
  }
  // 3. The path.
  if (!comm.IsParallel())
  {
    record.Path = "serial";
    return paths.Serial(request, inputVector, outputVector);
  }
  // OpenMP threads per rank = cores / ranks on the node (collective).
  const vtkTranslucency::ThreadsPerRankScope threads(comm);
  switch (plan.Kind)
  {
    case vtkTranslucencyParallelPlan::Kinds::PerPiece:
    case vtkTranslucencyParallelPlan::Kinds::Distributed:
    {
      const bool perPiece = plan.Kind == vtkTranslucencyParallelPlan::Kinds::PerPiece;
      const vtkTranslucencyDispatch::PiecePath& path = perPiece ? paths.PerPiece : paths.Distributed;
      record.Path = plan.GetKindName();
      if (!path)
      {
        return Fail(self, outputVector,
          std::string("internal error: the plan is '") + plan.GetKindName() +
            "' but the filter has no such path");
      }
      return comm.RunAgreed(self, outputVector,
        [&]() { return path(inputVector, outputVector, comm); });
    }
    case vtkTranslucencyParallelPlan::Kinds::Replicated:
      record.Path = plan.GetKindName();
      return vtkTranslucencyParallel::RunGathered(
        self, request, inputVector, outputVector, plan.Mode, paths.Serial, comm, true);
    default:
      record.Path = "gathered";
      return vtkTranslucencyParallel::RunGathered(
        self, request, inputVector, outputVector, plan.Mode, paths.Serial, comm);
  }
}
}

int vtkTranslucencyDispatch::Run(vtkAlgorithm* self, vtkInformation* request,
  vtkInformationVector** inputVector, vtkInformationVector* outputVector, const Planner& planner,
  const Paths& paths, Record record)
{
  // Under ParaView's executive, the new output arrays' ranges, once, in
  // parallel (vtkTranslucencyRanges.h: what ParaView asks for after every
  // execution; elsewhere nothing asks, and nothing changes).
  const int result = RunPath(self, request, inputVector, outputVector, planner, paths, record);
  if (result == 1 && vtkTranslucency::IsParaViewExecutive(self->GetExecutive()))
  {
    vtkTranslucency::CacheOutputRanges(outputVector);
  }
  return result;
}
