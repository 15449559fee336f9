#include "DistributedVertexSolver.h"

#include "DiffusionSolverFactory.h"
#include "Error.h"
#include "Fresnel.h"
#include "RankThreads.h"
#include "TetContributions.h"
#include "VertexAssembly.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>
#include <sstream>

#include <time.h>

namespace translucency
{

namespace
{

/// Local number (0..3) of point id in tet tv (the caller knows it is there).
inline int LocalIndex(const int* tv, int id)
{
  return tv[0] == id ? 0 : (tv[1] == id ? 1 : (tv[2] == id ? 2 : 3));
}

/// The element matrix of one tet and channel: fem's or the divergence's
/// (the full assembly and the changed-rows update must give the same bits).
inline void ElementMatrix(bool fem, const TetGeometry& geometry, double muA, double sigmaS,
  double diag[4], double off[6])
{
  if (fem)
    FiniteElementTetMatrix(geometry, muA, sigmaS, diag, off);
  else
    DivergenceTetMatrix(geometry, muA, sigmaS, diag, off);
}

double Milliseconds(double since)
{
  return 1000.0 * (MPI_Wtime() - since);
}

/// This process's CPU time (ms).
double CpuMilliseconds()
{
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1000.0 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

/// The registry's distributed variants of divergence and fem, registered
/// when this layer is loaded (a build without it has none).
const bool Registered = [] {
  for (const char* name : { "divergence", "fem" })
  {
    const std::string discretization = name;
    RegisterDistributedDiffusionSolver(discretization, [discretization] {
      return std::unique_ptr<DiffusionSolver>(
        std::make_unique<DistributedVertexSolver>(discretization));
    });
  }
  return true;
}();

/// The positions of the owned rows (3 per row; zeros for a row without a
/// local point), for a linear solver that aggregates by distance
/// (DistributedLinearSolver::SetCoordinates).
std::vector<double> RowPositions(const TetMesh& mesh, const std::vector<int>& firstLocal)
{
  std::vector<double> xyz(3 * firstLocal.size(), 0.0);
  const std::vector<double>& points = mesh.GetPoints();
  for (std::size_t r = 0; r < firstLocal.size(); ++r)
  {
    const std::size_t i = static_cast<std::size_t>(firstLocal[r]);
    if (firstLocal[r] >= 0 && 3 * i + 2 < points.size())
      std::copy(points.begin() + 3 * i, points.begin() + 3 * i + 3, xyz.begin() + 3 * r);
  }
  return xyz;
}

} // namespace

DistributedVertexSolver::DistributedVertexSolver(const std::string& discretization)
  : DistributedVertexSolver(GetMPIComm(Communicator()), discretization)
{
}

DistributedVertexSolver::DistributedVertexSolver(MPI_Comm comm, const std::string& discretization)
  : Comm_(comm)
  , Name_(discretization)
{
  if (discretization != "divergence" && discretization != "fem")
  {
    throw Error("distributed solve: unknown discretisation '" + discretization +
      "' (divergence or fem)");
  }
  Fem_ = discretization == "fem";
  EnsureHypreInitialized();
  (void)Registered;
}

DistributedVertexSolver::~DistributedVertexSolver() = default;

void DistributedVertexSolver::SetCommunicator(const Communicator& comm)
{
  const MPI_Comm next = GetMPIComm(comm);
  if (next == Comm_)
  {
    return;
  }
  Reset();
  HaveGeometry_ = false;
  Keys_.clear();
  Points_.clear();
  Tets_.clear();
  OwnMesh_ = TetMesh();
  Beam_.Clear();
  Comm_ = next;
}

void DistributedVertexSolver::Reset()
{
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    Channels_[c].reset();
    Solution_[c].clear();
    Contributions_[c].clear();
    FullIterations_[c] = 0;
    ForceFull_[c] = false;
    Donor_[c] = -1;
    LocalValues_[c].clear();
    Received_[c].clear();
  }
  HaveLocalValues_ = false;
  Material_ = OpticalProperties();
  HaveMaterial_ = false;
  ChangedHint_.reset();
}

void DistributedVertexSolver::SetChangedTets(std::vector<int> changedTets, bool irradianceChanged)
{
  (void)irradianceChanged; // the right-hand side is assembled at every Solve
  ChangedHint_ = std::move(changedTets);
}

bool DistributedVertexSolver::HintApplies(
  const OpticalProperties& material, const std::vector<int>* hint) const
{
  const std::size_t numTets = material.RefractiveIndex.size();
  return hint && HaveMaterial_ && Material_.RefractiveIndex.size() == numTets &&
    Material_.AbsorptionCoefficient.size() == 3 * numTets &&
    Material_.ReducedScatteringCoefficient.size() == 3 * numTets &&
    material.AbsorptionCoefficient.size() == 3 * numTets &&
    material.ReducedScatteringCoefficient.size() == 3 * numTets;
}

bool DistributedVertexSolver::GetTalliedReadouts(TalliedReadouts& readouts) const
{
  readouts = TalliedReadouts();
  readouts.Readings = Readings_;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    readouts.Injected[c] = Balance_.BoundaryInjected[c] + SourcePower_[c];
    readouts.Absorbed[c] = Balance_.Absorbed[c];
    readouts.Escaped[c] = Balance_.Escaped[c];
    // The extended model's beam (DiffusionFrontEnd::ComputePowerBalance):
    // what entered, what it deposited directly, what leaves unscattered.
    const CollimatedSource& b = BeamResult_;
    readouts.Injected[c] += b.Entering[c];
    readouts.Absorbed[c] += b.Absorbed[c];
    readouts.Escaped[c] += b.Entering[c] - b.Scattered[c] - b.Absorbed[c];
  }
  return true;
}

void DistributedVertexSolver::SetLinearSolverOptions(const SolverOptions& options)
{
  LinearOptions_ = options;
  OptionsChanged_ = true;
}

int DistributedVertexSolver::GetNumberOfLevels(int c) const
{
  return Channels_[c] ? Channels_[c]->GetNumberOfLevels() : 0;
}

double DistributedVertexSolver::GetOperatorComplexity(int c) const
{
  return Channels_[c] ? Channels_[c]->GetOperatorComplexity() : 0.0;
}

DistributedPiece DistributedVertexSolver::Piece(const OpticalProperties& material) const
{
  DistributedPiece piece;
  piece.Mesh = Mesh_;
  piece.HasTets = HasTets();
  piece.NumberOfPoints = static_cast<int>(Keys_.size());
  piece.Physical = &PhysicalFace_;
  piece.Material = &material;
  return piece;
}

void DistributedVertexSolver::BuildGeometry(const TetMesh* mesh, const std::vector<PointKey>& keys)
{
  // The local mesh: the owned tets on the local points (partition faces
  // are boundary faces of it; the count across ranks sorts them out).
  HaveGeometry_ = false;
  ++Numberings_;
  for (auto& channel : Channels_)
    channel.reset();
  for (auto& x : Solution_)
    x.clear();
  Donor_ = { -1, -1, -1 };
  HaveMaterial_ = false;
  HaveLocalValues_ = false;
  OwnedMeasures_.clear();
  MatrixMeasures_.clear();
  OwnedRobin_.clear();
  const std::size_t numPoints = keys.size();
  Mesh_ = mesh && mesh->GetNumberOfTets() > 0 ? mesh : &EmptyMesh_;
  std::string error;
  Used_.assign(numPoints, 0);
  for (int id : Mesh_->GetTets())
    Used_[static_cast<std::size_t>(id)] = 1;
  Numbering_.Build(Comm_, keys, Used_);

  // The physical boundary: local boundary faces no other tet shares.
  const std::vector<int>& triangles = Mesh_->GetBoundaryTriangles();
  std::vector<int> triangleRows(triangles.size());
  for (std::size_t k = 0; k < triangles.size(); ++k)
    triangleRows[k] = Numbering_.GetRow(triangles[k]);
  const std::vector<int> counts = CountSharedTriangles(Comm_, triangleRows);
  PhysicalFace_.assign(counts.size(), 0);
  for (std::size_t f = 0; f < counts.size(); ++f)
  {
    PhysicalFace_[f] = counts[f] == 1;
    if (counts[f] > 2 && error.empty())
    {
      const int* v = triangles.data() + 3 * f;
      std::ostringstream os;
      os << "the face of points (" << v[0] << ", " << v[1] << ", " << v[2]
         << ") of this rank's piece belongs to " << counts[f]
         << " tets over all ranks (at most 2 in a tet mesh): overlapping pieces? Mark the copies "
            "as ghost cells (vtkGhostType) or use the gathered solve";
      error = os.str();
    }
  }
  AgreeOnError(Comm_, error);

  // The owned rows on the physical boundary: a vertex of a physical face on
  // any rank (the owner need not hold that face), counted at the owners.
  std::vector<double> onBoundary(numPoints, 0.0);
  for (std::size_t f = 0; f < PhysicalFace_.size(); ++f)
  {
    if (PhysicalFace_[f])
      for (int a = 0; a < 3; ++a)
        onBoundary[static_cast<std::size_t>(triangles[3 * f + a])] = 1.0;
  }
  const std::vector<double> ownedBoundary = Numbering_.SumToOwners(Comm_, onBoundary, 1);
  BoundaryRows_.clear();
  for (std::size_t r = 0; r < ownedBoundary.size(); ++r)
  {
    if (ownedBoundary[r] > 0.0)
      BoundaryRows_.push_back(static_cast<int>(r));
  }

  BuildOwnedRows();
  Keys_ = keys;
  Revision_ = HasTets() ? Mesh_->GetGeometryRevision() : 0;
  HaveGeometry_ = true;
}

namespace
{
/**
 * BuildOwnedRows: the owned rows' pattern (per row the sorted distinct
 * columns of its entries, `entryRow` local to this rank's rows) into
 * `ownedOffsets` and `ownedColumns`, and each entry's place in it into
 * `targets`.
 */
void OwnedPattern(int owned, const std::vector<int>& entryRow, const std::vector<int>& entryColumn,
  std::vector<int>& targets, std::vector<int>& ownedOffsets, std::vector<int>& ownedColumns)
{
  std::vector<int> rowStart(static_cast<std::size_t>(owned) + 1, 0);
  for (int r : entryRow)
    ++rowStart[static_cast<std::size_t>(r) + 1];
  for (int r = 0; r < owned; ++r)
    rowStart[r + 1] += rowStart[r];
  std::vector<int> byRow(entryRow.size());
  {
    std::vector<int> fill(rowStart.begin(), rowStart.end() - 1);
    for (std::size_t e = 0; e < entryRow.size(); ++e)
      byRow[static_cast<std::size_t>(fill[static_cast<std::size_t>(entryRow[e])]++)] =
        static_cast<int>(e);
  }
  targets.assign(entryRow.size(), -1);
  ownedOffsets.assign(static_cast<std::size_t>(owned) + 1, 0);
  ownedColumns.clear();
  ownedColumns.reserve(entryRow.size());
  std::vector<int> row;
  for (int r = 0; r < owned; ++r)
  {
    row.clear();
    bool increasing = true;
    for (int k = rowStart[r]; k < rowStart[r + 1]; ++k)
    {
      const int column = entryColumn[static_cast<std::size_t>(byRow[static_cast<std::size_t>(k)])];
      increasing = increasing && (row.empty() || column > row.back());
      row.push_back(column);
    }
    if (increasing)
    {
      // Already sorted and distinct (a row of one local point whose
      // neighbours' rows ascend with their local ids: one rank, most rows
      // of a slab): each entry is its own place, no sort or search.
      const int base = static_cast<int>(ownedColumns.size());
      ownedColumns.insert(ownedColumns.end(), row.begin(), row.end());
      ownedOffsets[r + 1] = static_cast<int>(ownedColumns.size());
      for (int k = rowStart[r]; k < rowStart[r + 1]; ++k)
        targets[static_cast<std::size_t>(byRow[static_cast<std::size_t>(k)])] = base + k - rowStart[r];
      continue;
    }
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    const int base = static_cast<int>(ownedColumns.size());
    ownedColumns.insert(ownedColumns.end(), row.begin(), row.end());
    ownedOffsets[r + 1] = static_cast<int>(ownedColumns.size());
    for (int k = rowStart[r]; k < rowStart[r + 1]; ++k)
    {
      const std::size_t e = static_cast<std::size_t>(byRow[static_cast<std::size_t>(k)]);
      targets[e] = base +
        static_cast<int>(std::lower_bound(row.begin(), row.end(), entryColumn[e]) - row.begin());
    }
  }
}

} // namespace

void DistributedVertexSolver::BuildOwnedRows()
{
  // Whole owned rows, handed to hypre once (issue 32): every local CSR
  // entry of a used point goes to its row's owner, this rank's own into
  // place directly, the others' (partition rows) sent once per assembly
  // as values in a fixed order; the pattern and the places are built here,
  // once per mesh. Every rank calls the exchanges (an empty piece too).
  const int rank = [this] {
    int r = 0;
    MPI_Comm_rank(Comm_, &r);
    return r;
  }();
  int ranks = 1;
  MPI_Comm_size(Comm_, &ranks);
  const int owned = Numbering_.GetNumberOfOwnedRows();
  const int rowBegin = Numbering_.GetRowBegin();
  const std::size_t numPoints = Used_.size();
  FirstLocal_.assign(static_cast<std::size_t>(owned), -1);
  const std::vector<int>& offsets = Mesh_->GetRowOffsets();
  const std::vector<int>& columns = Mesh_->GetColumnIndices();

  // This rank's entries (row, column, local CSR position), and per owner
  // rank the (row, column) pairs of the entries it sends.
  std::vector<std::vector<int>> outgoing(static_cast<std::size_t>(ranks));
  std::vector<std::vector<int>> outgoingPositions(static_cast<std::size_t>(ranks));
  std::vector<std::vector<int>> outgoingPoints(static_cast<std::size_t>(ranks));
  std::vector<int> localRows, localColumns;
  RowEntryOffsets_.clear();
  RowEntries_.clear();
  LocalPositions_.clear();
  if (HasTets())
  {
    const std::size_t entries = static_cast<std::size_t>(offsets[numPoints]);
    localRows.reserve(entries);
    localColumns.reserve(entries);
    LocalPositions_.reserve(entries);
  }
  for (std::size_t i = 0; i < numPoints && HasTets(); ++i)
  {
    if (!Used_[i])
      continue;
    const int row = Numbering_.GetRow(static_cast<int>(i));
    const int owner = Numbering_.GetOwner(static_cast<int>(i));
    if (owner == rank)
    {
      int& first = FirstLocal_[static_cast<std::size_t>(row - rowBegin)];
      if (first < 0)
        first = static_cast<int>(i);
    }
    for (int k = offsets[i]; k < offsets[i + 1]; ++k)
    {
      const int column = Numbering_.GetRow(columns[static_cast<std::size_t>(k)]);
      if (owner == rank)
      {
        localRows.push_back(row - rowBegin);
        localColumns.push_back(column);
        LocalPositions_.push_back(k);
      }
      else
      {
        outgoing[static_cast<std::size_t>(owner)].push_back(row);
        outgoing[static_cast<std::size_t>(owner)].push_back(column);
        outgoingPositions[static_cast<std::size_t>(owner)].push_back(k);
        outgoingPoints[static_cast<std::size_t>(owner)].push_back(static_cast<int>(i));
      }
    }
  }
  SendCounts_.assign(static_cast<std::size_t>(ranks), 0);
  SendPositionsOff_.clear();
  SendPoints_.clear();
  for (int r = 0; r < ranks; ++r)
  {
    SendCounts_[r] = static_cast<int>(outgoingPositions[r].size());
    SendPositionsOff_.insert(
      SendPositionsOff_.end(), outgoingPositions[r].begin(), outgoingPositions[r].end());
    SendPoints_.insert(SendPoints_.end(), outgoingPoints[r].begin(), outgoingPoints[r].end());
  }
  RecvCounts_.assign(static_cast<std::size_t>(ranks), 0);
  MPI_Alltoall(SendCounts_.data(), 1, MPI_INT, RecvCounts_.data(), 1, MPI_INT, Comm_);
  std::vector<int> pairCounts(static_cast<std::size_t>(ranks)), pairDispls(ranks + 1, 0),
    recvPairCounts(static_cast<std::size_t>(ranks)), recvPairDispls(ranks + 1, 0);
  std::vector<int> sendPairs;
  for (int r = 0; r < ranks; ++r)
  {
    pairCounts[r] = 2 * SendCounts_[r];
    recvPairCounts[r] = 2 * RecvCounts_[r];
    pairDispls[r + 1] = pairDispls[r] + pairCounts[r];
    recvPairDispls[r + 1] = recvPairDispls[r] + recvPairCounts[r];
    sendPairs.insert(sendPairs.end(), outgoing[r].begin(), outgoing[r].end());
  }
  outgoing = {};
  std::vector<int> recvPairs(static_cast<std::size_t>(recvPairDispls[ranks]));
  MPI_Alltoallv(sendPairs.data(), pairCounts.data(), pairDispls.data(), MPI_INT, recvPairs.data(),
    recvPairCounts.data(), recvPairDispls.data(), MPI_INT, Comm_);
  sendPairs = {};

  // The owned rows' pattern: per row the sorted distinct columns of the
  // local and received entries; every entry's place in it.
  const std::size_t numLocal = localRows.size(), numReceived = recvPairs.size() / 2;
  std::vector<int> entryRow = std::move(localRows), entryColumn = std::move(localColumns);
  entryRow.resize(numLocal + numReceived);
  entryColumn.resize(numLocal + numReceived);
  for (std::size_t e = 0; e < numReceived; ++e)
  {
    entryRow[numLocal + e] = recvPairs[2 * e] - rowBegin;
    entryColumn[numLocal + e] = recvPairs[2 * e + 1];
  }
  recvPairs = {};
  OwnedPattern(owned, entryRow, entryColumn, Targets_, OwnedOffsets_, OwnedColumns_);
  IdentityGather_ = numReceived == 0 && SendPositionsOff_.empty() &&
    LocalPositions_.size() == OwnedColumns_.size() && Targets_.size() == OwnedColumns_.size() &&
    HasTets() && LocalPositions_.size() == static_cast<std::size_t>(offsets[numPoints]);
  for (std::size_t e = 0; IdentityGather_ && e < Targets_.size(); ++e)
    IdentityGather_ = Targets_[e] == static_cast<int>(e) && LocalPositions_[e] == static_cast<int>(e);
}

void DistributedVertexSolver::GatherOwnedRows(const std::vector<double>& local,
  std::vector<double>& ownedValues, std::vector<double>* received) const
{
  // This rank's entries into place, the partition rows' partial values sent
  // to their owners in the order BuildOwnedRows fixed (one exchange).
  int ranks = 1;
  MPI_Comm_size(Comm_, &ranks);
  const std::size_t numLocal = LocalPositions_.size();
  if (IdentityGather_ && local.size() == numLocal)
  {
    ownedValues.assign(local.begin(), local.end());
  }
  else
  {
    ownedValues.assign(OwnedColumns_.size(), 0.0);
    for (std::size_t e = 0; e < numLocal; ++e)
      ownedValues[static_cast<std::size_t>(Targets_[e])] +=
        local[static_cast<std::size_t>(LocalPositions_[e])];
  }
  std::vector<double> send(SendPositionsOff_.size());
  for (std::size_t e = 0; e < send.size(); ++e)
    send[e] = local[static_cast<std::size_t>(SendPositionsOff_[e])];
  std::vector<int> sendDispls(ranks + 1, 0), recvDispls(ranks + 1, 0);
  for (int r = 0; r < ranks; ++r)
  {
    sendDispls[r + 1] = sendDispls[r] + SendCounts_[r];
    recvDispls[r + 1] = recvDispls[r] + RecvCounts_[r];
  }
  std::vector<double> partial(static_cast<std::size_t>(recvDispls[ranks]));
  if (ranks > 1)
  {
    MPI_Alltoallv(send.data(), SendCounts_.data(), sendDispls.data(), MPI_DOUBLE, partial.data(),
      RecvCounts_.data(), recvDispls.data(), MPI_DOUBLE, Comm_);
  }
  for (std::size_t e = 0; e < partial.size(); ++e)
    ownedValues[static_cast<std::size_t>(Targets_[numLocal + e])] += partial[e];
  if (received)
    received->swap(partial);
}

void DistributedVertexSolver::CheckPiece(const std::vector<double>& points,
  const std::vector<PointKey>& keys, const std::vector<int>& tets,
  const OpticalProperties& material, const std::vector<double>& irradiance) const
{
  // Sizes and ids (the values are checked by the assembly).
  const std::size_t numPoints = keys.size();
  std::string error;
  try
  {
    if (points.size() != 3 * numPoints || irradiance.size() != 3 * numPoints ||
      tets.size() % 4 != 0)
    {
      std::ostringstream os;
      os << "distributed solve: " << numPoints << " point keys, " << points.size() / 3
         << " points, " << irradiance.size() << " irradiance values (3 per point) and "
         << tets.size() << " tet ids (4 per tet) do not match";
      throw Error(os.str());
    }
    for (std::size_t k = 0; k < tets.size(); ++k)
    {
      if (tets[k] < 0 || static_cast<std::size_t>(tets[k]) >= numPoints)
      {
        std::ostringstream os;
        os << "tet " << k / 4 << " has point id " << tets[k] << " (the piece has " << numPoints
           << " points)";
        throw Error(os.str());
      }
    }
    material.Validate(static_cast<int>(tets.size() / 4));
  }
  catch (const Error& e)
  {
    error = e.what();
  }
  AgreeOnError(Comm_, error);
}

void DistributedVertexSolver::CheckPiece(const TetMesh* mesh, const std::vector<PointKey>& keys,
  const OpticalProperties& material, const std::vector<double>& irradiance,
  const std::vector<int>* hint) const
{
  // Sizes (the mesh checked its ids; the values are checked by the assembly).
  const std::size_t numPoints = keys.size();
  const int numTets = mesh ? mesh->GetNumberOfTets() : 0;
  std::string error;
  try
  {
    if ((mesh && static_cast<std::size_t>(mesh->GetNumberOfPoints()) != numPoints) ||
      irradiance.size() != 3 * numPoints)
    {
      std::ostringstream os;
      os << "distributed solve: " << numPoints << " point keys, "
         << (mesh ? mesh->GetNumberOfPoints() : 0) << " mesh points and " << irradiance.size()
         << " irradiance values (3 per point) do not match";
      throw Error(os.str());
    }
    if (HintApplies(material, hint))
      material.ValidateTets(numTets, *hint); // the rest was valid at the last Solve
    else
      material.Validate(numTets);
  }
  catch (const Error& e)
  {
    error = e.what();
  }
  AgreeOnError(Comm_, error);
}

void DistributedVertexSolver::AssembleLocal(const OpticalProperties& material,
  const std::vector<double>& irradiance, DiffusionSystem& system)
{
  // The element matrices of the owned tets (TetContributions.h, the serial
  // assemblies' expressions).
  std::string error;
  const int numTets = Mesh_->GetNumberOfTets();
  const double* muA = material.AbsorptionCoefficient.data();
  const double* sigmaS = material.ReducedScatteringCoefficient.data();
  if (numTets > 0)
  {
    const int threads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();
    ResizeVertexSystem(*Mesh_, system); // sized first: the kernel keeps pointers into it
    const ChannelPointers channels(system);
    const ChannelPointers* pointers = &channels;
    const bool fem = Fem_;
    auto kernel = [&](size_t t, const int*, const int* pos, const TetGeometry& geometry) {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        double diag[4], off[6];
        ElementMatrix(fem, geometry, muA[3 * t + c], sigmaS[3 * t + c], diag, off);
        ScatterTetMatrix(pointers->Values[c], pos, diag, off);
      }
    };
    if (!AssembleVertexSystem(*Mesh_, material, irradiance, system, threads, GeometryCache_,
          [] {}, kernel, [] {}))
    {
      try
      {
        CheckIrradiance(*Mesh_, irradiance); // names the point (the material was checked)
        error = "distributed solve: invalid material or irradiance";
      }
      catch (const Error& e)
      {
        error = e.what();
      }
    }
  }
  AgreeOnError(Comm_, error);
}

void DistributedVertexSolver::AddBoundaryTerms(const OpticalProperties& material,
  const std::vector<double>& irradiance, DiffusionSystem* system, std::vector<double>& localRhs)
{
  const std::vector<int>& triangles = Mesh_->GetBoundaryTriangles();
  const std::vector<int>& triangleTets = Mesh_->GetBoundaryTriangleTets();
  const std::vector<double>& areas = Mesh_->GetBoundaryTriangleAreas();
  const double* tetEta = material.RefractiveIndex.data();
  const double* q = irradiance.data();
  if (Fem_)
  {
    // Each physical face with its tet, on the tet's rank (TransCut eq. 2).
    const int* tetPositions = Mesh_->GetTetNonZeroPositions().data();
    for (std::size_t f = 0; f < PhysicalFace_.size(); ++f)
    {
      if (!PhysicalFace_[f])
        continue;
      const int t = triangleTets[f];
      const int* tv = Mesh_->GetTet(t);
      const int* pos = tetPositions + 16 * static_cast<std::size_t>(t);
      const int* tri = triangles.data() + 3 * f;
      const int l[3] = { LocalIndex(tv, tri[0]), LocalIndex(tv, tri[1]), LocalIndex(tv, tri[2]) };
      const double eta = tetEta[t];
      double robin, load;
      const Fresnel::RobinCoefficients robinCoefficients = Fresnel::BoundaryCoefficients(eta, Rule_);
      FiniteElementRobin(areas[f], robinCoefficients.A, robinCoefficients.Fdr, robin, load);
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        double* v = system ? system->Values[c].data() : nullptr;
        double sum = 0.0;
        for (int a = 0; a < 3; ++a)
          sum += q[3 * static_cast<std::size_t>(tri[a]) + c];
        for (int a = 0; a < 3; ++a)
        {
          for (int b = 0; v && b < 3; ++b)
            v[pos[4 * l[a] + l[b]]] += a == b ? robin + robin : robin;
          localRhs[3 * static_cast<std::size_t>(tri[a]) + c] +=
            load * (sum + q[3 * static_cast<std::size_t>(tri[a]) + c]);
        }
      }
    }
    return;
  }
  // S_i and sum of S_f eta_f around i over every rank's physical faces, at
  // the owner, which adds the lumped Robin term (eq. 12-13). Kept, with
  // each row's Robin coefficients, while no eta changed on any rank (a
  // relight, a paint of mu_a and sigma_s' only: KeepMeasures_).
  const bool keep = KeepMeasures_ && OwnedMeasures_.size() == 2 * FirstLocal_.size();
  if (!keep)
  {
    const std::size_t numPoints = Keys_.size();
    std::vector<double> measures(2 * numPoints, 0.0);
    for (std::size_t f = 0; f < PhysicalFace_.size(); ++f)
    {
      if (!PhysicalFace_[f])
        continue;
      const double eta = tetEta[triangleTets[f]];
      for (int a = 0; a < 3; ++a)
      {
        const std::size_t i = static_cast<std::size_t>(triangles[3 * f + a]);
        measures[2 * i] += areas[f];
        measures[2 * i + 1] += areas[f] * eta;
      }
    }
    OwnedMeasures_ = Numbering_.SumToOwners(Comm_, measures, 2);
  }
  const std::vector<double>& owned = OwnedMeasures_;
  if (!keep || RobinRule_ != Rule_ || OwnedRobin_.size() != owned.size())
  {
    // Each row's A and Fdr of its area-weighted eta (Fresnel's moments rule
    // integrates for every eta it did not see last).
    OwnedRobin_.assign(owned.size(), 0.0);
    for (std::size_t r = 0; r < FirstLocal_.size(); ++r)
    {
      const double s = owned[2 * r];
      if (!(s > 0.0))
        continue;
      const Fresnel::RobinCoefficients robin =
        Fresnel::BoundaryCoefficients(owned[2 * r + 1] / s, Rule_);
      OwnedRobin_[2 * r] = robin.A;
      OwnedRobin_[2 * r + 1] = robin.Fdr;
    }
    RobinRule_ = Rule_;
  }
  const int* diagonal = Mesh_->GetDiagonalPositions().data();
  for (std::size_t r = 0; r < FirstLocal_.size(); ++r)
  {
    const double s = owned[2 * r];
    if (!(s > 0.0))
      continue;
    const std::size_t i = static_cast<std::size_t>(FirstLocal_[r]);
    const double a = OwnedRobin_[2 * r], fdr = OwnedRobin_[2 * r + 1];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      if (system)
        system->Values[c][static_cast<std::size_t>(diagonal[i])] += DivergenceRobinDiagonal(s, a);
      localRhs[3 * i + c] = DivergenceRobinLoad(s, q[3 * i + c], a, fdr);
    }
  }
}

void DistributedVertexSolver::SetUpChannel(int c)
{
  const double cpu = CpuMilliseconds();
  double preparedCpu = 0.0; // PrepareUpdates: the matrix's share, not the hierarchy's
  std::string error;
  ForceFull_[c] = false;
  FullIterations_[c] = -1; // set by this Solve's PCG
  try
  {
    // From the linear-solver registry (its distributed variant), not hypre itself.
    const std::string name = LinearSolverName();
    if (!Channels_[c] || OptionsChanged_ || name != ChannelLinear_[c])
    {
      ChannelLinear_[c].clear();
      Channels_[c] = CreateDistributedLinearSolver(name, MakeCommunicator(&Comm_));
      Channels_[c]->SetOptions(LinearOptions_);
      ChannelLinear_[c] = name;
    }
    Donor_[c] = -1;
    const std::vector<double> xyz = RowPositions(*Mesh_, FirstLocal_);
    Channels_[c]->SetCoordinates(xyz.data(), static_cast<int>(FirstLocal_.size()));
    Channels_[c]->Setup(Numbering_.GetRowBegin(), Numbering_.GetRowEnd(), OwnedOffsets_.data(),
      OwnedColumns_.data(), Contributions_[c].data());
    if (ValuesOnly_) // the next paint's values-only update: its places found now
    {
      const double before = CpuMilliseconds();
      Channels_[c]->PrepareUpdates(OwnedOffsets_.data(), OwnedColumns_.data());
      preparedCpu = CpuMilliseconds() - before;
    }
    Donor_[c] = c;
    ++HierarchySetups_;
  }
  catch (const Error& e)
  {
    error = e.what();
  }
  if (Channels_[c])
    AddHierarchyCpu(c, CpuMilliseconds() - cpu - preparedCpu);
  AgreeOnError(Comm_, error);
}

void DistributedVertexSolver::AddHierarchyCpu(int c, double setupCpu)
{
  // The hierarchy's share of the channel's set-up, in CPU time (the matrix's
  // share measured in wall time, scaled alike).
  const double matrix = Channels_[c]->GetMatrixMilliseconds();
  const double levels = Channels_[c]->GetHierarchyMilliseconds();
  const double wall = matrix + levels;
  HierarchyCpu_ += (wall > 0.0 ? levels / wall : 1.0) * setupCpu;
}

void DistributedVertexSolver::ShareChannel(int c, int donor, double& hierarchyMs)
{
  const double cpu = CpuMilliseconds();
  std::string error;
  bool shared = false;
  ForceFull_[c] = false;
  FullIterations_[c] = -1; // set by this Solve's PCG
  try
  {
    const std::string name = LinearSolverName();
    if (!Channels_[c] || OptionsChanged_ || name != ChannelLinear_[c])
    {
      ChannelLinear_[c].clear();
      Channels_[c] = CreateDistributedLinearSolver(name, MakeCommunicator(&Comm_));
      Channels_[c]->SetOptions(LinearOptions_);
      ChannelLinear_[c] = name;
    }
    Donor_[c] = -1;
    shared = Channels_[c]->SetupShared(Numbering_.GetRowBegin(), Numbering_.GetRowEnd(),
      OwnedOffsets_.data(), OwnedColumns_.data(), Contributions_[c].data(), *Channels_[donor]);
    if (shared)
    {
      // Its own Galerkin levels on the donor's coarsening are hierarchy work.
      Donor_[c] = donor;
      hierarchyMs += Channels_[c]->GetHierarchyMilliseconds();
      AddHierarchyCpu(c, CpuMilliseconds() - cpu);
      if (ValuesOnly_)
        Channels_[c]->PrepareUpdates(OwnedOffsets_.data(), OwnedColumns_.data());
    }
  }
  catch (const Error& e)
  {
    error = e.what();
  }
  AgreeOnError(Comm_, error);
  if (!shared) // the same answer on every rank (the same solver kind and rows)
  {
    SetUpChannel(c);
    hierarchyMs += Channels_[c]->GetHierarchyMilliseconds();
  }
}

void DistributedVertexSolver::ReshareDependents(int donor, double& hierarchyMs)
{
  for (int o = 0; o < NumberOfChannels; ++o)
  {
    if (o != donor && Donor_[o] == donor)
      ShareChannel(o, donor, hierarchyMs);
  }
}

int DistributedVertexSolver::MedianChannel() const
{
  // The trace of each channel's owned rows, summed over the ranks.
  std::array<double, NumberOfChannels> trace{};
  const int rowBegin = Numbering_.GetRowBegin();
  const int owned = Numbering_.GetNumberOfOwnedRows();
  for (int r = 0; r < owned; ++r)
  {
    for (int k = OwnedOffsets_[r]; k < OwnedOffsets_[r + 1]; ++k)
    {
      if (OwnedColumns_[static_cast<std::size_t>(k)] == rowBegin + r)
      {
        for (int c = 0; c < NumberOfChannels; ++c)
          trace[c] += Contributions_[c][static_cast<std::size_t>(k)];
      }
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, trace.data(), NumberOfChannels, MPI_DOUBLE, MPI_SUM, Comm_);
  std::array<int, NumberOfChannels> order{ 0, 1, 2 };
  std::sort(order.begin(), order.end(), [&trace](int a, int b) { return trace[a] < trace[b]; });
  return order[1];
}

bool DistributedVertexSolver::FindChangedTets(const OpticalProperties& material,
  const std::vector<int>* hint, std::vector<int>& changed, long long& etaChanged) const
{
  changed.clear();
  etaChanged = 0;
  if (HintApplies(material, hint))
  {
    // The caller's kept material (SetChangedTets): only the hinted tets can
    // differ from Material_; which of them changed eta is compared.
    changed = *hint;
    for (const int t : changed)
    {
      const std::size_t k = static_cast<std::size_t>(t);
      etaChanged +=
        std::memcmp(&Material_.RefractiveIndex[k], &material.RefractiveIndex[k], sizeof(double))
        ? 1
        : 0;
    }
    return true;
  }
  const std::size_t numTets = material.RefractiveIndex.size();
  if (!HaveMaterial_ || Material_.RefractiveIndex.size() != numTets ||
    Material_.AbsorptionCoefficient.size() != material.AbsorptionCoefficient.size() ||
    Material_.ReducedScatteringCoefficient.size() != material.ReducedScatteringCoefficient.size() ||
    material.AbsorptionCoefficient.size() != 3 * numTets ||
    material.ReducedScatteringCoefficient.size() != 3 * numTets)
  {
    return false;
  }
  if (material.SameCoefficients(Material_))
    return true; // a relight: one pass over the arrays
  const double* a0 = Material_.AbsorptionCoefficient.data();
  const double* a1 = material.AbsorptionCoefficient.data();
  const double* s0 = Material_.ReducedScatteringCoefficient.data();
  const double* s1 = material.ReducedScatteringCoefficient.data();
  const double* e0 = Material_.RefractiveIndex.data();
  const double* e1 = material.RefractiveIndex.data();
  for (std::size_t t = 0; t < numTets; ++t)
  {
    const bool eta = std::memcmp(e0 + t, e1 + t, sizeof(double)) != 0;
    if (eta || std::memcmp(a0 + 3 * t, a1 + 3 * t, 3 * sizeof(double)) != 0 ||
      std::memcmp(s0 + 3 * t, s1 + 3 * t, 3 * sizeof(double)) != 0)
    {
      changed.push_back(static_cast<int>(t));
      etaChanged += eta ? 1 : 0;
    }
  }
  return true;
}

namespace
{
/// Which of DivergenceTetMatrix's `off` (pairs 01, 02, 03, 12, 13, 23) is
/// entry (a, b) of a tet (ScatterTetMatrix's layout); -1 on the diagonal.
constexpr int OffDiagonal[4][4] = { { -1, 0, 1, 2 }, { 0, -1, 3, 4 }, { 1, 3, -1, 5 },
  { 2, 4, 5, -1 } };
} // namespace

void DistributedVertexSolver::UpdateChangedRows(const OpticalProperties& material,
  const std::vector<int>& changedTets, std::vector<int>& ownedRows,
  std::array<bool, NumberOfChannels>& changed)
{
  // The serial path's SetupChangedRows, distributed (issue 32): only the
  // rows of the changed tets' vertices are assembled again, each value
  // summed in the full assembly's order, so that LocalValues_, Received_
  // and Contributions_ equal what AssembleLocal, AddBoundaryTerms and
  // GatherOwnedRows would give.
  HaveLocalValues_ = false; // until every row is the new one
  const std::size_t numPoints = Keys_.size();
  std::vector<char> rowFlag(numPoints, 0);
  std::vector<int> rows;
  auto flag = [&rowFlag, &rows](int i) {
    if (!rowFlag[static_cast<std::size_t>(i)])
    {
      rowFlag[static_cast<std::size_t>(i)] = 1;
      rows.push_back(i);
    }
  };
  const int* tets = Mesh_->GetTets().data();
  for (const int t : changedTets)
  {
    for (int a = 0; a < 4; ++a)
      flag(tets[4 * static_cast<std::size_t>(t) + a]);
  }
  if (!Fem_)
  {
    // The divergence's Robin diagonal of an owned row comes from the
    // boundary measures summed over the ranks: an eta changed on another
    // rank changes it here. Such a row is assembled again at its first
    // local point, where AddBoundaryTerms adds the term.
    const bool comparable = MatrixMeasures_.size() == OwnedMeasures_.size();
    for (std::size_t r = 0; r < FirstLocal_.size(); ++r)
    {
      if (FirstLocal_[r] >= 0 &&
        (!comparable ||
          std::memcmp(MatrixMeasures_.data() + 2 * r, OwnedMeasures_.data() + 2 * r,
            2 * sizeof(double)) != 0))
      {
        flag(FirstLocal_[r]);
      }
    }
  }
  ResumLocalRows(material, rowFlag, rows);

  // The owned rows to sum again: this rank's flagged points it owns, and
  // those the other ranks sent changed partial entries of.
  int rank = 0;
  MPI_Comm_rank(Comm_, &rank);
  const int owned = Numbering_.GetNumberOfOwnedRows();
  const int rowBegin = Numbering_.GetRowBegin();
  std::vector<char> ownedFlag(static_cast<std::size_t>(owned), 0);
  for (const int i : rows)
  {
    if (Numbering_.GetOwner(i) == rank)
      ownedFlag[static_cast<std::size_t>(Numbering_.GetRow(i) - rowBegin)] = 1;
  }
  ExchangeChangedEntries(rowFlag, ownedFlag);
  if (RowEntryOffsets_.size() != static_cast<std::size_t>(owned) + 1)
    BuildRowEntries();

  // Each such row summed as GatherOwnedRows sums it: from zero, the local
  // entries, then the received ones, in their order.
  ownedRows.clear();
  changed = {};
  const std::size_t numLocal = LocalPositions_.size();
  std::vector<double> row;
  for (int r = 0; r < owned; ++r)
  {
    if (!ownedFlag[static_cast<std::size_t>(r)])
      continue;
    ownedRows.push_back(r);
    const int begin = OwnedOffsets_[r], end = OwnedOffsets_[r + 1];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      const std::vector<double>& local = LocalValues_[c];
      if (IdentityGather_)
      {
        row.assign(local.begin() + begin, local.begin() + end);
      }
      else
      {
        row.assign(static_cast<std::size_t>(end - begin), 0.0);
        for (int n = RowEntryOffsets_[r]; n < RowEntryOffsets_[r + 1]; ++n)
        {
          const std::size_t x = static_cast<std::size_t>(RowEntries_[static_cast<std::size_t>(n)]);
          const double value = x < numLocal
            ? local[static_cast<std::size_t>(LocalPositions_[x])]
            : Received_[c][x - numLocal];
          row[static_cast<std::size_t>(Targets_[x] - begin)] += value;
        }
      }
      double* kept = Contributions_[c].data() + begin;
      if (std::memcmp(kept, row.data(), row.size() * sizeof(double)) != 0)
      {
        changed[c] = true;
        std::copy(row.begin(), row.end(), kept);
      }
    }
  }
}

void DistributedVertexSolver::ResumLocalRows(const OpticalProperties& material,
  const std::vector<char>& rowFlag, const std::vector<int>& rows)
{
  if (rows.empty())
    return;
  // Clear the rows; flag every tet that adds to one of them.
  const int* rowOffsets = Mesh_->GetRowOffsets().data();
  const int* pointTetOffsets = Mesh_->GetPointTetOffsets().data();
  const int* pointTets = Mesh_->GetPointTets().data();
  std::vector<char> tetFlag(static_cast<std::size_t>(Mesh_->GetNumberOfTets()), 0);
  for (const int i : rows)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      std::fill(LocalValues_[c].begin() + rowOffsets[i], LocalValues_[c].begin() + rowOffsets[i + 1],
        0.0);
    }
    for (int k = pointTetOffsets[i]; k < pointTetOffsets[i + 1]; ++k)
      tetFlag[static_cast<std::size_t>(pointTets[k])] = 1;
  }

  // The tets in the full assembly's order (the scatter schedule: every
  // entry receives its contributions in this order in AssembleVertexSystem),
  // the same element matrices (TetContributions.h), into the flagged rows.
  const double* points = Mesh_->GetPoints().data();
  const int* tets = Mesh_->GetTets().data();
  const int* positions = Mesh_->GetTetNonZeroPositions().data();
  const bool cached = GeometryCache_.IsValidFor(*Mesh_);
  const double* muA = material.AbsorptionCoefficient.data();
  const double* sigmaS = material.ReducedScatteringCoefficient.data();
  for (const int t0 : Mesh_->GetScatterSchedule().Tets)
  {
    const std::size_t t = static_cast<std::size_t>(t0);
    if (!tetFlag[t])
      continue;
    const int* tv = tets + 4 * t;
    // The cached geometry has the bits ComputeTetGeometry gives.
    const TetGeometry geometry = cached ? GeometryCache_.Get(t)
                                        : ComputeTetGeometry(points + 3 * static_cast<std::size_t>(tv[0]),
                                            points + 3 * static_cast<std::size_t>(tv[1]),
                                            points + 3 * static_cast<std::size_t>(tv[2]),
                                            points + 3 * static_cast<std::size_t>(tv[3]));
    const int* pos = positions + 16 * t;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double diag[4], off[6];
      ElementMatrix(Fem_, geometry, muA[3 * t + c], sigmaS[3 * t + c], diag, off);
      double* v = LocalValues_[c].data();
      for (int a = 0; a < 4; ++a)
      {
        if (!rowFlag[static_cast<std::size_t>(tv[a])])
          continue;
        for (int b = 0; b < 4; ++b)
          v[pos[4 * a + b]] += a == b ? diag[a] : off[OffDiagonal[a][b]];
      }
    }
  }

  // The Robin terms of these rows, as AddBoundaryTerms adds them (after
  // every tet, in the same order).
  if (Fem_)
  {
    const std::vector<int>& triangles = Mesh_->GetBoundaryTriangles();
    const std::vector<int>& triangleTets = Mesh_->GetBoundaryTriangleTets();
    const std::vector<double>& areas = Mesh_->GetBoundaryTriangleAreas();
    for (std::size_t f = 0; f < PhysicalFace_.size(); ++f)
    {
      const int* tri = triangles.data() + 3 * f;
      if (!PhysicalFace_[f] ||
        !(rowFlag[static_cast<std::size_t>(tri[0])] || rowFlag[static_cast<std::size_t>(tri[1])] ||
          rowFlag[static_cast<std::size_t>(tri[2])]))
        continue;
      const int t = triangleTets[f];
      const int* tv = Mesh_->GetTet(t);
      const int* pos = positions + 16 * static_cast<std::size_t>(t);
      const int l[3] = { LocalIndex(tv, tri[0]), LocalIndex(tv, tri[1]), LocalIndex(tv, tri[2]) };
      const Fresnel::RobinCoefficients robinCoefficients =
        Fresnel::BoundaryCoefficients(material.RefractiveIndex[static_cast<std::size_t>(t)], Rule_);
      double robin, load;
      FiniteElementRobin(areas[f], robinCoefficients.A, robinCoefficients.Fdr, robin, load);
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        double* v = LocalValues_[c].data();
        for (int a = 0; a < 3; ++a)
        {
          if (!rowFlag[static_cast<std::size_t>(tri[a])])
            continue;
          for (int b = 0; b < 3; ++b)
            v[pos[4 * l[a] + l[b]]] += a == b ? robin + robin : robin;
        }
      }
    }
    return;
  }
  const int* diagonal = Mesh_->GetDiagonalPositions().data();
  for (std::size_t r = 0; r < FirstLocal_.size(); ++r)
  {
    const int i = FirstLocal_[r];
    if (i < 0 || !rowFlag[static_cast<std::size_t>(i)])
      continue;
    const double s = OwnedMeasures_[2 * r];
    if (!(s > 0.0))
      continue;
    const double eta = OwnedMeasures_[2 * r + 1] / s;
    const Fresnel::RobinCoefficients robinCoefficients = Fresnel::BoundaryCoefficients(eta, Rule_);
    for (int c = 0; c < NumberOfChannels; ++c)
      LocalValues_[c][static_cast<std::size_t>(diagonal[i])] +=
        DivergenceRobinDiagonal(s, robinCoefficients.A);
  }
}

void DistributedVertexSolver::ExchangeChangedEntries(
  const std::vector<char>& rowFlag, std::vector<char>& ownedFlag)
{
  int ranks = 1;
  MPI_Comm_size(Comm_, &ranks);
  if (ranks == 1)
    return;
  // Per owner rank, the changed entries of its partition rows: the entry's
  // number in this rank's send list to it (BuildOwnedRows' order) and its
  // three channels' values, as doubles.
  std::vector<int> sendCounts(static_cast<std::size_t>(ranks), 0),
    recvCounts(static_cast<std::size_t>(ranks), 0);
  std::vector<double> send;
  std::size_t e = 0;
  for (int r = 0; r < ranks; ++r)
  {
    const std::size_t before = send.size();
    for (int n = 0; n < SendCounts_[r]; ++n, ++e)
    {
      if (!rowFlag[static_cast<std::size_t>(SendPoints_[e])])
        continue;
      const std::size_t k = static_cast<std::size_t>(SendPositionsOff_[e]);
      send.push_back(static_cast<double>(n));
      for (int c = 0; c < NumberOfChannels; ++c)
        send.push_back(LocalValues_[c][k]);
    }
    sendCounts[r] = static_cast<int>(send.size() - before);
  }
  MPI_Alltoall(sendCounts.data(), 1, MPI_INT, recvCounts.data(), 1, MPI_INT, Comm_);
  std::vector<int> sendDispls(ranks + 1, 0), recvDispls(ranks + 1, 0), entryDispls(ranks + 1, 0);
  for (int r = 0; r < ranks; ++r)
  {
    sendDispls[r + 1] = sendDispls[r] + sendCounts[r];
    recvDispls[r + 1] = recvDispls[r] + recvCounts[r];
    entryDispls[r + 1] = entryDispls[r] + RecvCounts_[r];
  }
  std::vector<double> received(static_cast<std::size_t>(recvDispls[ranks]));
  MPI_Alltoallv(send.data(), sendCounts.data(), sendDispls.data(), MPI_DOUBLE, received.data(),
    recvCounts.data(), recvDispls.data(), MPI_DOUBLE, Comm_);

  // Into the kept partial values; the owned rows they add to are flagged.
  const std::size_t numLocal = LocalPositions_.size();
  for (int r = 0; r < ranks; ++r)
  {
    for (int q = recvDispls[r]; q < recvDispls[r + 1]; q += 1 + NumberOfChannels)
    {
      const std::size_t entry = static_cast<std::size_t>(entryDispls[r]) +
        static_cast<std::size_t>(received[static_cast<std::size_t>(q)]);
      for (int c = 0; c < NumberOfChannels; ++c)
        Received_[c][entry] = received[static_cast<std::size_t>(q + 1 + c)];
      const int place = Targets_[numLocal + entry];
      const int row = static_cast<int>(
        std::upper_bound(OwnedOffsets_.begin(), OwnedOffsets_.end(), place) - OwnedOffsets_.begin()) - 1;
      ownedFlag[static_cast<std::size_t>(row)] = 1;
    }
  }
}

void DistributedVertexSolver::BuildRowEntries()
{
  // A counting sort of the entries by their owned row, stable (ascending
  // entry numbers within a row: GatherOwnedRows' order).
  const int owned = Numbering_.GetNumberOfOwnedRows();
  std::vector<int> placeRow(OwnedColumns_.size());
  for (int r = 0; r < owned; ++r)
    std::fill(placeRow.begin() + OwnedOffsets_[r], placeRow.begin() + OwnedOffsets_[r + 1], r);
  RowEntryOffsets_.assign(static_cast<std::size_t>(owned) + 1, 0);
  for (const int place : Targets_)
    ++RowEntryOffsets_[static_cast<std::size_t>(placeRow[static_cast<std::size_t>(place)]) + 1];
  for (int r = 0; r < owned; ++r)
    RowEntryOffsets_[r + 1] += RowEntryOffsets_[r];
  RowEntries_.assign(Targets_.size(), 0);
  std::vector<int> fill(RowEntryOffsets_.begin(), RowEntryOffsets_.end() - 1);
  for (std::size_t x = 0; x < Targets_.size(); ++x)
  {
    const std::size_t r = static_cast<std::size_t>(placeRow[static_cast<std::size_t>(Targets_[x])]);
    RowEntries_[static_cast<std::size_t>(fill[r]++)] = static_cast<int>(x);
  }
}

std::array<DistributedVertexSolver::ChannelSetup, NumberOfChannels>
DistributedVertexSolver::SetUpMatrices(bool sameMesh, DiffusionSystem& system,
  const std::vector<int>* changedRows, const std::array<bool, NumberOfChannels>& rowsChanged,
  std::string& assembly, double& hierarchyMs)
{
  // Rebuilt (values added, hierarchy set up) when changed, or, on the same
  // mesh, new values under the kept hierarchy. Returns what each channel got.
  std::array<ChannelSetup, NumberOfChannels> setup{};
  std::array<bool, NumberOfChannels> fresh{};
  bool updated = false;
  std::string error;
  HaveLocalValues_ = false; // until every channel's are the matrices'
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    // Another linear solver (SetLinearSolver) rebuilds the channel.
    const bool renamed = LinearSolverName() != ChannelLinear_[c];
    std::vector<double> values;
    if (!changedRows)
    {
      // The whole local matrix gathered into owned rows; the local values
      // and the partial rows received kept for a changed-rows update.
      std::vector<double> received;
      GatherOwnedRows(system.Values[c], values, &received);
      LocalValues_[c].swap(system.Values[c]);
      Received_[c].swap(received);
    }
    const bool differs = changedRows ? rowsChanged[c] : values != Contributions_[c];
    int changed =
      (!Channels_[c] || Donor_[c] < 0 || OptionsChanged_ || renamed || differs) ? 1 : 0;
    int anyChanged = 0;
    MPI_Allreduce(&changed, &anyChanged, 1, MPI_INT, MPI_MAX, Comm_);
    system.Values[c] = {};
    // Values only when every rank can (the same branch on every rank).
    int canUpdate = sameMesh && Channels_[c] && Donor_[c] >= 0 && !OptionsChanged_ && !renamed &&
        !ForceFull_[c] && (changedRows || values.size() == Contributions_[c].size())
      ? 1
      : 0;
    int allCanUpdate = 0;
    MPI_Allreduce(&canUpdate, &allCanUpdate, 1, MPI_INT, MPI_MIN, Comm_);
    if (anyChanged && ValuesOnly_ && allCanUpdate)
    {
      try
      {
        if (changedRows)
        {
          // Contributions_ holds the new values; only these rows changed.
          Channels_[c]->UpdateRows(OwnedOffsets_.data(), OwnedColumns_.data(),
            Contributions_[c].data(), changedRows->data(), static_cast<int>(changedRows->size()));
        }
        else
        {
          Channels_[c]->UpdateValues(OwnedOffsets_.data(), OwnedColumns_.data(), values.data());
        }
      }
      catch (const Error& e)
      {
        error = e.what();
      }
      int failed = error.empty() ? 0 : 1, anyFailed = 0;
      MPI_Allreduce(&failed, &anyFailed, 1, MPI_INT, MPI_MAX, Comm_);
      if (anyFailed)
      {
        // The matrix is half-updated: the next Solve sets up from scratch,
        // and the channels that used its hierarchy too.
        for (int o = 0; o < NumberOfChannels; ++o)
        {
          if (o != c && Donor_[o] == c)
          {
            Channels_[o].reset();
            Donor_[o] = -1;
            Contributions_[o].clear();
          }
        }
        Channels_[c].reset();
        Donor_[c] = -1;
        Contributions_[c].clear();
      }
      AgreeOnError(Comm_, error);
      updated = true;
      setup[c] = ChannelSetup::ValuesOnly;
      if (!changedRows)
        Contributions_[c].swap(values);
    }
    else if (anyChanged)
    {
      if (!changedRows)
        Contributions_[c].swap(values);
      fresh[c] = true;
    }
  }
  HaveLocalValues_ = true;
  // New hierarchies: one for the three channels when all three need one
  // (the median channel's, shared), else each its own.
  const bool all = fresh[0] && fresh[1] && fresh[2];
  const int donor = all && SharedHierarchy_ ? MedianChannel() : -1;
  if (donor >= 0)
  {
    SetUpChannel(donor);
    hierarchyMs += Channels_[donor]->GetHierarchyMilliseconds();
    setup[donor] = ChannelSetup::Fresh;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      if (c == donor)
        continue;
      ShareChannel(c, donor, hierarchyMs);
      setup[c] = Donor_[c] == c ? ChannelSetup::Fresh : ChannelSetup::Shared;
    }
  }
  else
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      if (!fresh[c])
        continue;
      SetUpChannel(c);
      hierarchyMs += Channels_[c]->GetHierarchyMilliseconds();
      setup[c] = ChannelSetup::Fresh;
    }
    // A channel that shared a hierarchy rebuilt now takes the new one.
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      if (fresh[c])
        ReshareDependents(c, hierarchyMs);
    }
  }
  OptionsChanged_ = false;
  const bool rebuilt = fresh[0] || fresh[1] || fresh[2];
  assembly = rebuilt ? "full" : updated ? "values-only" : "unchanged";
  return setup;
}

void DistributedVertexSolver::SolveChannels(const std::vector<double>& rhs,
  const std::array<ChannelSetup, NumberOfChannels>& setup, bool sameMesh,
  std::vector<double>& solution, SolverReport& report, double& hierarchyMs)
{
  // The three channels in one PCG (DistributedLinearSolver::SolveChannels),
  // from the previous solution on the same unknowns, with the serial rules:
  // at least one iteration in a channel whose matrix values changed on the
  // same mesh (a paint: LinearSolver::SetMinIter(1), VertexDiffusionSolver),
  // and the change rule over the owned boundary rows (ChangeTol_, set by
  // the filter at the interactive RelTol).
  // Never a non-converged result from a kept or shared hierarchy: a channel
  // that does not converge under a hierarchy set up before this Solve
  // (values-only update after a paint, a relight) or on another channel's
  // matrix gets its own, set up from scratch, and is solved again, cold
  // (issue 32: a kept hierarchy broke down after 1 iteration).
  const int owned = Numbering_.GetNumberOfOwnedRows();
  solution.assign(3 * static_cast<std::size_t>(owned), 0.0);
  std::array<std::vector<double>, NumberOfChannels> b;
  std::array<const double*, NumberOfChannels> bp{};
  std::array<double*, NumberOfChannels> xp{};
  std::array<bool, NumberOfChannels> guess{};
  DistributedSolveControl control;
  control.RelTol = RelTol_;
  control.MaxIter = MaxIter_;
  control.ChangeTol = ChangeTol_;
  control.ChangeRows = ChangeTol_ > 0.0 ? &BoundaryRows_ : nullptr;
  control.FuseChannels = FusedReductions_;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    b[c].resize(static_cast<std::size_t>(owned));
    for (int r = 0; r < owned; ++r)
      b[c][static_cast<std::size_t>(r)] = rhs[3 * static_cast<std::size_t>(r) + c];
    bp[c] = b[c].data();
    std::vector<double>& x = Solution_[c];
    guess[c] = WarmStart_ && x.size() == static_cast<std::size_t>(owned);
    if (!guess[c])
      x.assign(static_cast<std::size_t>(owned), 0.0);
    xp[c] = x.data();
    control.MinIter[c] = sameMesh && setup[c] != ChannelSetup::Kept ? 1 : 0;
  }
  std::array<bool, NumberOfChannels> pending{ true, true, true };
  std::string error;
  for (int attempt = 0; attempt < 2 && (pending[0] || pending[1] || pending[2]); ++attempt)
  {
    std::array<DistributedLinearSolver*, NumberOfChannels> solvers{};
    DistributedLinearSolver* first = nullptr;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      solvers[c] = pending[c] ? Channels_[c].get() : nullptr;
      if (!first && solvers[c])
        first = solvers[c];
    }
    std::array<DistributedChannelStats, NumberOfChannels> stats{};
    try
    {
      if (ThreeChannelPCG_)
        first->SolveChannels(solvers, bp, xp, guess, control, stats);
      else
        first->SolveChannelsOneByOne(solvers, bp, xp, guess, control, stats);
    }
    catch (const Error& e)
    {
      error = e.what();
    }
    AgreeOnError(Comm_, error);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      if (!pending[c])
        continue;
      // Global: the same on every rank.
      report.Iterations[c] = stats[c].Iterations;
      report.Residual[c] = stats[c].RelativeResidual;
      report.Converged[c] = stats[c].Converged;
      report.StoppedByChange[c] = stats[c].StoppedByChange;
      const int iterations = stats[c].Iterations;
      if (report.Converged[c] || setup[c] == ChannelSetup::Fresh || attempt > 0)
      {
        pending[c] = false;
        if (FullIterations_[c] < 0)
          FullIterations_[c] = iterations;
        else if (setup[c] == ChannelSetup::ValuesOnly && iterations > 2 * std::max(FullIterations_[c], 5))
          ForceFull_[c] = true; // the kept hierarchy has aged: rebuild at the next change
      }
    }
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      if (!pending[c])
        continue;
      SetUpChannel(c); // the kept or shared hierarchy failed: its own, solve again cold
      hierarchyMs += Channels_[c]->GetHierarchyMilliseconds();
      ReshareDependents(c, hierarchyMs); // the others that used c's old hierarchy
      report.Resolved = true;
      guess[c] = false;
    }
  }
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    const std::vector<double>& x = Solution_[c];
    for (int r = 0; r < owned; ++r)
      solution[3 * static_cast<std::size_t>(r) + c] = x[static_cast<std::size_t>(r)];
  }
}

void DistributedVertexSolver::ReadOuts(const OpticalProperties& material,
  const std::vector<double>& irradiance, const std::vector<double>& fluence,
  const std::array<double, NumberOfChannels>& localSourcePower)
{
  Readings_.clear();
  if (!Detectors_.empty())
    Readings_ = ReadDistributedDetectors(Comm_, Piece(material), Detectors_, fluence, &irradiance, Rule_);

  // The power balance: this rank's tets and physical faces, summed.
  std::array<double, 4 * NumberOfChannels> sums{};
  if (HasTets())
  {
    // (The material was validated by this Solve's CheckPiece.)
    const PowerBalance local = ComputePowerBalanceOfValidMaterial(
      *Mesh_, material, fluence, &irradiance, Rule_, &PhysicalFace_);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      sums[c] = local.Absorbed[c];
      sums[NumberOfChannels + c] = local.Escaped[c];
      sums[2 * NumberOfChannels + c] = local.BoundaryInjected[c];
    }
  }
  for (int c = 0; c < NumberOfChannels; ++c)
    sums[3 * NumberOfChannels + c] = localSourcePower[c];
  MPI_Allreduce(MPI_IN_PLACE, sums.data(), static_cast<int>(sums.size()), MPI_DOUBLE, MPI_SUM,
    Comm_);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    Balance_.Absorbed[c] = sums[c];
    Balance_.Escaped[c] = sums[NumberOfChannels + c];
    Balance_.BoundaryInjected[c] = sums[2 * NumberOfChannels + c];
    SourcePower_[c] = sums[3 * NumberOfChannels + c];
  }
}

void DistributedVertexSolver::FillStatistics(SolverReport& report) const
{
  const int owned = Numbering_.GetNumberOfOwnedRows();
  report.SetupMilliseconds = Timings_.Numbering + Timings_.Assembly + Timings_.AMGSetup;
  report.SolveMilliseconds = Timings_.Solve;
  report.NumberOfUnknowns = Numbering_.GetNumberOfRows();
  report.NumberOfNonZeros = Channels_[0] ? Channels_[0]->GetNumberOfNonZeros() : 0;
  std::size_t bytes = Numbering_.GetMemoryBytes() +
    (OwnedOffsets_.capacity() + OwnedColumns_.capacity() + LocalPositions_.capacity() +
      Targets_.capacity() + SendPositionsOff_.capacity() + SendPoints_.capacity() +
      RowEntryOffsets_.capacity() + RowEntries_.capacity()) * sizeof(int) +
    (MatrixMeasures_.capacity() + OwnedMeasures_.capacity()) * sizeof(double);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    bytes += Contributions_[c].capacity() * sizeof(double) + Solution_[c].capacity() * sizeof(double);
    // The local values and partial rows kept for the changed-rows update.
    bytes += (LocalValues_[c].capacity() + Received_[c].capacity()) * sizeof(double);
    if (Channels_[c])
    {
      // The hierarchy below the fine level with its interpolation, the two IJ
      // vectors, and the fine matrix (~ the entries sent, 12 bytes each).
      bytes += Channels_[c]->GetMemoryBytes() + static_cast<std::size_t>(owned) * 2 * sizeof(double) +
        OwnedColumns_.size() * (sizeof(int) + sizeof(double));
    }
  }
  // The beam kept across paints (the surface, rays, E_c and loads).
  report.MemoryBytes = bytes + Beam_.GetMemoryBytes();
}

void DistributedVertexSolver::Solve(const std::vector<double>& points,
  const std::vector<PointKey>& keys, const std::vector<int>& tets,
  const OpticalProperties& material, const std::vector<double>& irradiance,
  std::vector<double>& fluence, SolverReport& report)
{
  // The piece's sizes and ids, then its TetMesh (kept while the arrays are
  // the same: its revision keys the numbering and the geometry cache).
  ChangedHint_.reset(); // (the arrays carry no promise)
  CheckPiece(points, keys, tets, material, irradiance);
  std::string error;
  if (tets.empty())
  {
    OwnMesh_ = TetMesh();
    Points_.clear();
    Tets_.clear();
  }
  else if (OwnMesh_.GetNumberOfTets() == 0 || points != Points_ || tets != Tets_)
  {
    try
    {
      Points_.clear();
      Tets_.clear();
      OwnMesh_.SetGeometry(points, tets);
      Points_ = points;
      Tets_ = tets;
    }
    catch (const Error& e)
    {
      error = e.what();
      OwnMesh_ = TetMesh();
    }
  }
  AgreeOnError(Comm_, error);
  SolvePiece(
    tets.empty() ? nullptr : &OwnMesh_, keys, material, irradiance, nullptr, fluence, report);
}

bool DistributedVertexSolver::Solve(
  const DiffusionProblem& problem, std::vector<double>& fluence, SolverReport& report)
{
  // SetChangedTets' promise is for this Solve only.
  const std::optional<std::vector<int>> hint = std::exchange(ChangedHint_, std::nullopt);
  std::string error;
  if (!problem.PointKeys)
  {
    error = "the distributed " + Name_ +
      " solve needs the points' global keys (DiffusionProblem::PointKeys)";
  }
  else if (!problem.Material || !problem.Irradiance)
  {
    error = "the distributed " + Name_ + " solve needs a material and an irradiance";
  }
  AgreeOnError(Comm_, error);
  // The lights and the collimated model: the lowest rank with tets' (an
  // empty piece may carry no field data), the same on every rank.
  Lights_ = problem.Lights;
  Shadows_ = problem.Shadows;
  Collimated_ = problem.Collimated;
  double uniform = problem.UniformIrradiance;
  int unused = 0;
  AgreeOnLights(Comm_, problem.Mesh && problem.Mesh->GetNumberOfTets() > 0, Lights_, uniform,
    Shadows_, Collimated_, unused);
  Rule_ = Collimated_ == CollimatedModel::ExtendedMoments ? Fresnel::BoundaryRule::Moments
                                                          : Fresnel::BoundaryRule::Fit;
  Sources_ = problem.InteriorSources;
  try
  {
    SolvePiece(problem.Mesh, *problem.PointKeys, *problem.Material, *problem.Irradiance,
      hint ? &*hint : nullptr, fluence, report);
  }
  catch (...)
  {
    Sources_ = nullptr;
    Mesh_ = &EmptyMesh_;
    Collimated_ = CollimatedModel::Surface;
    Rule_ = Fresnel::BoundaryRule::Fit;
    throw;
  }
  Sources_ = nullptr; // borrowed for this call only
  Mesh_ = &EmptyMesh_;
  // The array Solve (the bench) has the surface model.
  Collimated_ = CollimatedModel::Surface;
  Rule_ = Fresnel::BoundaryRule::Fit;
  return true;
}

void DistributedVertexSolver::AddVolumeSources(const std::vector<PointKey>& keys,
  const OpticalProperties& material, std::vector<double>& localRhs,
  std::array<double, NumberOfChannels>& localSourcePower)
{
  // The extended collimated models: the beam's volume source (its rank's
  // tets' share, summed at the owners by the caller).
  BeamResult_ = CollimatedSource();
  if (IsExtendedCollimatedModel(Collimated_))
  {
    // (The numbering and boundary count of step 1: not built again.)
    Beam_.Compute(Comm_, HasTets() ? Mesh_ : nullptr, keys, Used_, material, Lights_, Shadows_,
      BeamResult_, &Numbering_, &PhysicalFace_);
    for (std::size_t k = 0; k < BeamResult_.Load.size(); ++k)
      localRhs[k] += 4.0 * BeamResult_.Load[k];
  }
  if (Sources_ && !Sources_->Empty())
  {
    const std::vector<double> load =
      ComputeDistributedSourceLoad(Comm_, Piece(material), *Sources_);
    for (std::size_t k = 0; k < load.size(); ++k)
    {
      localRhs[k] += 4.0 * load[k];
      localSourcePower[k % 3] += load[k];
    }
  }
}

DistributedVertexSolver::MatrixChange DistributedVertexSolver::FindMatrixChange(bool sameMesh,
  const OpticalProperties& material, const std::vector<int>* hint, std::vector<int>& changedTets)
{
  // The same mesh, options, linear solvers and Robin rule (the collimated
  // model's) everywhere, and the tets whose coefficients changed since the
  // last matrices, counted over the ranks: none is a relight; a few
  // (MaximumChangedFraction_ of all) the changed-rows update.
  changedTets.clear();
  ChangedTets_ = -1;
  ChangedRowCount_ = 0;
  KeepMeasures_ = false;
  bool ready = sameMesh && !OptionsChanged_;
  for (int c = 0; c < NumberOfChannels; ++c)
    ready = ready && Channels_[c] && Donor_[c] >= 0 && LinearSolverName() == ChannelLinear_[c];
  int allReady = ready ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &allReady, 1, MPI_INT, MPI_MIN, Comm_);
  if (!allReady || Rule_ != MatrixRule_)
    return MatrixChange::Assemble;
  long long etaChanged = 0;
  const bool comparable = FindChangedTets(material, hint, changedTets, etaChanged);
  long long counts[5] = { comparable ? 0 : 1, static_cast<long long>(changedTets.size()),
    Mesh_->GetNumberOfTets(), HaveLocalValues_ ? 0 : 1, etaChanged };
  MPI_Allreduce(MPI_IN_PLACE, counts, 5, MPI_LONG_LONG, MPI_SUM, Comm_);
  if (counts[0] != 0)
    return MatrixChange::Assemble;
  // No eta changed on any rank: the divergence's boundary measures are the last ones.
  KeepMeasures_ = counts[4] == 0;
  if (counts[1] == 0)
    return MatrixChange::None;
  return ChangedRowsUpdate_ && counts[3] == 0 &&
      static_cast<double>(counts[1]) <= MaximumChangedFraction_ * static_cast<double>(counts[2])
    ? MatrixChange::ChangedRows
    : MatrixChange::Assemble;
}

std::array<DistributedVertexSolver::ChannelSetup, NumberOfChannels>
DistributedVertexSolver::UpdateMatrices(MatrixChange change, bool sameMesh,
  const OpticalProperties& material, const std::vector<double>& irradiance,
  const std::vector<int>& changedTets, DiffusionSystem& system, SolverReport& report,
  double& hierarchyMs)
{
  std::array<ChannelSetup, NumberOfChannels> setup{};
  if (change != MatrixChange::Assemble)
  {
    // The irradiance is checked here (AssembleLocal checks it otherwise).
    std::string error;
    try
    {
      if (HasTets())
        CheckIrradiance(*Mesh_, irradiance);
    }
    catch (const Error& e)
    {
      error = e.what();
    }
    AgreeOnError(Comm_, error);
  }
  if (change == MatrixChange::None)
  {
    report.Assembly = "unchanged";
    return setup;
  }
  HaveMaterial_ = false;
  const bool rows = change == MatrixChange::ChangedRows;
  std::vector<int> ownedRows;
  std::array<bool, NumberOfChannels> rowsChanged{};
  if (rows)
  {
    UpdateChangedRows(material, changedTets, ownedRows, rowsChanged);
    ChangedTets_ = static_cast<long long>(changedTets.size());
    ChangedRowCount_ = static_cast<long long>(ownedRows.size());
  }
  setup = SetUpMatrices(
    sameMesh, system, rows ? &ownedRows : nullptr, rowsChanged, report.Assembly, hierarchyMs);
  MatrixMeasures_ = OwnedMeasures_;
  MatrixRule_ = Rule_;
  if (rows)
  {
    // The kept material differs from this one in the changed tets only.
    for (const int t : changedTets)
    {
      const std::size_t k = static_cast<std::size_t>(t);
      std::copy_n(material.AbsorptionCoefficient.begin() + 3 * k, 3,
        Material_.AbsorptionCoefficient.begin() + 3 * k);
      std::copy_n(material.ReducedScatteringCoefficient.begin() + 3 * k, 3,
        Material_.ReducedScatteringCoefficient.begin() + 3 * k);
      Material_.RefractiveIndex[k] = material.RefractiveIndex[k];
    }
  }
  else
  {
    Material_.AbsorptionCoefficient = material.AbsorptionCoefficient;
    Material_.ReducedScatteringCoefficient = material.ReducedScatteringCoefficient;
    Material_.RefractiveIndex = material.RefractiveIndex;
  }
  HaveMaterial_ = true;
  return setup;
}

void DistributedVertexSolver::SolvePiece(const TetMesh* mesh, const std::vector<PointKey>& keys,
  const OpticalProperties& material, const std::vector<double>& irradiance,
  const std::vector<int>* hint, std::vector<double>& fluence, SolverReport& report)
{
  Timings_ = Timings();
  HierarchyCpu_ = 0.0;
  Readings_.clear();
  report = SolverReport();
  // NumberOfThreads 0: the node's cores shared by its ranks (collective).
  std::unique_ptr<ScopedRankThreads> threads;
  if (NumberOfThreads_ <= 0)
  {
    threads = std::make_unique<ScopedRankThreads>(Comm_);
  }
  report.Solver = Name_;
  report.LinearSolver = LinearSolverName() + " (distributed)";
  report.Assembly = "full";

  // 0. The piece's sizes.
  CheckPiece(mesh, keys, material, irradiance, hint);
  if (mesh && mesh->GetNumberOfTets() == 0)
  {
    mesh = nullptr;
  }

  // 1. The global identity and boundary, unless the mesh is the last one.
  double start = MPI_Wtime();
  double cpu = CpuMilliseconds();
  const std::uint64_t revision = mesh ? mesh->GetGeometryRevision() : 0;
  int same = HaveGeometry_ && revision == Revision_ && keys == Keys_ ? 1 : 0;
  int allSame = 0;
  MPI_Allreduce(&same, &allSame, 1, MPI_INT, MPI_MIN, Comm_);
  Mesh_ = mesh ? mesh : &EmptyMesh_;
  if (!allSame)
  {
    BuildGeometry(mesh, keys);
    Timings_.Numbering = Milliseconds(start);
    Timings_.NumberingCpu = CpuMilliseconds() - cpu;
  }

  // 2. The local system: element matrices of the owned tets, boundary terms
  // of the physical faces, interior sources (their load on the rank owning
  // each source's tet, times 4 as every right-hand side: FiniteElement.h).
  // A relight (every rank's mesh and material the last set-up's, bit for
  // bit, the hierarchies kept) assembles the right-hand side only.
  start = MPI_Wtime();
  cpu = CpuMilliseconds();
  std::vector<int> changedTets;
  const MatrixChange change = FindMatrixChange(allSame != 0, material, hint, changedTets);
  const bool relight = change == MatrixChange::None;
  const bool rowsUpdate = change == MatrixChange::ChangedRows;
  DiffusionSystem system;
  if (!relight && !rowsUpdate)
  {
    AssembleLocal(material, irradiance, system);
  }
  std::vector<double> localRhs(3 * keys.size(), 0.0);
  AddBoundaryTerms(
    material, irradiance, relight || rowsUpdate ? nullptr : &system, localRhs);
  std::array<double, NumberOfChannels> localSourcePower{};
  AddVolumeSources(keys, material, localRhs, localSourcePower);
  const std::vector<double> rhs = Numbering_.SumToOwners(Comm_, localRhs, 3);
  localRhs = {};

  // 3. The hypre matrices and their hierarchies.
  double hierarchyMs = 0.0;
  const long long hierarchiesBefore = HierarchySetups_;
  const std::array<ChannelSetup, NumberOfChannels> setup = UpdateMatrices(
    change, allSame != 0, material, irradiance, changedTets, system, report, hierarchyMs);
  system = DiffusionSystem();
  Timings_.Assembly = Milliseconds(start) - hierarchyMs;
  Timings_.AssemblyCpu = CpuMilliseconds() - cpu - HierarchyCpu_;
  Timings_.AMGSetupCpu = HierarchyCpu_;

  // 4. PCG per channel (again after a full set-up if a kept hierarchy fails).
  start = MPI_Wtime();
  cpu = CpuMilliseconds();
  HierarchyCpu_ = 0.0;
  double retryMs = 0.0;
  std::vector<double> solution;
  SolveChannels(rhs, setup, allSame != 0, solution, report, retryMs);
  fluence = Numbering_.FetchFromOwners(Comm_, solution, 3);
  Timings_.Solve = Milliseconds(start) - retryMs;
  // The diffuse fluence read out below; Fluence = phi_d + E_c (the serial
  // VertexDiffusionSolver's AddCollimatedFluence).
  std::vector<double> diffuse;
  const bool beam = BeamResult_.Fluence.size() == fluence.size() && !BeamResult_.Beams.empty();
  if (beam)
  {
    diffuse = fluence;
    for (std::size_t k = 0; k < fluence.size(); ++k)
      fluence[k] += BeamResult_.Fluence[k];
  }
  Timings_.AMGSetup = hierarchyMs + retryMs;
  Timings_.SolveCpu = CpuMilliseconds() - cpu - HierarchyCpu_;
  Timings_.AMGSetupCpu += HierarchyCpu_;

  // 5. Detectors and the power balance, summed over the ranks.
  ReadOuts(material, irradiance, beam ? diffuse : fluence, localSourcePower);
  FillStatistics(report);
  if (IsExtendedCollimatedModel(Collimated_))
  {
    report.CollimatedFluence = BeamResult_.Fluence;
    report.CollimatedEntering = BeamResult_.Entering;
    report.CollimatedScattered = BeamResult_.Scattered;
    report.CollimatedAbsorbed = BeamResult_.Absorbed;
    // What the beam did (kept rays and loads on a paint), as the serial
    // solver's CollimatedSourceCache reports it.
    report.Collimated = Beam_.GetLastUpdate();
    if (report.CollimatedFluence.size() != fluence.size())
      report.CollimatedFluence.assign(fluence.size(), 0.0);
  }
  // Only the power sums are read later (GetTalliedReadouts).
  BeamResult_.Fluence = {};
  BeamResult_.Load = {};
  BeamResult_.Beams = {};
  std::ostringstream linear;
  linear << (HierarchySetups_ > hierarchiesBefore ? "rebuilt"
               : report.Assembly == "values-only"  ? (rowsUpdate ? "rows" : "values")
                                                   : "kept")
         << " (numberings " << Numberings_ << ", hierarchies " << HierarchySetups_ << ")";
  report.LinearSetup = linear.str();
}

} // namespace translucency
