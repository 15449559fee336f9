/**
 * @class pqTranslucencyLinearSolverDecorator
 * @brief Solve Diffusion's Linear Solver drop-down lists only what the chosen
 * Solver accepts.
 *
 * The accepted linear solvers of each diffusion solver are its registry
 * entry's (translucency::DiffusionSolverTraits::LinearSolvers), which the
 * filter hands to the panel as the information property LinearSolverTable
 * (pairs: solver name, linear solver name; vtkSolveDiffusion::
 * GetLinearSolverTable). Whenever the Solver drop-down changes (its unchecked
 * value, before Apply) or the Linear Solver's StringListDomain is refreshed
 * from LinearSolverNames (every name of the build, from the server), this
 * decorator sets the client's copy of LinearSolverNames to "default" and the
 * chosen solver's names; the domain and its combo box follow.
 * A Linear Solver value the new Solver does not accept becomes "default".
 *
 * XML (the hint on the LinearSolver property):
 * @code
 * <PropertyWidgetDecorator type="TranslucencyLinearSolverDecorator"
 *                          solver_property="Solver" table_property="LinearSolverTable"/>
 * @endcode
 * Both attributes are optional (these are the defaults).
 *
 * @warning Only the GUI has decorators: in pvpython the domain lists every
 * name of the build (LinearSolverNames), and a name the chosen solver does
 * not accept makes Solve Diffusion fail with an error naming what it accepts.
 */
#ifndef pqTranslucencyLinearSolverDecorator_h
#define pqTranslucencyLinearSolverDecorator_h

#include "pqPropertyWidgetDecorator.h"

#include <vtkWeakPointer.h>

#include <string>
#include <vector>

class vtkSMProperty;
class vtkSMStringListDomain;

class pqTranslucencyLinearSolverDecorator : public pqPropertyWidgetDecorator
{
  Q_OBJECT
  typedef pqPropertyWidgetDecorator Superclass;

public:
  pqTranslucencyLinearSolverDecorator(vtkPVXMLElement* config, pqPropertyWidget* parent);
  ~pqTranslucencyLinearSolverDecorator() override;

  /// "default" and the names LinearSolverTable pairs with `solver`.
  std::vector<std::string> AcceptedNames(const std::string& solver) const;

private Q_SLOTS:
  /// Sets the domain's strings from the Solver's unchecked value.
  void updateChoices();

private:
  Q_DISABLE_COPY(pqTranslucencyLinearSolverDecorator)

  vtkWeakPointer<vtkSMProperty> Solver;
  vtkWeakPointer<vtkSMProperty> Table;
  vtkWeakPointer<vtkSMStringListDomain> Domain;
  unsigned long SolverObserver = 0;
  unsigned long DomainObserver = 0;
  bool Updating = false;
};

#endif
