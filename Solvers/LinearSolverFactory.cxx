#include "LinearSolver.h"

#include "ConjugateGradient.h"
#include "Error.h"
#include "MultiresSolvers.h"

#include <algorithm>
#include <cctype>

namespace translucency
{

namespace
{

/// Jacobi-preconditioned CG (Eigen), the default.
class JacobiConjugateGradient : public LinearSolver
{
public:
  std::string GetName() const override { return "cg-jacobi"; }

  void Setup(const DiffusionSystem&, const TetMesh*, bool) override {}

  bool Solve(const DiffusionSystem& system, std::array<Eigen::VectorXd, NumberOfChannels>& x,
    bool warmStart, std::array<LinearSolveStats, NumberOfChannels>& stats) override
  {
    CG_.SetRelTol(RelTol_);
    CG_.SetMaxIter(MaxIter_);
    CG_.SetProgressCallback(Progress_);
    const bool done = CG_.Solve(system, x, warmStart);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      stats[c].Iterations = CG_.GetNumIterations(c);
      stats[c].RelativeResidual = CG_.GetFinalNorm(c);
      stats[c].Converged = CG_.GetConverged(c);
      // One SpMV per iteration plus the initial residual.
      stats[c].SpMVEquivalents = CG_.GetNumIterations(c) + 1.0;
    }
    return done;
  }

private:
  ConjugateGradient CG_;
};

std::string Lower(std::string s)
{
  std::transform(s.begin(), s.end(), s.begin(),
    [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return s;
}

} // namespace

std::vector<std::string> GetLinearSolverNames()
{
  std::vector<std::string> names{ "cg-jacobi" };
  names.push_back("transcut-multires");
  names.push_back("multigrid-cg");
  return names;
}

std::unique_ptr<LinearSolver> CreateLinearSolver(const std::string& name)
{
  const std::string key = Lower(name);
  if (key == "cg-jacobi")
  {
    return std::make_unique<JacobiConjugateGradient>();
  }
  if (key == "transcut-multires")
  {
    return std::make_unique<TransCutMultiresSolver>();
  }
  if (key == "multigrid-cg")
  {
    return std::make_unique<MultigridConjugateGradient>();
  }
  std::string known;
  for (const auto& n : GetLinearSolverNames())
  {
    known += (known.empty() ? "" : ", ") + n;
  }
  throw Error("unknown linear solver '" + name + "' (this build has: " + known + ")");
}

} // namespace translucency
