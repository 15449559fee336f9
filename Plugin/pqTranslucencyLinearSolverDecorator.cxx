#include "pqTranslucencyLinearSolverDecorator.h"

#include "pqPropertyWidget.h"

#include <vtkCommand.h>
#include <vtkPVXMLElement.h>
#include <vtkSMEnumerationDomain.h>
#include <vtkSMProperty.h>
#include <vtkSMPropertyHelper.h>
#include <vtkSMProxy.h>
#include <vtkSMStringListDomain.h>
#include <vtkSMStringVectorProperty.h>
#include <vtkSMUncheckedPropertyHelper.h>

#include <algorithm>

namespace
{
const char* Attribute(vtkPVXMLElement* config, const char* name, const char* fallback)
{
  const char* value = config ? config->GetAttribute(name) : nullptr;
  return value ? value : fallback;
}
} // namespace

pqTranslucencyLinearSolverDecorator::pqTranslucencyLinearSolverDecorator(
  vtkPVXMLElement* config, pqPropertyWidget* parent)
  : Superclass(config, parent)
{
  vtkSMProxy* proxy = parent->proxy();
  vtkSMProperty* linearSolver = parent->property();
  if (!proxy || !linearSolver)
  {
    return;
  }
  this->Solver = proxy->GetProperty(Attribute(config, "solver_property", "Solver"));
  this->Table = proxy->GetProperty(Attribute(config, "table_property", "LinearSolverTable"));
  this->Domain = linearSolver->FindDomain<vtkSMStringListDomain>();
  if (!this->Solver || !this->Table || !this->Domain)
  {
    qWarning("TranslucencyLinearSolverDecorator: the proxy has no Solver, LinearSolverTable "
             "or a StringListDomain on the decorated property");
    return;
  }
  // Plain VTK observers (the events fire synchronously, on this thread).
  this->SolverObserver = this->Solver->AddObserver(vtkCommand::UncheckedPropertyModifiedEvent,
    this, &pqTranslucencyLinearSolverDecorator::updateChoices);
  this->DomainObserver = this->Domain->AddObserver(
    vtkCommand::DomainModifiedEvent, this, &pqTranslucencyLinearSolverDecorator::updateChoices);
  this->updateChoices();
}

pqTranslucencyLinearSolverDecorator::~pqTranslucencyLinearSolverDecorator()
{
  if (this->Solver && this->SolverObserver)
  {
    this->Solver->RemoveObserver(this->SolverObserver);
  }
  if (this->Domain && this->DomainObserver)
  {
    this->Domain->RemoveObserver(this->DomainObserver);
  }
}

std::vector<std::string> pqTranslucencyLinearSolverDecorator::AcceptedNames(
  const std::string& solver) const
{
  std::vector<std::string> names{ "default" };
  if (!this->Table)
  {
    return names;
  }
  vtkSMPropertyHelper table(this->Table);
  const unsigned int count = table.GetNumberOfElements();
  for (unsigned int i = 0; i + 1 < count; i += 2)
  {
    const char* owner = table.GetAsString(i);
    const char* name = table.GetAsString(i + 1);
    if (owner && name && solver == owner)
    {
      names.emplace_back(name);
    }
  }
  return names;
}

void pqTranslucencyLinearSolverDecorator::updateChoices()
{
  if (this->Updating || !this->Solver || !this->Domain)
  {
    return;
  }
  this->Updating = true;
  auto* solvers = this->Solver->FindDomain<vtkSMEnumerationDomain>();
  const int value = vtkSMUncheckedPropertyHelper(this->Solver).GetAsInt();
  const char* solver = solvers ? solvers->GetEntryTextForValue(value) : nullptr;
  const std::vector<std::string> names = this->AcceptedNames(solver ? solver : "");
  // The domain lists its required information property (LinearSolverNames,
  // every name of the build, from the server): the client's copy of it is set
  // to the chosen solver's names, and the domain follows (its Update). The
  // next information update from the server brings the full list back, the
  // domain changes, and this runs again.
  if (auto* source =
        vtkSMStringVectorProperty::SafeDownCast(this->Domain->GetRequiredProperty("ArrayList")))
  {
    // "default" first, as in the filter's own list (GetAvailableLinearSolvers).
    source->SetElements(names);
  }
  // A value the new solver does not accept goes back to its default.
  vtkSMProperty* linearSolver = this->parentWidget()->property();
  vtkSMUncheckedPropertyHelper current(linearSolver);
  const char* chosen = current.GetAsString(0);
  if (!chosen || std::find(names.begin(), names.end(), chosen) == names.end())
  {
    current.Set("default");
  }
  this->Updating = false;
}
