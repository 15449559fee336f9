/**
 * @file TranslucencyChildProcess.h
 * @brief Runs a piece of work in a forked child process and reads its result
 * back through a pipe: the meshers' isolation (TetGen and gmsh's HXT in
 * vtkTetrahedralizeSurface), so that a crash inside them is a clean error
 * and their runtimes never end inside the caller's process.
 *
 * Private to the Filters module. POSIX only (fork, pipe, waitpid).
 */
#pragma once

#include <cstddef>
#include <functional>
#include <string>

namespace translucency
{

/// Writes all of `size` bytes to `fd`; false on an error or a closed pipe.
bool WriteAll(int fd, const void* data, std::size_t size);

/// Reads all of `size` bytes from `fd`; false at an early end.
bool ReadAll(int fd, void* data, std::size_t size);

/// How a child run ended.
struct ChildOutcome
{
  bool Started = false;  ///< false: pipe or fork failed (StartError says why)
  std::string StartError;
  bool Received = false; ///< what `read` returned
  int Signal = 0;        ///< the signal that ended the child, 0 if none
  int ExitStatus = -1;   ///< the child's exit status when it exited
};

/**
 * Forks. The child runs `work(fd)` with its standard output and error sent to
 * /dev/null (the raw lines of a failed assertion), writes its result to fd and
 * ends with _exit(0) when work returned true, _exit(3) otherwise (no atexit
 * handler, no destructor of the caller's objects runs in it). The caller runs
 * `read(fd)` on the other end of the pipe, then waits for the child.
 * Buffered output is flushed before the fork (nothing is written twice).
 */
ChildOutcome RunInChildProcess(
  const std::function<bool(int fd)>& work, const std::function<bool(int fd)>& read);

} // namespace translucency
