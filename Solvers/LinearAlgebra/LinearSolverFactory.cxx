#include "LinearSolver.h"

#include "AggregationMultigrid.h"
#include "ConjugateGradient.h"
#include "Error.h"
#include "MultiresSolvers.h"
#include "Strings.h"
#include "IncompleteCholeskySolver.h"
#ifdef TRANSLUCENCY_HAVE_CHOLMOD
#include "CholmodSolver.h"
#endif
#ifdef TRANSLUCENCY_HAVE_HYPRE
#include "HypreSolver.h"
#endif

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

} // namespace

std::vector<std::string> GetLinearSolverNames()
{
  std::vector<std::string> names{ "cg-jacobi" };
  names.push_back("transcut-multires");
  names.push_back("multigrid-cg");
  names.push_back("multigrid-agg");
  // Peers (optional libraries only when this build found them).
  names.push_back("cg-ichol");
#ifdef TRANSLUCENCY_HAVE_CHOLMOD
  names.push_back("cholmod");
#endif
#ifdef TRANSLUCENCY_HAVE_HYPRE
  names.push_back("hypre-amg");
#endif
  return names;
}

std::unique_ptr<LinearSolver> CreateLinearSolver(const std::string& name)
{
  const std::string key = ToLower(name);
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
  if (key == "multigrid-agg")
  {
    return std::make_unique<AggregationMultigridSolver>();
  }
  if (key == "cg-ichol")
  {
    return std::make_unique<IncompleteCholeskySolver>();
  }
#ifdef TRANSLUCENCY_HAVE_CHOLMOD
  if (key == "cholmod")
  {
    return std::make_unique<CholmodSolver>();
  }
#endif
#ifdef TRANSLUCENCY_HAVE_HYPRE
  if (key == "hypre-amg")
  {
    return std::make_unique<HypreSolver>();
  }
#endif
  std::string known;
  for (const auto& n : GetLinearSolverNames())
  {
    known += (known.empty() ? "" : ", ") + n;
  }
  if (key == "cholmod" || key == "hypre-amg")
  {
    throw Error("linear solver '" + name + "' is not in this build (" +
      (key == "cholmod"
          ? std::string("TRANSLUCENCY_USE_CHOLMOD was off or CMake did not find CHOLMOD: "
                        "install libsuitesparse-dev")
          : std::string("TRANSLUCENCY_USE_HYPRE was off or CMake did not find hypre: "
                        "install libhypre-dev")) +
      " and reconfigure; this build has: " + known + ")");
  }
  throw Error("unknown linear solver '" + name + "' (this build has: " + known + ")");
}

} // namespace translucency
