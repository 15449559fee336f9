#include "vtkTranslucencyCommunicator.h"

#include "vtkTranslucencyOutputGuard.h"

#include <vtkAlgorithm.h>
#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkCommunicator.h>
#include <vtkDataObject.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMultiProcessController.h>
#include <vtkNew.h>
#include <vtkStreamingDemandDrivenPipeline.h>

#include <climits>
#include <exception>

namespace
{
/// LocalScopes alive on this thread.
thread_local int LocalDepth = 0;
/// The innermost ReplicatedScope's communicator on this thread (or null).
thread_local const vtkTranslucencyCommunicator* ReplicatedTop = nullptr;

/// The body of a captured error message: the text after "<Class> (0x...): ".
std::string MessageBody(const std::string& text)
{
  std::string body = text;
  const size_t at = body.find("): ");
  if (at != std::string::npos)
  {
    body = body.substr(at + 3);
  }
  while (!body.empty() && (body.back() == '\n' || body.back() == ' '))
  {
    body.pop_back();
  }
  return body;
}

void CaptureFirstError(vtkObject*, unsigned long, void* clientData, void* callData)
{
  auto* message = static_cast<std::string*>(clientData);
  if (callData && message->empty())
  {
    *message = MessageBody(static_cast<const char*>(callData));
  }
}
}

//------------------------------------------------------------------------------
vtkTranslucencyCommunicator vtkTranslucencyCommunicator::World()
{
  vtkTranslucencyCommunicator comm;
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  if (LocalDepth == 0 && controller && controller->GetNumberOfProcesses() > 1)
  {
    comm.Controller = controller;
    comm.Size = controller->GetNumberOfProcesses();
    comm.Rank = controller->GetLocalProcessId();
  }
  return comm;
}

vtkTranslucencyCommunicator vtkTranslucencyCommunicator::Self()
{
  return vtkTranslucencyCommunicator();
}

//------------------------------------------------------------------------------
long long vtkTranslucencyCommunicator::Sum(long long value) const
{
  long long total = value;
  if (this->Controller)
  {
    this->Controller->AllReduce(&value, &total, 1, vtkCommunicator::SUM_OP);
  }
  return total;
}

long long vtkTranslucencyCommunicator::ExclusiveSum(long long value) const
{
  if (!this->Controller)
  {
    return 0;
  }
  std::vector<long long> all(static_cast<size_t>(this->Size));
  this->Controller->AllGather(&value, all.data(), 1);
  long long below = 0;
  for (int r = 0; r < this->Rank; ++r)
  {
    below += all[static_cast<size_t>(r)];
  }
  return below;
}

int vtkTranslucencyCommunicator::Min(int value) const
{
  int result = value;
  if (this->Controller)
  {
    this->Controller->AllReduce(&value, &result, 1, vtkCommunicator::MIN_OP);
  }
  return result;
}

int vtkTranslucencyCommunicator::Max(int value) const
{
  int result = value;
  if (this->Controller)
  {
    this->Controller->AllReduce(&value, &result, 1, vtkCommunicator::MAX_OP);
  }
  return result;
}

bool vtkTranslucencyCommunicator::Any(bool value) const
{
  return this->Max(value ? 1 : 0) != 0;
}

//------------------------------------------------------------------------------
std::string vtkTranslucencyCommunicator::FirstMessage(
  const std::string& local, bool prefix) const
{
  if (!this->Controller)
  {
    return local;
  }
  const int first = this->Min(local.empty() ? INT_MAX : this->Rank);
  if (first == INT_MAX)
  {
    return std::string();
  }
  int length = this->Rank == first ? static_cast<int>(local.size()) : 0;
  this->Controller->Broadcast(&length, 1, first);
  std::vector<char> text(static_cast<size_t>(length) + 1, '\0');
  if (this->Rank == first)
  {
    local.copy(text.data(), local.size());
  }
  this->Controller->Broadcast(text.data(), length + 1, first);
  const std::string body(text.data(), static_cast<size_t>(length));
  return prefix ? "rank " + std::to_string(first) + ": " + body : body;
}

std::string vtkTranslucencyCommunicator::AgreeOnError(const std::string& localError) const
{
  return this->FirstMessage(localError, true);
}

//------------------------------------------------------------------------------
int vtkTranslucencyCommunicator::RunAgreed(
  vtkAlgorithm* self, vtkInformationVector* outputs, const std::function<int()>& step) const
{
  if (!this->Controller)
  {
    return step();
  }
  std::string captured;
  vtkNew<vtkCallbackCommand> capture;
  capture->SetCallback(CaptureFirstError);
  capture->SetClientData(&captured);
  const unsigned long observer = self->AddObserver(vtkCommand::ErrorEvent, capture);
  int status = 0;
  try
  {
    status = step();
  }
  catch (const std::exception& e)
  {
    status = 0;
    if (captured.empty())
    {
      captured = e.what();
    }
  }
  self->RemoveObserver(observer);
  const long long failed = this->Sum(status ? 0 : 1);
  if (failed == 0)
  {
    return status;
  }
  // Every rank failed: the step agreed on its message (or each rank found
  // its own before any collective): the lowest rank's text as it is. Else
  // the lowest failing rank's, "rank r: ...".
  const std::string own =
    status || !captured.empty() ? captured : std::string("failed (no message)");
  const std::string message = failed == this->Size
    ? this->FirstMessage(captured, false)
    : this->AgreeOnError(status ? std::string() : own);
  if (!message.empty())
  {
    vtkErrorWithObjectMacro(self, << message);
  }
  for (int port = 0; outputs && port < outputs->GetNumberOfInformationObjects(); ++port)
  {
    vtkTranslucencyOutputGuard::MakeEmpty(vtkDataObject::GetData(outputs, port));
  }
  return 0;
}

//------------------------------------------------------------------------------
int vtkTranslucencyCommunicator::RunReaderAgreed(
  vtkAlgorithm* self, vtkInformationVector* outputs, const std::function<int()>& step)
{
  vtkInformation* info = outputs ? outputs->GetInformationObject(0) : nullptr;
  const bool pieces = info &&
    info->Has(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES()) &&
    info->Get(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES()) > 1;
  return pieces ? World().RunAgreed(self, outputs, step) : step();
}

void vtkTranslucencyCommunicator::ExecuteEveryPiece(vtkInformationVector* outputs)
{
  if (vtkInformation* info = outputs ? outputs->GetInformationObject(0) : nullptr)
  {
    info->Set(vtkAlgorithm::CAN_HANDLE_PIECE_REQUEST(), 1);
  }
}

//------------------------------------------------------------------------------
vtkTranslucencyCommunicator::LocalScope::LocalScope()
{
  ++LocalDepth;
}

vtkTranslucencyCommunicator::LocalScope::~LocalScope()
{
  --LocalDepth;
}

bool vtkTranslucencyCommunicator::IsLocal()
{
  return LocalDepth > 0;
}

//------------------------------------------------------------------------------
vtkTranslucencyCommunicator::ReplicatedScope::ReplicatedScope(
  const vtkTranslucencyCommunicator& comm)
  : Previous(ReplicatedTop)
  , Current(comm)
{
  ReplicatedTop = &this->Current;
}

vtkTranslucencyCommunicator::ReplicatedScope::~ReplicatedScope()
{
  ReplicatedTop = this->Previous;
}

vtkTranslucencyCommunicator vtkTranslucencyCommunicator::Replicated()
{
  return ReplicatedTop ? *ReplicatedTop : Self();
}
