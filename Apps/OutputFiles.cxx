#include "OutputFiles.h"
#include "Utilities.h"

#include "Error.h"
#include "Strings.h"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <random>
#include <system_error>

namespace translucency_app
{

namespace
{
// The cleanup table the signal handler reads: fixed storage, each slot's
// path written before its flag is set, so the handler sees only whole paths.
constexpr int CleanupSlots = 256;
constexpr size_t CleanupPathBytes = 4096;
char CleanupPaths[CleanupSlots][CleanupPathBytes];
volatile sig_atomic_t CleanupUsed[CleanupSlots];
volatile sig_atomic_t CleanupIsDirectory[CleanupSlots];
std::mutex CleanupMutex;
pthread_t MainThread; ///< the thread that installed the handler (main's)

extern "C" void RemoveRegisteredOnSignal(int sig)
{
  // A library's worker thread (OpenBLAS starts its pool when loaded) may be
  // the one a signal is delivered to: hand it to the main thread, which
  // holds it back while it creates and registers a lock (HoldCleanupSignals).
  if (!pthread_equal(pthread_self(), MainThread))
  {
    pthread_kill(MainThread, sig);
    return;
  }
  // Files first, then the folders that held them (compare's staging folder).
  for (int pass = 0; pass < 2; ++pass)
    for (int k = 0; k < CleanupSlots; ++k)
      if (CleanupUsed[k] && CleanupIsDirectory[k] == pass)
      {
        if (pass == 0)
          unlink(CleanupPaths[k]);
        else
          rmdir(CleanupPaths[k]);
      }
  signal(sig, SIG_DFL);
  raise(sig); // delivered when the handler returns: the exit status says which signal
}

/// SIGINT, SIGTERM and SIGHUP held back on this thread while it lives: a
/// lock file is created and registered for removal as one step, so a signal
/// between the two (the handler would not know the file yet) cannot leave
/// it behind; a held-back signal is delivered when the scope ends.
class HoldCleanupSignals
{
public:
  HoldCleanupSignals()
  {
    sigset_t held;
    sigemptyset(&held);
    for (int sig : { SIGINT, SIGTERM, SIGHUP })
      sigaddset(&held, sig);
    pthread_sigmask(SIG_BLOCK, &held, &this->Previous);
  }
  ~HoldCleanupSignals() { pthread_sigmask(SIG_SETMASK, &this->Previous, nullptr); }
  HoldCleanupSignals(const HoldCleanupSignals&) = delete;
  HoldCleanupSignals& operator=(const HoldCleanupSignals&) = delete;

private:
  sigset_t Previous;
};

std::string Quote(const std::string& path)
{
  return "'" + EscapeControl(path) + "'";
}

/// `path` with its folder resolved (symlinks, ".."), its last component kept:
/// what a rename onto `path` replaces.
std::string ResolvedFolder(const std::string& path)
{
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path p = fs::absolute(path, ec);
  fs::path parent = fs::weakly_canonical(p.parent_path(), ec);
  if (ec)
    parent = p.parent_path().lexically_normal();
  return (parent / p.filename()).string();
}

/// `path` with every symlink resolved: what a reader opens.
std::string Resolved(const std::string& path)
{
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  if (ec)
    return ResolvedFolder(path);
  return p.string();
}

std::string RandomName()
{
  static const char* letters = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
  static std::mt19937_64 random(std::random_device{}() ^
    static_cast<uint64_t>(getpid()) ^
    static_cast<uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count()));
  std::string s(6, 'x');
  for (char& c : s)
    c = letters[random() % 62];
  return s;
}
} // namespace

void InstallOutputCleanup()
{
  MainThread = pthread_self();
  struct sigaction action;
  std::memset(&action, 0, sizeof(action));
  action.sa_handler = RemoveRegisteredOnSignal;
  sigemptyset(&action.sa_mask);
  for (int sig : { SIGINT, SIGTERM, SIGHUP })
  {
    // Keep "ignored" (nohup) as it is.
    struct sigaction old;
    if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN)
      continue;
    sigaction(sig, &action, nullptr);
  }
}

int RegisterCleanup(const std::string& path, bool directory)
{
  if (path.size() + 1 > CleanupPathBytes)
    return -1;
  std::lock_guard<std::mutex> lock(CleanupMutex);
  for (int k = 0; k < CleanupSlots; ++k)
    if (!CleanupUsed[k])
    {
      std::memcpy(CleanupPaths[k], path.c_str(), path.size() + 1);
      CleanupIsDirectory[k] = directory ? 1 : 0;
      CleanupUsed[k] = 1;
      return k;
    }
  return -1;
}

void UnregisterCleanup(int slot)
{
  if (slot < 0 || slot >= CleanupSlots)
    return;
  std::lock_guard<std::mutex> lock(CleanupMutex);
  CleanupUsed[slot] = 0;
}

TemporaryFile::TemporaryFile(const std::string& target)
  : TargetPath(target)
{
  for (int attempt = 0; attempt < 100; ++attempt)
  {
    const std::string path = target + "." + RandomName() + ".part";
    // Registered before it exists: a signal between open and registration
    // would otherwise leave it behind (unlinking a missing file is harmless).
    const int slot = RegisterCleanup(path);
    const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd >= 0)
    {
      close(fd);
      this->TempPath = path;
      this->Slot = slot;
      return;
    }
    const int error = errno;
    UnregisterCleanup(slot);
    if (error != EEXIST)
    {
      this->Message = "cannot create a temporary file next to " + Quote(target) + ": " +
        std::strerror(error) + " (no output changed)";
      return;
    }
  }
  this->Message = "cannot create a temporary file next to " + Quote(target) +
    ": 100 names taken (no output changed)";
}

TemporaryFile::~TemporaryFile()
{
  this->Discard();
}

void TemporaryFile::Discard()
{
  if (!this->TempPath.empty())
  {
    unlink(this->TempPath.c_str());
    this->TempPath.clear();
  }
  UnregisterCleanup(this->Slot);
  this->Slot = -1;
}

bool TemporaryFile::Commit(std::string& error)
{
  if (this->TempPath.empty())
  {
    error = this->Message.empty() ? "no temporary file for " + Quote(this->TargetPath) : this->Message;
    return false;
  }
  if (std::rename(this->TempPath.c_str(), this->TargetPath.c_str()) != 0)
  {
    error = "cannot rename " + Quote(this->TempPath) + " to " + Quote(this->TargetPath) + ": " +
      std::strerror(errno);
    this->Discard();
    return false;
  }
  this->TempPath.clear();
  UnregisterCleanup(this->Slot);
  this->Slot = -1;
  return true;
}

OutputPlan::~OutputPlan()
{
  for (Lock& lock : this->Locks)
  {
    // Unlinked while still held: a run waiting on the old file sees that
    // its file is no longer the lock (the inode check in Check()).
    unlink(lock.Path.c_str());
    close(lock.Fd);
    UnregisterCleanup(lock.Slot);
  }
}

void OutputPlan::Input(const std::string& path, const std::string& option)
{
  if (!path.empty())
    this->Inputs.push_back({ path, option });
}

void OutputPlan::Output(const std::string& path, const std::string& option, bool lock)
{
  if (path.empty())
    return;
  this->Outputs.push_back({ path, option });
  if (lock)
  {
    const std::filesystem::path p(path);
    this->LockPrefixes.push_back((p.parent_path() / p.stem()).string());
  }
}

void OutputPlan::Check()
{
  struct Identity
  {
    std::string Name;
    bool Exists = false;
    dev_t Device = 0;
    ino_t Inode = 0;
  };
  // An input is what a reader opens (symlinks followed); an output is the
  // directory entry a rename replaces (its last component kept).
  const auto identify = [](const std::string& path, bool output) {
    Identity id;
    id.Name = output ? ResolvedFolder(path) : Resolved(path);
    struct stat st;
    if ((output ? lstat(path.c_str(), &st) : stat(path.c_str(), &st)) == 0)
    {
      id.Exists = true;
      id.Device = st.st_dev;
      id.Inode = st.st_ino;
    }
    return id;
  };
  const auto same = [](const Identity& a, const Identity& b) {
    return a.Name == b.Name || (a.Exists && b.Exists && a.Device == b.Device && a.Inode == b.Inode);
  };
  std::vector<Identity> inputs, outputs;
  for (const Entry& e : this->Inputs)
    inputs.push_back(identify(e.Path, false));
  for (const Entry& e : this->Outputs)
    outputs.push_back(identify(e.Path, true));
  for (size_t o = 0; o < outputs.size(); ++o)
  {
    std::error_code ec;
    if (std::filesystem::is_directory(std::filesystem::symlink_status(this->Outputs[o].Path, ec)))
      throw UsageError(this->Outputs[o].Option + " " + Quote(this->Outputs[o].Path) +
        " is a folder: an output file cannot replace it");
    for (size_t i = 0; i < inputs.size(); ++i)
      if (same(outputs[o], inputs[i]) || outputs[o].Name == inputs[i].Name)
        throw UsageError(this->Outputs[o].Option + " " + Quote(this->Outputs[o].Path) +
          " is the input " + this->Inputs[i].Option + " " + Quote(this->Inputs[i].Path) +
          ": refused (the run would overwrite its own input)");
    for (size_t p = 0; p < o; ++p)
      if (same(outputs[o], outputs[p]))
        throw UsageError(this->Outputs[o].Option + " " + Quote(this->Outputs[o].Path) +
          " is also the output of " + this->Outputs[p].Option + " " +
          Quote(this->Outputs[p].Path) + ": refused (one would overwrite the other)");
  }
  // The locks, one per prefix.
  std::vector<std::string> taken;
  for (const std::string& prefix : this->LockPrefixes)
  {
    const std::string key = ResolvedFolder(prefix);
    bool seen = false;
    for (const std::string& t : taken)
      seen = seen || t == key;
    if (seen)
      continue;
    taken.push_back(key);
    const std::string path = prefix + ".lock";
    EnsureParentDirectory(path);
    while (true)
    {
      // The lock's creation and its registration for removal are one step
      // for the signal handler (which runs on the main thread: the locks
      // are taken there, before any work).
      HoldCleanupSignals hold;
      const int fd = open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0666);
      if (fd < 0)
      {
        const int error = errno;
        throw translucency::Error("cannot create the lock file " + Quote(path) + ": " +
          std::strerror(error) + (error == ELOOP ? " (it is a symlink: remove it)" : ""));
      }
      if (flock(fd, LOCK_EX | LOCK_NB) != 0)
      {
        const int error = errno;
        close(fd);
        if (error == EWOULDBLOCK)
          throw translucency::Error("another translucency run is writing the outputs " +
            Quote(prefix + ".*") + " (it holds the lock " + Quote(path) +
            "): wait until it has finished, or write to another name");
        throw translucency::Error(
          "cannot lock " + Quote(path) + ": " + std::strerror(error));
      }
      // The file may have been removed by the run that held it just before
      // we locked it: then lock the new one.
      struct stat held, now;
      if (fstat(fd, &held) == 0 && stat(path.c_str(), &now) == 0 && held.st_dev == now.st_dev &&
        held.st_ino == now.st_ino)
      {
        // Registered only once held: a run refused here must never remove
        // the lock of the run that holds it.
        this->Locks.push_back({ path, fd, RegisterCleanup(path) });
        break;
      }
      close(fd);
    }
  }
}

} // namespace translucency_app
