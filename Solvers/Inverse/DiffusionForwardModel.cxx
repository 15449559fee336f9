#include "DiffusionForwardModel.h"

#include "Error.h"
#include "Fresnel.h"
#include "Radiance.h"
#include "SparseFactorization.h"
#include "TetGeometry.h"
#include "TetMesh.h"
#include "VertexAssembly.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>
#include <tuple>

namespace translucency
{

namespace
{
constexpr double Pi = 3.14159265358979323846;

/// The constructor's neighbouring elements: tets sharing a face, in
/// different elements, each pair once with its finite-volume weight
/// A_ef / d_ef (shared area over the distance of the element centroids).
void FindElementNeighbours(const TetMesh& mesh, const std::vector<int>& tetElement,
  const std::vector<double>& centroid, std::vector<int>& neighbours, std::vector<double>& weights)
{
  const int numTets = mesh.GetNumberOfTets();
  const double* pts = mesh.GetPoints().data();
  std::vector<std::array<int, 4>> faces;
  faces.reserve(4 * static_cast<size_t>(numTets));
  for (int t = 0; t < numTets; ++t)
  {
    const int* tv = mesh.GetTet(t);
    for (int skip = 0; skip < 4; ++skip)
    {
      std::array<int, 4> f;
      int k = 0;
      for (int a = 0; a < 4; ++a)
      {
        if (a != skip)
        {
          f[k++] = tv[a];
        }
      }
      std::sort(f.begin(), f.begin() + 3);
      f[3] = t;
      faces.push_back(f);
    }
  }
  std::sort(faces.begin(), faces.end());
  // (e, f, area of the shared triangle) for every face between two elements.
  std::vector<std::tuple<int, int, double>> shared;
  for (size_t k = 0; k + 1 < faces.size(); ++k)
  {
    const auto& a = faces[k];
    const auto& b = faces[k + 1];
    if (a[0] == b[0] && a[1] == b[1] && a[2] == b[2])
    {
      const int ea = tetElement[a[3]], eb = tetElement[b[3]];
      if (ea != eb)
      {
        const double* p0 = pts + 3 * a[0];
        const double* p1 = pts + 3 * a[1];
        const double* p2 = pts + 3 * a[2];
        const double u[3] = { p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2] };
        const double v[3] = { p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2] };
        const double cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2],
                     cz = u[0] * v[1] - u[1] * v[0];
        shared.emplace_back(
          std::min(ea, eb), std::max(ea, eb), 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz));
      }
    }
  }
  std::sort(shared.begin(), shared.end());
  for (size_t k = 0; k < shared.size();)
  {
    const int e = std::get<0>(shared[k]), f = std::get<1>(shared[k]);
    double area = 0.0;
    for (; k < shared.size() && std::get<0>(shared[k]) == e && std::get<1>(shared[k]) == f; ++k)
    {
      area += std::get<2>(shared[k]);
    }
    const double dx = centroid[3 * e] - centroid[3 * f];
    const double dy = centroid[3 * e + 1] - centroid[3 * f + 1];
    const double dz = centroid[3 * e + 2] - centroid[3 * f + 2];
    neighbours.push_back(e);
    neighbours.push_back(f);
    // Finite-volume weight A_ef / d_ef: sum_pairs w (k_e - k_f)^2 approximates
    // the integral of |grad kappa|^2 over the volume (mm), whatever the grid size.
    weights.push_back(area / std::sqrt(dx * dx + dy * dy + dz * dz));
  }
}

} // namespace

// OpenBLAS thread control, resolved at run time if OpenBLAS is the BLAS in use.
extern "C" void openblas_set_num_threads(int) __attribute__((weak));
extern "C" int openblas_get_num_threads() __attribute__((weak));

int DiffusionForwardModel::SetBlasThreads(int n)
{
  int previous = 0;
  if (openblas_get_num_threads)
  {
    previous = openblas_get_num_threads();
  }
  if (openblas_set_num_threads && n > 0)
  {
    openblas_set_num_threads(n);
  }
  return previous;
}

struct DiffusionForwardModel::Factor::Impl
{
  /// The registry's default factorisation (GetFactorizationName).
  std::unique_ptr<SparseFactorization> Solver = CreateSparseFactorization();
  Eigen::SparseMatrix<double> Matrix;
  bool Analysed = false;
  bool Valid = false;
};

DiffusionForwardModel::Factor::Factor()
  : Impl_(new Impl)
{
}
DiffusionForwardModel::Factor::~Factor() = default;
DiffusionForwardModel::Factor::Factor(Factor&&) noexcept = default;
DiffusionForwardModel::Factor& DiffusionForwardModel::Factor::operator=(Factor&&) noexcept = default;

bool DiffusionForwardModel::Factor::IsValid() const
{
  return Impl_ && Impl_->Valid;
}

void DiffusionForwardModel::Factor::Solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const
{
  if (!IsValid())
  {
    throw Error("DiffusionForwardModel::Factor::Solve: the system is not factorised");
  }
  Impl_->Solver->Solve(rhs, x);
}

void DiffusionForwardModel::Factor::Solve(const Eigen::MatrixXd& rhs, Eigen::MatrixXd& x) const
{
  if (!IsValid())
  {
    throw Error("DiffusionForwardModel::Factor::Solve: the system is not factorised");
  }
  Impl_->Solver->Solve(rhs, x);
}

std::string DiffusionForwardModel::GetFactorizationName()
{
  return GetDefaultSparseFactorizationName();
}

std::vector<int> DiffusionForwardModel::DenseElements(
  const std::vector<long long>& labels, int& numElements)
{
  std::map<long long, int> dense; // labels -> 0..E-1, in increasing order
  for (long long label : labels)
  {
    dense.emplace(label, 0);
  }
  int next = 0;
  for (auto& entry : dense)
  {
    entry.second = next++;
  }
  std::vector<int> elements(labels.size());
  for (size_t t = 0; t < labels.size(); ++t)
  {
    elements[t] = dense[labels[t]];
  }
  numElements = next;
  return elements;
}

DiffusionForwardModel::DiffusionForwardModel(const TetMesh& mesh, std::vector<int> tetElement,
  int numElements, const std::vector<double>& tetEta)
  : Mesh_(mesh)
  , TetElement_(std::move(tetElement))
  , NumberOfElements_(numElements)
{
  const int numTets = mesh.GetNumberOfTets();
  const int numPoints = mesh.GetNumberOfPoints();
  if (numTets == 0)
  {
    throw Error("DiffusionForwardModel: the mesh has no tets");
  }
  if (static_cast<int>(TetElement_.size()) != numTets)
  {
    std::ostringstream os;
    os << "DiffusionForwardModel: " << TetElement_.size() << " element ids for " << numTets
       << " tets";
    throw Error(os.str());
  }
  if (numElements <= 0)
  {
    throw Error("DiffusionForwardModel: the number of elements must be > 0");
  }
  if (static_cast<int>(tetEta.size()) != numTets)
  {
    std::ostringstream os;
    os << "DiffusionForwardModel: RefractiveIndex has " << tetEta.size() << " values for "
       << numTets << " tets";
    throw Error(os.str());
  }
  for (int t = 0; t < numTets; ++t)
  {
    if (!(std::isfinite(tetEta[t]) && tetEta[t] > 0.0))
    {
      std::ostringstream os;
      os << "DiffusionForwardModel: RefractiveIndex of tet " << t << " is " << tetEta[t]
         << ": must be finite and > 0";
      throw Error(os.str());
    }
    if (TetElement_[t] < 0 || TetElement_[t] >= numElements)
    {
      std::ostringstream os;
      os << "DiffusionForwardModel: tet " << t << " has element id " << TetElement_[t]
         << ", outside [0, " << numElements << ")";
      throw Error(os.str());
    }
  }

  // Per-tet geometric stiffness (TransCut eq. 10: w_ijt = kappa_t g_ij).
  TetStiffness_.resize(10 * static_cast<size_t>(numTets));
  ElementCentroid_.assign(3 * static_cast<size_t>(numElements), 0.0);
  ElementVolume_.assign(numElements, 0.0);
  const double* pts = mesh.GetPoints().data();
  for (int t = 0; t < numTets; ++t)
  {
    const int* tv = mesh.GetTet(t);
    const TetGeometry geo = ComputeTetGeometry(
      pts + 3 * tv[0], pts + 3 * tv[1], pts + 3 * tv[2], pts + 3 * tv[3]);
    double* s = &TetStiffness_[10 * static_cast<size_t>(t)];
    s[0] = geo.Stiffness[0][0];
    s[1] = geo.Stiffness[1][1];
    s[2] = geo.Stiffness[2][2];
    s[3] = geo.Stiffness[3][3];
    s[4] = geo.Stiffness[0][1];
    s[5] = geo.Stiffness[0][2];
    s[6] = geo.Stiffness[0][3];
    s[7] = geo.Stiffness[1][2];
    s[8] = geo.Stiffness[1][3];
    s[9] = geo.Stiffness[2][3];
    const int e = TetElement_[t];
    const double v = mesh.GetTetVolume(t);
    ElementVolume_[e] += v;
    for (int d = 0; d < 3; ++d)
    {
      const double c =
        0.25 * (pts[3 * tv[0] + d] + pts[3 * tv[1] + d] + pts[3 * tv[2] + d] + pts[3 * tv[3] + d]);
      ElementCentroid_[3 * e + d] += v * c;
    }
  }
  for (int e = 0; e < numElements; ++e)
  {
    if (!(ElementVolume_[e] > 0.0))
    {
      std::ostringstream os;
      os << "DiffusionForwardModel: element " << e << " owns no tet";
      throw Error(os.str());
    }
    for (int d = 0; d < 3; ++d)
    {
      ElementCentroid_[3 * e + d] /= ElementVolume_[e];
    }
  }

  // Neighbouring elements: tets sharing a face, in different elements.
  FindElementNeighbours(mesh, TetElement_, ElementCentroid_, Neighbours_, NeighbourWeights_);

  // Boundary terms and read-out weights.
  const std::vector<double> pointEta = BoundaryPointRefractiveIndex(mesh, tetEta);
  const std::vector<double>& area = mesh.GetBoundaryAreas();
  BoundaryDiagonal_ = Eigen::VectorXd::Zero(numPoints);
  SourceScale_ = Eigen::VectorXd::Zero(numPoints);
  Alpha_ = Eigen::VectorXd::Zero(numPoints);
  Beta_ = Eigen::VectorXd::Zero(numPoints);
  for (int i : mesh.GetBoundaryPoints())
  {
    const double eta = pointEta[i];
    const double fdr = Fresnel::DiffuseReflectance(eta);
    const double a = Fresnel::MismatchA(eta);
    BoundaryDiagonal_[i] = 2.0 * area[i] / (3.0 * a);                // TransCut eq. 13, boundary
    SourceScale_[i] = 8.0 * area[i] / (3.0 * a * (1.0 - fdr));       // TransCut eq. 12
    const double ft = Fresnel::Transmittance(1.0, eta);
    Alpha_[i] = ft / (4.0 * Pi) * (1.0 + 1.0 / a); // TransCut eq. 3 at normal exit
    Beta_[i] = ft / (4.0 * Pi) * 4.0 / (1.0 + fdr);
  }
}

DiffusionForwardModel::~DiffusionForwardModel() = default;

int DiffusionForwardModel::GetNumberOfPoints() const
{
  return Mesh_.GetNumberOfPoints();
}

Eigen::VectorXd DiffusionForwardModel::Source(const Eigen::VectorXd& q) const
{
  if (q.size() != SourceScale_.size())
  {
    std::ostringstream os;
    os << "DiffusionForwardModel::Source: " << q.size() << " irradiance values for "
       << SourceScale_.size() << " points";
    throw Error(os.str());
  }
  return SourceScale_.cwiseProduct(q);
}

Eigen::SparseMatrix<double> DiffusionForwardModel::Matrix(const double* kappa, const double* mu) const
{
  for (int e = 0; e < NumberOfElements_; ++e)
  {
    if (!(std::isfinite(kappa[e]) && kappa[e] > 0.0 && std::isfinite(mu[e]) && mu[e] > 0.0))
    {
      std::ostringstream os;
      os << "DiffusionForwardModel: element " << e << " has kappa = " << kappa[e]
         << " mm and mu_a = " << mu[e] << " 1/mm: both must be finite and > 0";
      throw Error(os.str());
    }
  }
  return Assemble(kappa, mu, true);
}

Eigen::SparseMatrix<double> DiffusionForwardModel::DerivativeMatrix(
  const double* dKappa, const double* dMu) const
{
  for (int e = 0; e < NumberOfElements_; ++e)
  {
    if (!(std::isfinite(dKappa[e]) && std::isfinite(dMu[e])))
    {
      std::ostringstream os;
      os << "DiffusionForwardModel::DerivativeMatrix: element " << e << " has direction ("
         << dKappa[e] << ", " << dMu[e] << "): must be finite";
      throw Error(os.str());
    }
  }
  return Assemble(dKappa, dMu, false);
}

Eigen::SparseMatrix<double> DiffusionForwardModel::Assemble(
  const double* kappa, const double* mu, bool boundary) const
{
  const int n = Mesh_.GetNumberOfPoints();
  const std::vector<int>& offsets = Mesh_.GetRowOffsets();
  const std::vector<int>& columns = Mesh_.GetColumnIndices();
  const int nnz = static_cast<int>(columns.size());
  // The pattern is symmetric: the CSR arrays are also the CSC arrays.
  Eigen::SparseMatrix<double> m(n, n);
  m.resizeNonZeros(nnz);
  std::copy(offsets.begin(), offsets.end(), m.outerIndexPtr());
  std::copy(columns.begin(), columns.end(), m.innerIndexPtr());
  double* v = m.valuePtr();
  std::fill(v, v + nnz, 0.0);
  const int* positions = Mesh_.GetTetNonZeroPositions().data();
  const int numTets = Mesh_.GetNumberOfTets();
  for (int t = 0; t < numTets; ++t)
  {
    const int e = TetElement_[t];
    const double four = 4.0 * kappa[e];             // TransCut eq. 14: M_ij = 4 w_ij
    const double mass = Mesh_.GetTetVolume(t) * mu[e]; // eq. 13: V_i mu(x_i), per tet share
    const double* s = &TetStiffness_[10 * static_cast<size_t>(t)];
    const int* pos = positions + 16 * static_cast<size_t>(t);
    const double diag[4] = { four * s[0] + mass, four * s[1] + mass, four * s[2] + mass,
      four * s[3] + mass };
    const double off[6] = { four * s[4], four * s[5], four * s[6], four * s[7], four * s[8],
      four * s[9] };
    ScatterTetMatrix(v, pos, diag, off);
  }
  const int* diagonal = Mesh_.GetDiagonalPositions().data();
  const int* pointTetOffsets = Mesh_.GetPointTetOffsets().data();
  for (int i = 0; boundary && i < n; ++i)
  {
    v[diagonal[i]] += BoundaryDiagonal_[i]; // TransCut eq. 13, boundary case
    if (pointTetOffsets[i + 1] == pointTetOffsets[i])
    {
      v[diagonal[i]] = 1.0; // point used by no tet: identity row
    }
  }
  return m;
}

void DiffusionForwardModel::Factorize(const double* kappa, const double* mu, Factor& factor) const
{
  if (!factor.Impl_)
  {
    factor.Impl_.reset(new Factor::Impl);
  }
  Factor::Impl& impl = *factor.Impl_;
  impl.Valid = false;
  impl.Matrix = Matrix(kappa, mu);
  if (!impl.Analysed)
  {
    impl.Solver->AnalyzePattern(impl.Matrix);
    impl.Analysed = true;
  }
  if (!impl.Solver->Factorize(impl.Matrix))
  {
    throw Error("DiffusionForwardModel: the Cholesky factorisation failed (matrix not positive "
                "definite: check the coefficients)");
  }
  impl.Valid = true;
}

void DiffusionForwardModel::AccumulateGradient(const Eigen::Ref<const Eigen::VectorXd>& adjoint,
  const Eigen::Ref<const Eigen::VectorXd>& phi, double* gKappa, double* gMu) const
{
  const int numTets = Mesh_.GetNumberOfTets();
  for (int t = 0; t < numTets; ++t)
  {
    const int* tv = Mesh_.GetTet(t);
    const double l0 = adjoint[tv[0]], l1 = adjoint[tv[1]], l2 = adjoint[tv[2]], l3 = adjoint[tv[3]];
    const double p0 = phi[tv[0]], p1 = phi[tv[1]], p2 = phi[tv[2]], p3 = phi[tv[3]];
    const double* s = &TetStiffness_[10 * static_cast<size_t>(t)];
    // lambda^T G_t phi over the tet's 4 vertices.
    const double lgp = s[0] * l0 * p0 + s[1] * l1 * p1 + s[2] * l2 * p2 + s[3] * l3 * p3 +
      s[4] * (l0 * p1 + l1 * p0) + s[5] * (l0 * p2 + l2 * p0) + s[6] * (l0 * p3 + l3 * p0) +
      s[7] * (l1 * p2 + l2 * p1) + s[8] * (l1 * p3 + l3 * p1) + s[9] * (l2 * p3 + l3 * p2);
    const double lp = l0 * p0 + l1 * p1 + l2 * p2 + l3 * p3;
    const int e = TetElement_[t];
    // dM/dkappa_e = sum_{t in e} 4 G_t, dM/dmu_e = sum_{t in e} V_t I_t: the
    // discrete counterparts of grad(varphi).grad(phi) and varphi phi in
    // polygrid eq. 7.
    gKappa[e] -= 4.0 * lgp;
    gMu[e] -= Mesh_.GetTetVolume(t) * lp;
  }
}

} // namespace translucency
