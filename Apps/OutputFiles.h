/**
 * @file OutputFiles.h
 * @brief What a `translucency` run may do to the user's files
 * (Documentation/Reliability.md, "Outputs").
 *
 * - Every output is written to a temporary of a unique name,
 *   "<target>.<6 random characters>.part", created with O_CREAT | O_EXCL |
 *   O_NOFOLLOW in the target's directory (so it never follows a planted
 *   symlink, and two runs never share one), then renamed over the target
 *   (rename replaces a symlink at the target, never its target file).
 * - Temporaries are removed on every error, and on SIGINT, SIGTERM and SIGHUP
 *   by a signal handler (InstallOutputCleanup) that unlinks every registered
 *   temporary and lock file (async-signal-safe: unlink, rmdir, raise only).
 * - An OutputPlan names the run's inputs and outputs before any work: an
 *   output equal to an input or to another output (same file by device and
 *   inode, or the same resolved path) is a UsageError; and it takes an
 *   advisory lock (flock) per output prefix, the path without its extension
 *   + ".lock", so a second run into the same prefix refuses at once with a
 *   message naming the lock rather than mixing its files with the first's.
 */
#pragma once

#include <string>
#include <vector>

namespace translucency_app
{

/// Install the SIGINT/SIGTERM/SIGHUP handler that removes the registered
/// temporaries and locks, then dies of the same signal. Called once by main().
void InstallOutputCleanup();

/// Register `path` (a file, or with `directory` an empty-once-cleaned folder)
/// for removal on a signal; returns a slot for UnregisterCleanup (-1 when the
/// table of 256 slots is full: then it is not removed on a signal).
int RegisterCleanup(const std::string& path, bool directory = false);
/// Forget slot `slot` (the file was renamed into place or removed).
void UnregisterCleanup(int slot);

/**
 * A temporary for `target`: "<target>.XXXXXX.part" created exclusively
 * (O_CREAT | O_EXCL | O_NOFOLLOW, mode 0666 & ~umask) in the target's
 * directory and registered for removal on a signal. Its destructor removes
 * the file unless Commit() renamed it over the target.
 */
class TemporaryFile
{
public:
  /// Creates the file; Path() is empty and Error() says why on a failure.
  explicit TemporaryFile(const std::string& target);
  ~TemporaryFile();
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;

  const std::string& Path() const { return this->TempPath; }
  const std::string& Target() const { return this->TargetPath; }
  const std::string& Error() const { return this->Message; }
  /// Rename the temporary over the target; false with `error` on a failure
  /// (the temporary is then removed).
  bool Commit(std::string& error);
  /// Remove the temporary now (idempotent).
  void Discard();

private:
  std::string TargetPath, TempPath, Message;
  int Slot = -1;
};

/**
 * The files of one run: inputs, outputs and the prefixes to lock. Check()
 * refuses (UsageError) an output that is an input or another output, and
 * takes every lock (translucency::Error if another run holds one). The locks
 * are released and their files removed when the plan is destroyed.
 */
class OutputPlan
{
public:
  OutputPlan() = default;
  ~OutputPlan();
  OutputPlan(const OutputPlan&) = delete;
  OutputPlan& operator=(const OutputPlan&) = delete;

  /// An input file (ignored if empty); `option` names it in messages.
  void Input(const std::string& path, const std::string& option);
  /// An output file (ignored if empty); locked by its prefix (the path
  /// without extension) unless `lock` is false.
  void Output(const std::string& path, const std::string& option, bool lock = true);
  /// Check and lock; call before any work. Throws on a conflict.
  void Check();

private:
  struct Entry
  {
    std::string Path, Option;
  };
  std::vector<Entry> Inputs, Outputs;
  std::vector<std::string> LockPrefixes;
  struct Lock
  {
    std::string Path;
    int Fd = -1;
    int Slot = -1;
  };
  std::vector<Lock> Locks;
};

} // namespace translucency_app
