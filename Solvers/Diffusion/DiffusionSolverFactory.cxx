#include "DiffusionSolverFactory.h"

#include "DiscreteDivergence.h"
#include "Error.h"
#include "FiniteElement.h"
#include "GridSolver.h"
#include "MonteCarlo.h"
#include "QuadGraph.h"
#include "Strings.h"
#include "VertexDiffusionSolver.h"

#include <algorithm>
#include <cctype>

namespace translucency
{

std::vector<std::string> GetDiffusionSolverNames()
{
  return { "divergence", "fem", "quadgraph", "grid", "montecarlo" };
}

std::unique_ptr<DiffusionSolver> CreateDiffusionSolver(const std::string& name)
{
  std::string key = name;
  key = ToLower(key);
  if (key == "divergence")
  {
    return std::make_unique<VertexDiffusionSolver>(std::make_unique<DiscreteDivergence>());
  }
  if (key == "fem")
  {
    return std::make_unique<VertexDiffusionSolver>(std::make_unique<FiniteElement>());
  }
  if (key == "quadgraph")
  {
    return std::make_unique<QuadGraphSolver>();
  }
  if (key == "grid")
  {
    return std::make_unique<GridSolver>();
  }
  if (key == "montecarlo")
  {
    return std::make_unique<MonteCarloSolver>();
  }
  std::string known;
  for (const std::string& n : GetDiffusionSolverNames())
  {
    known += (known.empty() ? "" : ", ") + n;
  }
  throw Error("unknown solver '" + name + "' (known solvers: " + known + ")");
}

} // namespace translucency
