#include "vtkTranslucencyParallelPlan.h"

#include "Error.h"

#include <cstdlib>
#include <cstring>

vtkTranslucencyParallelPlan vtkTranslucencyParallelPlan::PerPiece(
  GatherMode ifGathered, const std::string& reason)
{
  vtkTranslucencyParallelPlan plan;
  plan.Kind = Kinds::PerPiece;
  plan.Mode = ifGathered;
  plan.Reason = reason;
  return plan;
}

vtkTranslucencyParallelPlan vtkTranslucencyParallelPlan::Distributed(
  GatherMode ifGathered, const std::string& reason)
{
  vtkTranslucencyParallelPlan plan = PerPiece(ifGathered, reason);
  plan.Kind = Kinds::Distributed;
  return plan;
}

vtkTranslucencyParallelPlan vtkTranslucencyParallelPlan::Gathered(
  GatherMode mode, const std::string& reason)
{
  vtkTranslucencyParallelPlan plan = PerPiece(mode, reason);
  plan.Kind = Kinds::Gathered;
  return plan;
}

vtkTranslucencyParallelPlan vtkTranslucencyParallelPlan::Replicated(const std::string& reason)
{
  vtkTranslucencyParallelPlan plan = PerPiece(GatherMode::SameMesh, reason);
  plan.Kind = Kinds::Replicated;
  return plan;
}

const char* vtkTranslucencyParallelPlan::GetKindName() const
{
  switch (this->Kind)
  {
    case Kinds::PerPiece:
      return "per piece";
    case Kinds::Distributed:
      return "distributed";
    case Kinds::Gathered:
      return "gathered";
    case Kinds::Replicated:
      return "replicated";
    default:
      return "serial";
  }
}

std::string vtkTranslucencyParallelPlan::Describe() const
{
  std::string text = this->GetKindName();
  if (this->Kind == Kinds::Gathered)
  {
    text += this->Mode == GatherMode::SameMesh ? " (same mesh)" : " (rank 0)";
  }
  return this->Reason.empty() ? text : text + ": " + this->Reason;
}

bool vtkTranslucencyParallelPlan::IsSet(const char* variable)
{
  const char* value = variable ? std::getenv(variable) : nullptr;
  return value && *value && std::strcmp(value, "0") != 0;
}

bool vtkTranslucencyParallelPlan::ReadOverride()
{
  const char* value = std::getenv("TRANSLUCENCY_PARALLEL");
  if (!value || !*value || std::strcmp(value, "auto") == 0)
  {
    return false;
  }
  if (std::strcmp(value, "gathered") == 0)
  {
    return true;
  }
  throw translucency::Error(std::string("TRANSLUCENCY_PARALLEL='") + value +
    "': expected 'auto' (each filter's own plan, the default) or 'gathered' (every filter "
    "gathers its input to rank 0)");
}
