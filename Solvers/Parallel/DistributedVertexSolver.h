/**
 * @file DistributedVertexSolver.h
 * @brief The diffusion solve of a tet mesh distributed over MPI ranks
 * (divergence or fem discretisation): each rank assembles its own tets
 * into one hypre IJ matrix, solved by PCG with BoomerAMG on all ranks.
 *
 * Every rank gives its piece: its points (with a global key each: a
 * global id, or the exact coordinates), the tets it owns (ghost cells
 * left out by the caller), their material, and the irradiance at its
 * points. The result is the fluence at every local point, shared points
 * included, equal to the serial solve on the union of the tets:
 *  - a vertex shared by pieces is one unknown (DistributedNumbering);
 *  - a face is boundary only if no tet of any rank shares it: each rank's
 *    local boundary faces are counted across ranks (CountSharedTriangles);
 *    S_i and the area-weighted boundary eta of the divergence are summed
 *    over the ranks at the vertex's owner, the fem's Robin terms added by
 *    the rank of the face's tet;
 *  - each rank adds its tets' element matrices (TetContributions.h, the
 *    serial assemblies' expressions) to the rows of their vertices, off-rank
 *    rows through HYPRE_IJMatrixAddToValues.
 * The three channels are solved in one PCG with the serial stopping rules
 * (SetThreeChannelPCG); iterations and residuals are global (the same on
 * every rank). The hierarchy is kept while the matrix is unchanged (a relight),
 * and the solve warm-starts from the previous solution on the same mesh.
 *
 * Every public call is collective over the communicator (ranks with empty
 * pieces too); an error on any rank is thrown on every rank with the same
 * message (AgreeOnError).
 *
 * It is the registry's distributed variant of "divergence" and "fem"
 * (DiffusionSolverFactory.h, trait Distributed; registered when this layer
 * is loaded): a DiffusionSolver that takes its communicator as PETSc objects
 * do (SetCommunicator; none means MPI_COMM_SELF, one rank, so it runs
 * without mpiexec too), and takes RelTol, MaxIter, the warm start, interior
 * sources and detectors as the serial solvers do. DiffusionFrontEnd chooses
 * it by that trait (SetCommunicator); its detector readings and power
 * balance, summed over the ranks, are its tallied read-outs
 * (GetTalliedReadouts).
 */
#pragma once

#include "DiffusionSolver.h"
#include "DistributedCollimatedSource.h"
#include "DistributedNumbering.h"
#include "DistributedSources.h"
#include "DistributedLinearSolver.h"
#include "HypreSolver.h" // GetMPIComm, MakeCommunicator: the MPI side of Communicator
#include "OpticalProperties.h"
#include "TetGeometry.h"
#include "TetMesh.h"

#include <mpi.h>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace translucency
{

class DistributedVertexSolver : public DiffusionSolver
{
public:
  /// `discretization`: "divergence" or "fem" (else translucency::Error), on
  /// MPI_COMM_SELF until SetCommunicator.
  explicit DistributedVertexSolver(const std::string& discretization);
  /// As above on `comm`, which must outlive the solver.
  DistributedVertexSolver(MPI_Comm comm, const std::string& discretization);
  ~DistributedVertexSolver() override;

  /// "divergence" or "fem" (the discretisation's registry name).
  std::string GetName() const override { return Name_; }
  /// Any communicator (none: MPI_COMM_SELF). A new one forgets the mesh,
  /// the hierarchies and the warm start.
  void SetCommunicator(const Communicator& comm) override;
  /**
   * Collective: the DiffusionSolver interface. The problem's Mesh is this
   * rank's piece (owned tets on the local points; null for a rank without
   * tets), PointKeys the points' identities (required), Irradiance 3 per
   * point, InteriorSources the sources (null: none). Continuous wave. The
   * extended collimated models (Extended, ExtendedMoments; Irradiance then
   * without the directional lights) add the beam's volume source of
   * problem.Lights (DistributedCollimatedSource: the physical boundary
   * all-gathered, no mesh) and its E_c to the fluence, with the Robin rule
   * of the model (ExtendedMoments: Fresnel::BoundaryRule::Moments); the
   * lights, shadows and model are the lowest rank with tets' (AgreeOnLights:
   * an empty piece may carry none). The PCG stopping rule is ||b - A x|| <=
   * RelTol ||b|| per channel (global norms), with the serial solvers'
   * MinIter after a paint and change rule (SetThreeChannelPCG). Throws translucency::Error on
   * every rank on invalid input; returns true.
   */
  bool Solve(const DiffusionProblem& problem, std::vector<double>& fluence,
    SolverReport& report) override;
  /// Forgets the hierarchies and the warm start (keeps the numbering of an
  /// unchanged mesh): the next Solve sets up from scratch.
  void Reset() override;
  /**
   * The caller's promise for the next Solve (DiffusionSolver::SetChangedTets;
   * DiffusionFrontEnd makes it when it passes its kept material back: a
   * relight, or a paint it compared in place): since the last successful
   * Solve on this rank's mesh only `changedTets`' coefficients changed. That
   * Solve then takes them as this rank's changed tets instead of comparing
   * the whole material with the kept one, and validates only them. Used by
   * the next Solve only; ignored when this solver kept no material.
   */
  void SetChangedTets(std::vector<int> changedTets, bool irradianceChanged = false) override;
  /// The detector readings and power balance of the last Solve (the same on
  /// every rank): injected = the physical faces' irradiance + the sources.
  bool GetTalliedReadouts(TalliedReadouts& readouts) const override;
  /**
   * Values-only set-up (default on): when the mesh is the last Solve's and
   * only the matrix values changed (a paint), the new values go into the
   * same hypre matrices and the BoomerAMG hierarchies are kept
   * (DistributedLinearSolver::UpdateValues): no set-up, PCG still converges
   * to RelTol on the new matrix. A channel whose PCG then needs more than
   * twice the iterations of its last solve after a full set-up (at least
   * 10) gets a full set-up at the next change. A channel whose PCG does not
   * converge under a kept hierarchy (values-only or unchanged matrix) is set
   * up from scratch and solved again, cold, in the same Solve
   * (report.Resolved); the report then has the second solve's iterations
   * and residual, and the caller refuses a result that still did not
   * converge. Off: every change of values rebuilds the hierarchies.
   */
  void SetValuesOnlySetup(bool on) { ValuesOnly_ = on; }
  bool GetValuesOnlySetup() const { return ValuesOnly_; }
  /**
   * The three-channel PCG (default on; issue 32,
   * DistributedLinearSolver::SolveChannels, DistributedPCG.h): convergence
   * tested before the preconditioner (SetFusedReductions: the channels'
   * inner products in one MPI_Allreduce), and the serial stopping rules: a
   * channel whose matrix values changed on the same mesh (a paint) iterates
   * at least once (LinearSolver::SetMinIter(1)), and with
   * DiffusionSolver::SetChangeTol > 0 (the filter's interactive RelTol) a
   * channel also stops when its boundary fluence stopped changing (the
   * change rule over the physical boundary's rows, global sums;
   * report.StoppedByChange). Off: each channel by the linear solver's
   * Solve (hypre's PCG: the preconditioner applied before each convergence
   * test, neither rule), the path before issue 32's session 31, kept for
   * comparison.
   */
  void SetThreeChannelPCG(bool on) { ThreeChannelPCG_ = on; }
  bool GetThreeChannelPCG() const { return ThreeChannelPCG_; }
  /// With SetThreeChannelPCG: the channels' iterations interleaved, their
  /// inner products in one MPI_Allreduce per reduction point
  /// (DistributedSolveControl::FuseChannels; default off: one channel's PCG
  /// after the other's, measured faster, Documentation/Scaling.md).
  void SetFusedReductions(bool on) { FusedReductions_ = on; }
  bool GetFusedReductions() const { return FusedReductions_; }
  /// This rank's owned rows on the physical boundary (the change rule's rows).
  const std::vector<int>& GetBoundaryRows() const { return BoundaryRows_; }
  /**
   * Changed-rows update (default on; issue 32, the serial path's
   * LinearSolver::SetupChangedRows): when the mesh, the Robin rule and the
   * linear solvers are the last Solve's and at most
   * GetMaximumChangedFraction() of the tets (over every rank) have another
   * mu_a, sigma_s' or eta than the last matrices (bit for bit: the solver
   * keeps that material for the relight test; SetChangedTets' promise, when
   * given, replaces that comparison), only the rows of the changed
   * tets' vertices are assembled again: each rank re-sums its local rows of
   * them (every tet around them, in the full assembly's order, and their
   * Robin terms), sends only the changed entries of partition rows to their
   * owners, and the owners re-sum only the owned rows that changed, in the
   * order of the full gather, so the matrices equal a full assembly's bit
   * for bit; the linear solvers get those rows only
   * (DistributedLinearSolver::UpdateRows). The hierarchies follow the
   * values-only rule above (a full set-up when it is off or a channel aged).
   * Costs the local matrix values of the last assembly (3 doubles per local
   * non-zero), kept. report.LinearSetup then starts with "rows". Off: the
   * local matrices are assembled whole at every change.
   */
  void SetChangedRowsUpdate(bool on) { ChangedRowsUpdate_ = on; }
  bool GetChangedRowsUpdate() const { return ChangedRowsUpdate_; }
  /// Largest fraction of the tets (summed over the ranks, in [0, 1]) for
  /// which the changed-rows update is taken (default 0.05, as
  /// DiffusionFrontEnd's incremental assembly); beyond it the whole local
  /// assembly is cheaper.
  void SetMaximumChangedFraction(double fraction) { MaximumChangedFraction_ = fraction; }
  double GetMaximumChangedFraction() const { return MaximumChangedFraction_; }
  /// The last Solve on this rank: its changed tets (-1: the changed-rows
  /// update did not run) and the owned rows it wrote into the matrices.
  long long GetNumberOfChangedTets() const { return ChangedTets_; }
  long long GetNumberOfChangedRows() const { return ChangedRowCount_; }
  /**
   * This rank's owned rows of channel c's matrix as the linear solver got
   * them (CSR: row offsets from 0, sorted global columns, values; empty
   * before the first Solve): the kept values a changed-rows update writes
   * into, for tests against a full assembly.
   */
  const std::vector<int>& GetOwnedRowOffsets() const { return OwnedOffsets_; }
  const std::vector<int>& GetOwnedColumns() const { return OwnedColumns_; }
  const std::vector<double>& GetOwnedValues(int c) const { return Contributions_[c]; }
  /**
   * One BoomerAMG coarsening for the three channels (default on; issue
   * 32): when every channel needs a new hierarchy (a new mesh, a full
   * set-up), BoomerAMG is set up once, on the channel whose matrix has the
   * median trace (summed over the ranks), and the other two channels get
   * their own Galerkin levels on its interpolation
   * (DistributedLinearSolver::SetupShared: P^T A_c P per level, their own
   * smoother norms and coarsest matrix), so that each channel's V-cycle is
   * BoomerAMG's on a hierarchy of its own matrix, as the serial path's
   * aggregation multigrid shares one aggregation between its channels. The
   * convergence check still guards each channel: one that does not
   * converge gets a hierarchy of its own and is solved again
   * (report.Resolved). Measured at 1M tets on one rank (Scaling.md,
   * session 34): BoomerAMG set-up ~350 ms against ~700-800 ms with a
   * hierarchy per channel, at the same iterations. Off: one hierarchy per
   * channel.
   */
  void SetSharedHierarchy(bool on) { SharedHierarchy_ = on; }
  bool GetSharedHierarchy() const { return SharedHierarchy_; }
  /// Since construction: how many times the global numbering and boundary
  /// were built, and how many BoomerAMG hierarchies were set up (a relight
  /// adds to neither; a cold solve with a shared hierarchy adds 1 to each).
  long long GetNumberOfNumberings() const { return Numberings_; }
  long long GetNumberOfHierarchySetups() const { return HierarchySetups_; }
  /// OpenMP threads of the local assembly (0, the default: the node's
  /// cores shared by its ranks, ScopedRankThreads, unless OMP_NUM_THREADS).
  void SetNumberOfThreads(int n) override { NumberOfThreads_ = n; }
  /**
   * Interior sources (point sources, pencil beams) of the next Solves (null
   * or empty: none; the pointer must stay valid through Solve). Their load
   * is added to the right-hand side where the lowest rank owning each
   * source's tet puts it (DistributedSources.h); a source outside the
   * object is the same error on every rank. The matrix and its hierarchy
   * do not depend on them.
   */
  void SetInteriorSources(const Sources* sources) { Sources_ = sources; }
  /// Detectors read after each Solve (GetDetectorReadings: the same on every rank).
  void SetDetectors(const std::vector<Detector>& detectors) override { Detectors_ = detectors; }
  /// The readings of the last Solve (one per detector; empty without detectors).
  const std::vector<DetectorReading>& GetDetectorReadings() const { return Readings_; }
  /**
   * The power balance of the last Solve's fluence over the whole distributed
   * mesh, the same on every rank: each rank's ComputePowerBalance over its
   * owned tets and its physical boundary faces (a face shared with another
   * rank's tet is neither escaping nor entering surface), summed over the
   * ranks (one MPI_Allreduce at the end of Solve). Up to the order of the
   * sums, the serial ComputePowerBalance of the whole mesh.
   */
  const PowerBalance& GetPowerBalance() const { return Balance_; }
  /// Power the interior sources inject per channel (W; the sum of their
  /// load over the ranks: Sources::InjectedPower of the whole mesh).
  const std::array<double, NumberOfChannels>& GetInjectedSourcePower() const
  {
    return SourcePower_;
  }
  /**
   * The linear solver: DiffusionSolver::SetLinearSolver's name or
   * composition of the registry ("" = "cg/boomeramg", BoomerAMG-PCG with
   * BoomerAMGOptions::Tuned()), created through CreateDistributedLinearSolver
   * with these options (e.g. BoomerAMGOptions::ToOptions(); default none); a
   * change rebuilds the hierarchy at the next Solve.
   */
  void SetLinearSolverOptions(const SolverOptions& options);

  /**
   * Collective. points: 3 per local point (mm); keys: one per local point;
   * tets: 4 local point ids per owned tet; material: per owned tet;
   * irradiance: 3 per local point (W/mm^2). fluence gets 3 per local point.
   * Throws translucency::Error (on every rank) on invalid input.
   * report.Assembly is "full" when the hypre matrices and hierarchies were
   * rebuilt, "values-only" when new values went into the kept matrices and
   * hierarchies (SetValuesOnlySetup), "unchanged" when every rank's matrix
   * values equal the last Solve's (a relight: the hierarchies are kept,
   * only the right-hand side is new; when every rank's mesh and material are
   * the last Solve's, bit for bit, nothing but the right-hand side is
   * assembled); report.LinearSetup says "kept", "values", "rows" (values-only,
   * the changed rows only: SetChangedRowsUpdate) or "rebuilt" and
   * the counts so far, "(numberings N, hierarchies H)"; iterations and
   * residuals are the same on every rank. (The interface's Solve on a
   * TetMesh this solver builds.)
   */
  void Solve(const std::vector<double>& points, const std::vector<PointKey>& keys,
    const std::vector<int>& tets, const OpticalProperties& material,
    const std::vector<double>& irradiance, std::vector<double>& fluence, SolverReport& report);

private:
  /// This rank's piece as DistributedSources.h sees it.
  DistributedPiece Piece(const OpticalProperties& material) const;

public:

  /// Wall times of the last Solve on this rank (ms): global numbering and
  /// boundary (0 when the mesh is unchanged), local assembly and hypre's
  /// IJ assembly, BoomerAMG set-up (0 if kept), PCG solve.
  struct Timings
  {
    double Numbering = 0.0;
    double Assembly = 0.0;
    double AMGSetup = 0.0;
    double Solve = 0.0;
    /// The same phases in this process's CPU time (ms): the work, whatever
    /// the machine's load (a rank waiting in MPI may spin, though).
    double NumberingCpu = 0.0;
    double AssemblyCpu = 0.0;
    double AMGSetupCpu = 0.0;
    double SolveCpu = 0.0;
  };
  const Timings& GetTimings() const { return Timings_; }
  /// The extended collimated source of the last Solve (its figures: surface
  /// gathered or kept, wall times; empty under the surface model).
  const DistributedCollimatedSource& GetCollimatedSource() const { return Beam_; }
  /// Owned rows on this rank and the global number of unknowns.
  int GetNumberOfOwnedRows() const { return Numbering_.GetNumberOfOwnedRows(); }
  long long GetNumberOfRows() const { return Numbering_.GetNumberOfRows(); }
  /// Levels and operator complexity of channel c's hierarchy.
  int GetNumberOfLevels(int c) const;
  double GetOperatorComplexity(int c) const;

private:
  /// What a channel's hierarchy got in this Solve.
  enum class ChannelSetup
  {
    Kept,       ///< the matrix is unchanged (a relight)
    ValuesOnly, ///< new values under the kept hierarchy (a paint)
    Shared,     ///< a new matrix under another channel's new hierarchy
    Fresh       ///< set up from scratch
  };
  // The phases of Solve (each collective).
  /// `hint`: this rank's changed tets promised by SetChangedTets (or null).
  void SolvePiece(const TetMesh* mesh, const std::vector<PointKey>& keys,
    const OpticalProperties& material, const std::vector<double>& irradiance,
    const std::vector<int>* hint, std::vector<double>& fluence, SolverReport& report);
  void CheckPiece(const std::vector<double>& points, const std::vector<PointKey>& keys,
    const std::vector<int>& tets, const OpticalProperties& material,
    const std::vector<double>& irradiance) const;
  void CheckPiece(const TetMesh* mesh, const std::vector<PointKey>& keys,
    const OpticalProperties& material, const std::vector<double>& irradiance,
    const std::vector<int>* hint) const;
  /// Whether SetChangedTets' promise applies to `material` (a kept material
  /// of this rank's sizes to compare with).
  bool HintApplies(const OpticalProperties& material, const std::vector<int>* hint) const;
  bool HasTets() const { return Mesh_->GetNumberOfTets() > 0; }
  void AssembleLocal(const OpticalProperties& material, const std::vector<double>& irradiance,
    DiffusionSystem& system);
  /// The boundary terms: the Robin matrix terms into `system` (null: a
  /// relight, the right-hand side only) and the load into localRhs.
  void AddBoundaryTerms(const OpticalProperties& material, const std::vector<double>& irradiance,
    DiffusionSystem* system, std::vector<double>& localRhs);
  /// What the matrices need in this Solve (the same on every rank).
  enum class MatrixChange
  {
    None,        ///< every rank's matrix values are the last set-up's (a relight)
    ChangedRows, ///< a few tets changed: their rows only (SetChangedRowsUpdate)
    Assemble     ///< the whole local matrices
  };
  /// Collective: the change, and this rank's changed tets (ChangedRows).
  MatrixChange FindMatrixChange(bool sameMesh, const OpticalProperties& material,
    const std::vector<int>* hint, std::vector<int>& changedTets);
  /// Collective: the matrices after the assembly of `system` (Assemble) or
  /// with the changed rows (ChangedRows), their hierarchies, and the
  /// material they are of kept; report.Assembly. Returns what each channel got.
  std::array<ChannelSetup, NumberOfChannels> UpdateMatrices(MatrixChange change, bool sameMesh,
    const OpticalProperties& material, const std::vector<double>& irradiance,
    const std::vector<int>& changedTets, DiffusionSystem& system, SolverReport& report,
    double& hierarchyMs);
  /// This rank's tets whose coefficients differ from the last matrices'
  /// (Material_, bit for bit; with a `hint` that applies, the hinted tets
  /// without comparing the others); false when there is nothing to compare with.
  bool FindChangedTets(const OpticalProperties& material, const std::vector<int>* hint,
    std::vector<int>& changed, long long& etaChanged) const;
  /**
   * The changed-rows update of the local values and the owned rows
   * (collective; SetChangedRowsUpdate): LocalValues_, Received_ and
   * Contributions_ of every channel as a full assembly would give them.
   * `ownedRows` gets this rank's owned rows that were re-summed, `changed`
   * per channel whether any of their values changed on this rank.
   */
  void UpdateChangedRows(const OpticalProperties& material, const std::vector<int>& changedTets,
    std::vector<int>& ownedRows, std::array<bool, NumberOfChannels>& changed);
  /// UpdateChangedRows, 1: the local rows `rows` (flagged in rowFlag) of
  /// every channel re-summed from their tets and Robin terms.
  void ResumLocalRows(const OpticalProperties& material, const std::vector<char>& rowFlag,
    const std::vector<int>& rows);
  /// UpdateChangedRows, 2 (collective): the changed entries of partition
  /// rows sent to their owners into Received_; flags the owned rows they
  /// add to.
  void ExchangeChangedEntries(const std::vector<char>& rowFlag, std::vector<char>& ownedFlag);
  /// Per owned row, its local and received entries in GatherOwnedRows' order
  /// (RowEntryOffsets_, RowEntries_), once per mesh.
  void BuildRowEntries();
  /**
   * The matrices after the assembly (collective): rebuilt (values added,
   * hierarchy set up) when changed, or, on the same mesh, new values under
   * the kept hierarchy. `changedRows` null: the values are `system`'s local
   * ones, gathered into owned rows here; else Contributions_ holds them
   * already (UpdateChangedRows) and only the owned rows *changedRows
   * changed, in the channels `rowsChanged` names. Returns what each channel got.
   */
  std::array<ChannelSetup, NumberOfChannels> SetUpMatrices(bool sameMesh, DiffusionSystem& system,
    const std::vector<int>* changedRows, const std::array<bool, NumberOfChannels>& rowsChanged,
    std::string& assembly, double& hierarchyMs);
  void SetUpChannel(int c);
  /// Channel c's matrix under channel `donor`'s hierarchy (own set-up if the
  /// linear solver cannot share).
  void ShareChannel(int c, int donor, double& hierarchyMs);
  /// After channel `donor` got a new hierarchy: the channels that used its
  /// old one (not in `except`) point to the new one.
  void ReshareDependents(int donor, double& hierarchyMs);
  /// The channel whose matrix has the median global trace.
  int MedianChannel() const;
  /// Adds to HierarchyCpu_ the hierarchy's share of `setupCpu` (CPU ms of
  /// channel c's last set-up), in the proportion of its wall times.
  void AddHierarchyCpu(int c, double setupCpu);
  /// Collective: the three channels' PCG (again after a full set-up for a
  /// channel a kept or shared hierarchy failed); sameMesh: the numbering is
  /// the last Solve's (a channel whose values changed then iterates at least once).
  void SolveChannels(const std::vector<double>& rhs,
    const std::array<ChannelSetup, NumberOfChannels>& setup, bool sameMesh,
    std::vector<double>& solution, SolverReport& report, double& hierarchyMs);
  /// SolvePiece's volume sources on this rank's points: the extended
  /// collimated models' beam (BeamResult_) and the interior sources, 4 x
  /// their loads as every right-hand side (collective).
  void AddVolumeSources(const std::vector<PointKey>& keys, const OpticalProperties& material,
    std::vector<double>& localRhs, std::array<double, NumberOfChannels>& localSourcePower);
  void ReadOuts(const OpticalProperties& material, const std::vector<double>& irradiance,
    const std::vector<double>& fluence, const std::array<double, NumberOfChannels>& localSourcePower);
  void FillStatistics(SolverReport& report) const;
  void BuildGeometry(const TetMesh* mesh, const std::vector<PointKey>& keys);
  void BuildOwnedRows();
  /// The owned rows' values (OwnedColumns_ order) of the local CSR values
  /// `local`, with the other ranks' partial rows (collective); `received`
  /// (if not null) gets those partial values as they arrived.
  void GatherOwnedRows(const std::vector<double>& local, std::vector<double>& ownedValues,
    std::vector<double>* received = nullptr) const;

  MPI_Comm Comm_;
  std::string Name_;
  bool Fem_ = false;
  int NumberOfThreads_ = 0;
  SolverOptions LinearOptions_;
  bool OptionsChanged_ = false;
  /// The linear solver each channel was made with ("" = none yet).
  std::array<std::string, NumberOfChannels> ChannelLinear_;
  std::string LinearSolverName() const
  {
    return LinearSolver_.empty() ? std::string("cg/boomeramg") : LinearSolver_;
  }
  /// SetChangedTets' promise, taken by the next Solve.
  std::optional<std::vector<int>> ChangedHint_;
  bool ValuesOnly_ = true;
  bool ThreeChannelPCG_ = true;
  bool FusedReductions_ = false;
  bool SharedHierarchy_ = true;
  bool ChangedRowsUpdate_ = true;
  double MaximumChangedFraction_ = 0.05;
  long long ChangedTets_ = -1, ChangedRowCount_ = 0;
  /// Per channel: the channel whose hierarchy preconditions it (itself if
  /// its own; -1 none).
  std::array<int, NumberOfChannels> Donor_{ -1, -1, -1 };
  long long Numberings_ = 0, HierarchySetups_ = 0;
  /// The material of the last matrices (a relight compares it, bit for bit).
  OpticalProperties Material_;
  bool HaveMaterial_ = false;
  /// Per channel: iterations of the last solve after a full set-up, and
  /// whether the next change of values must rebuild the hierarchy.
  std::array<int, NumberOfChannels> FullIterations_{};
  std::array<bool, NumberOfChannels> ForceFull_{};

  // The geometry of the last Solve and what was derived from it.
  bool HaveGeometry_ = false;
  std::vector<PointKey> Keys_;
  std::uint64_t Revision_ = 0;  ///< of the mesh the numbering is of (0: no tets)
  /// The piece of the Solve in progress (the caller's or OwnMesh_; EmptyMesh_
  /// without tets): valid during Solve only.
  const TetMesh* Mesh_ = &EmptyMesh_;
  TetMesh EmptyMesh_;
  /// The arrays of the last array Solve and the mesh built from them.
  std::vector<double> Points_;
  std::vector<int> Tets_;
  TetMesh OwnMesh_;
  TetGeometryCache GeometryCache_;
  DistributedNumbering Numbering_;
  std::vector<char> PhysicalFace_; ///< per local boundary triangle of Mesh_
  /// The owned rows of vertices of a physical boundary face of any rank
  /// (ascending): the rows the change rule watches (the serial solver's
  /// TetMesh::GetBoundaryPoints()).
  std::vector<int> BoundaryRows_;
  std::vector<char> Used_;         ///< per local point: a vertex of an owned tet
  std::vector<int> FirstLocal_;    ///< per owned row: its first local point
  /// The owned rows handed to hypre whole (CSR, global sorted columns), and
  /// where each local CSR entry goes: this rank's entries (LocalPositions_
  /// in the local CSR, Targets_[e] in the owned rows), the partition rows'
  /// entries sent to their owners (SendPositionsOff_, SendCounts_ per rank),
  /// and the received ones (RecvCounts_ per rank, Targets_[local + e]).
  std::vector<int> OwnedOffsets_, OwnedColumns_;
  std::vector<int> LocalPositions_, Targets_, SendPositionsOff_, SendCounts_, RecvCounts_;
  /// Every local CSR entry is its own owned entry, in place (one rank):
  /// the owned rows' values are a copy of the local ones.
  bool IdentityGather_ = false;
  /// Per entry sent (SendPositionsOff_ order), its local point.
  std::vector<int> SendPoints_;
  /// The changed-rows update: per owned row, the entries that add into it
  /// (x < LocalPositions_.size(): local entry x, else received entry x -
  /// LocalPositions_.size()), ascending, as GatherOwnedRows adds them
  /// (built at the first update of a mesh; empty before).
  std::vector<int> RowEntryOffsets_, RowEntries_;

  // The matrices' local contributions of the last Solve, their hierarchies
  // and solutions (owned rows).
  std::array<std::vector<double>, NumberOfChannels> Contributions_;
  /// The local CSR values (element matrices and Robin terms) and the
  /// partial rows received (GatherOwnedRows) of Contributions_, kept for the
  /// changed-rows update (HaveLocalValues_), and the divergence's owned
  /// boundary measures (S_i, sum S_f eta_f; 2 per owned row) they were
  /// assembled with (MatrixMeasures_) and of the last boundary terms
  /// (OwnedMeasures_).
  std::array<std::vector<double>, NumberOfChannels> LocalValues_, Received_;
  bool HaveLocalValues_ = false;
  std::vector<double> MatrixMeasures_, OwnedMeasures_;
  /// This Solve may keep OwnedMeasures_ (no eta changed on any rank since
  /// they were summed: FindMatrixChange); OwnedRobin_ holds each owned
  /// row's Robin A and Fdr of them under RobinRule_.
  bool KeepMeasures_ = false;
  std::vector<double> OwnedRobin_;
  Fresnel::BoundaryRule RobinRule_ = Fresnel::BoundaryRule::Fit;
  std::array<std::unique_ptr<DistributedLinearSolver>, NumberOfChannels> Channels_;
  std::array<std::vector<double>, NumberOfChannels> Solution_;
  Timings Timings_;
  double HierarchyCpu_ = 0.0; ///< CPU ms of the hierarchies set up in this Solve

  const Sources* Sources_ = nullptr;
  /// The extended collimated model of the Solve in progress (Solve(problem)):
  /// the lights, shadows and model, agreed over the ranks; the Robin rule of
  /// the model and of the last assembled matrices.
  std::vector<LightSource> Lights_;
  bool Shadows_ = false;
  CollimatedModel Collimated_ = CollimatedModel::Surface;
  Fresnel::BoundaryRule Rule_ = Fresnel::BoundaryRule::Fit;
  Fresnel::BoundaryRule MatrixRule_ = Fresnel::BoundaryRule::Fit;
  DistributedCollimatedSource Beam_;
  /// The beam of the last Solve: its E_c at the local points and power.
  CollimatedSource BeamResult_;
  std::vector<Detector> Detectors_;
  std::vector<DetectorReading> Readings_;
  PowerBalance Balance_;
  std::array<double, NumberOfChannels> SourcePower_{};
};

} // namespace translucency
