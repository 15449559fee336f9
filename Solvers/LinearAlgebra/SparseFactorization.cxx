/**
 * @file SparseFactorization.cxx
 * @brief The registry of direct factorisations (SparseFactorization.h):
 * CHOLMOD's supernodal LLT when this build has CHOLMOD, Eigen's simplicial
 * LDLT always.
 */
#include "SparseFactorization.h"

#include "Error.h"
#include "Strings.h"

#ifdef TRANSLUCENCY_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#endif
#include <Eigen/SparseCholesky>

namespace translucency
{

namespace
{

/// One of Eigen's sparse Cholesky classes as a SparseFactorization.
template <typename EigenSolver>
class EigenFactorization : public SparseFactorization
{
public:
  explicit EigenFactorization(std::string name)
    : Name_(std::move(name))
  {
  }
  std::string GetName() const override { return Name_; }
  void AnalyzePattern(const Eigen::SparseMatrix<double>& matrix) override
  {
    Solver_.analyzePattern(matrix);
  }
  bool Factorize(const Eigen::SparseMatrix<double>& matrix) override
  {
    Solver_.factorize(matrix);
    return Solver_.info() == Eigen::Success;
  }
  void Solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const override
  {
    x = Solver_.solve(rhs);
  }
  void Solve(const Eigen::MatrixXd& rhs, Eigen::MatrixXd& x) const override
  {
    x = Solver_.solve(rhs);
  }

private:
  std::string Name_;
  EigenSolver Solver_;
};

template <typename EigenSolver>
SparseFactorizationRegistry::Entry Make(
  const std::string& name, SparseFactorizationTraits traits, const std::string& help)
{
  return { name,
    [name] {
      return std::unique_ptr<SparseFactorization>(
        std::make_unique<EigenFactorization<EigenSolver>>(name));
    },
    std::move(traits), help };
}

SparseFactorizationRegistry MakeRegistry()
{
  SparseFactorizationRegistry r("sparse factorization");
  const std::string cholmodName = "cholmod-supernodal";
  const std::string cholmodHelp =
    "CHOLMOD's supernodal Cholesky (BLAS does the dense work), the default when built";
  SparseFactorizationTraits cholmod{ "CHOLMOD", true,
    "TRANSLUCENCY_USE_CHOLMOD was off or CMake did not find CHOLMOD: install libsuitesparse-dev" };
#ifdef TRANSLUCENCY_HAVE_CHOLMOD
  r.Add(Make<Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower>>(
    cholmodName, cholmod, cholmodHelp));
#else
  cholmod.Built = false;
  r.Add({ cholmodName, []() -> std::unique_ptr<SparseFactorization> { return nullptr; },
    cholmod, cholmodHelp });
#endif
  r.Add(Make<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower>>(
    "eigen-simplicial-ldlt", {}, "Eigen's simplicial LDLT (no library needed)"));
  return r;
}

} // namespace

const SparseFactorizationRegistry& GetSparseFactorizationRegistry()
{
  static const SparseFactorizationRegistry registry = MakeRegistry();
  return registry;
}

std::string GetDefaultSparseFactorizationName()
{
  for (const auto& entry : GetSparseFactorizationRegistry().GetEntries())
  {
    if (entry.Properties.Built)
    {
      return entry.Name;
    }
  }
  throw Error("no sparse factorization is built"); // eigen-simplicial-ldlt always is
}

std::unique_ptr<SparseFactorization> CreateSparseFactorization(const std::string& name)
{
  const SparseFactorizationRegistry& registry = GetSparseFactorizationRegistry();
  const auto& entry = registry.Get(name.empty() ? GetDefaultSparseFactorizationName() : name);
  if (!entry.Properties.Built)
  {
    throw Error("sparse factorization '" + entry.Name + "' is not in this build (" +
      entry.Properties.Remedy + " and reconfigure)");
  }
  return entry.Create();
}

} // namespace translucency
