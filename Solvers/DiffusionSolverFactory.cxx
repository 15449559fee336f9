#include "DiffusionSolver.h"

#include "DiscreteDivergence.h"
#include "Error.h"
#include "VertexDiffusionSolver.h"

#include <algorithm>
#include <cctype>

namespace translucency
{

std::vector<std::string> GetDiffusionSolverNames()
{
  return { "divergence" };
}

std::unique_ptr<DiffusionSolver> CreateDiffusionSolver(const std::string& name)
{
  std::string key = name;
  std::transform(key.begin(), key.end(), key.begin(),
    [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  if (key == "divergence")
  {
    return std::make_unique<VertexDiffusionSolver>(std::make_unique<DiscreteDivergence>());
  }
  std::string known;
  for (const std::string& n : GetDiffusionSolverNames())
  {
    known += (known.empty() ? "" : ", ") + n;
  }
  throw Error("unknown solver '" + name + "' (known solvers: " + known + ")");
}

} // namespace translucency
