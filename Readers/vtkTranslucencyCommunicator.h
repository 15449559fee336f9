/**
 * @class vtkTranslucencyCommunicator
 * @brief The one communicator of the project's VTK side: ParaView's global
 *        controller, or a communicator of size one.
 *
 * As PETSc makes the communicator part of every object (serial is a
 * communicator of size one), every MPI-aware step of the filters and readers
 * takes its collectives from World(): the global vtkMultiProcessController
 * when it runs more than one process, else a communicator of size one on
 * which every collective is the identity. Inside a LocalScope (rank 0 runs a
 * gathered stage alone, Filters/Parallel/vtkTranslucencyDispatch) World() has
 * size one on that thread, so nothing run there waits for the other ranks:
 * the project's only re-entrancy mechanism.
 *
 * The errors: AgreeOnError() and RunAgreed() make every rank report the same
 * message (the lowest failing rank's, prefixed "rank r: ") before any rank
 * goes on to a collective the failing one would never reach.
 *
 * It lives in the Readers module, the lowest of the project's VTK modules,
 * so that the readers (rank 0 reads, the other ranks must learn of its
 * failure) and the filters share it. Not wrapped (not a vtkObject).
 */
#ifndef vtkTranslucencyCommunicator_h
#define vtkTranslucencyCommunicator_h

#include "TranslucencyReadersModule.h" // for export macro

#include <functional>
#include <string>
#include <vector>

class vtkAlgorithm;
class vtkInformationVector;
class vtkMultiProcessController;

class TRANSLUCENCYREADERS_EXPORT vtkTranslucencyCommunicator
{
public:
  /// The global controller's communicator when it runs more than one
  /// process and this thread is not inside a LocalScope; else size one.
  static vtkTranslucencyCommunicator World();
  /// A communicator of size one.
  static vtkTranslucencyCommunicator Self();

  int GetSize() const { return this->Size; }
  int GetRank() const { return this->Rank; }
  bool IsParallel() const { return this->Size > 1; }
  /// The controller (null for a communicator of size one).
  vtkMultiProcessController* GetController() const { return this->Controller; }

  ///@{
  /// Collective reductions (every rank calls them, an empty piece too).
  long long Sum(long long value) const;
  /// The sum over the ranks below this one (0 on rank 0).
  long long ExclusiveSum(long long value) const;
  int Min(int value) const;
  int Max(int value) const;
  bool Any(bool value) const;
  ///@}

  /**
   * Collective. "" on every rank if every `localError` is empty, else the
   * lowest such rank's message, prefixed "rank r: " (with more than one
   * process), on every rank.
   */
  std::string AgreeOnError(const std::string& localError) const;

  /**
   * Collective. Run `step` (a RequestData body returning 1 or 0) and agree
   * on its outcome: if it failed on some rank, every rank reports one error
   * on `self`, the same text on every rank (when every rank failed, the
   * lowest rank's message as it is: the step agreed on it, or each rank
   * found one on its own; else the lowest failing rank's, "rank r: ..."),
   * empties the outputs of `outputs` and returns 0. The step's errors are held back meanwhile (an
   * ErrorEvent observer on `self`) so each rank reports exactly one.
   * With size one: `step()`, nothing else.
   */
  int RunAgreed(vtkAlgorithm* self, vtkInformationVector* outputs,
    const std::function<int()>& step) const;

  /**
   * A reader's RequestData: RunAgreed() on World() when output port 0 is
   * asked for one of several pieces (a parallel pipeline: every rank
   * executes; rank 0 reads, the others learn of its failure), else `step()`
   * alone (one piece: this rank reads by itself, nothing to agree on).
   */
  static int RunReaderAgreed(vtkAlgorithm* self, vtkInformationVector* outputs,
    const std::function<int()>& step);
  /**
   * A reader's RequestInformation: mark output port 0 as able to produce
   * pieces, so that VTK's executive runs RequestData for every piece (it
   * skips a source's pieces above 0 otherwise) and every rank takes part in
   * RunReaderAgreed(). The reader itself returns an empty piece above 0.
   */
  static void ExecuteEveryPiece(vtkInformationVector* outputs);

  /// While alive, World() on this thread has size one (nestable).
  class TRANSLUCENCYREADERS_EXPORT LocalScope
  {
  public:
    LocalScope();
    ~LocalScope();
    LocalScope(const LocalScope&) = delete;
    LocalScope& operator=(const LocalScope&) = delete;
  };
  /// True inside a LocalScope on this thread.
  static bool IsLocal();

  /**
   * While alive, Replicated() on this thread is `comm` (nestable): the
   * serial path of a replicated run (vtkTranslucencyParallelPlan::Replicated:
   * every rank holds the whole data, inside a LocalScope) learns the ranks it
   * may share its work with. Only a serial path that splits its own work
   * (Solve Diffusion's Monte Carlo) reads it.
   */
  class ReplicatedScope;
  /// The innermost ReplicatedScope's communicator on this thread, else Self().
  static vtkTranslucencyCommunicator Replicated();

private:
  vtkTranslucencyCommunicator() = default;
  /// Collective: the lowest rank's non-empty `local` on every rank ("" if
  /// none), prefixed "rank r: " if `prefix`.
  std::string FirstMessage(const std::string& local, bool prefix) const;
  vtkMultiProcessController* Controller = nullptr;
  int Size = 1;
  int Rank = 0;
};

class TRANSLUCENCYREADERS_EXPORT vtkTranslucencyCommunicator::ReplicatedScope
{
public:
  explicit ReplicatedScope(const vtkTranslucencyCommunicator& comm);
  ~ReplicatedScope();
  ReplicatedScope(const ReplicatedScope&) = delete;
  ReplicatedScope& operator=(const ReplicatedScope&) = delete;

private:
  const vtkTranslucencyCommunicator* Previous;
  vtkTranslucencyCommunicator Current;
};

#endif
