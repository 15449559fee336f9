#include "TranslucencyChildProcess.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace translucency
{

namespace
{
/// Moves `size` bytes through `transfer` (read or write) in as many calls as
/// it takes; false at an error or an early end.
template <class Byte, class Transfer>
bool TransferAll(Byte* p, std::size_t size, Transfer transfer)
{
  while (size > 0)
  {
    const ssize_t n = transfer(p, size);
    if (n < 0 && errno == EINTR)
    {
      continue;
    }
    if (n <= 0)
    {
      return false;
    }
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}
} // namespace

bool WriteAll(int fd, const void* data, std::size_t size)
{
  return TransferAll(static_cast<const char*>(data), size,
    [fd](const char* p, std::size_t n) { return ::write(fd, p, n); });
}

bool ReadAll(int fd, void* data, std::size_t size)
{
  return TransferAll(
    static_cast<char*>(data), size, [fd](char* p, std::size_t n) { return ::read(fd, p, n); });
}

ChildOutcome RunInChildProcess(
  const std::function<bool(int fd)>& work, const std::function<bool(int fd)>& read)
{
  ChildOutcome outcome;
  int fds[2];
  if (::pipe(fds) != 0)
  {
    outcome.StartError = std::string("pipe: ") + std::strerror(errno);
    return outcome;
  }
  std::fflush(nullptr); // nothing buffered is written twice
  const pid_t child = ::fork();
  if (child < 0)
  {
    ::close(fds[0]);
    ::close(fds[1]);
    outcome.StartError = std::string("fork: ") + std::strerror(errno);
    return outcome;
  }
  if (child == 0)
  {
    ::close(fds[0]);
    const int devnull = ::open("/dev/null", O_WRONLY);
    if (devnull >= 0)
    {
      ::dup2(devnull, STDERR_FILENO);
      ::dup2(devnull, STDOUT_FILENO);
    }
    bool ok = false;
    try
    {
      ok = work(fds[1]);
    }
    catch (...)
    {
      ok = false;
    }
    ::_exit(ok ? 0 : 3);
  }
  outcome.Started = true;
  ::close(fds[1]);
  outcome.Received = read(fds[0]);
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR)
  {
  }
  if (WIFSIGNALED(status))
  {
    outcome.Signal = WTERMSIG(status);
  }
  else if (WIFEXITED(status))
  {
    outcome.ExitStatus = WEXITSTATUS(status);
  }
  return outcome;
}

} // namespace translucency
