#include "Process.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstring>

extern char** environ;

namespace translucency_app
{

std::vector<std::string> FilteredEnvironment(const std::vector<std::string>& dropPrefixes,
  const std::vector<std::string>& extra)
{
  std::vector<std::string> out;
  for (char** e = environ; e && *e; ++e)
  {
    const std::string entry = *e;
    bool drop = false;
    for (const std::string& prefix : dropPrefixes)
      drop = drop || entry.rfind(prefix, 0) == 0;
    if (!drop)
      out.push_back(entry);
  }
  out.insert(out.end(), extra.begin(), extra.end());
  return out;
}

int RunProgram(const std::vector<std::string>& argv, const std::vector<std::string>& environment,
  const std::string& logPath, std::string& error)
{
  if (argv.empty())
  {
    error = "no program to run";
    return -1;
  }
  std::vector<char*> args, env;
  for (const std::string& a : argv)
    args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  for (const std::string& e : environment)
    env.push_back(const_cast<char*>(e.c_str()));
  env.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!logPath.empty())
  {
    posix_spawn_file_actions_addopen(
      &actions, STDOUT_FILENO, logPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  }
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), env.data());
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0)
  {
    error = "cannot run '" + argv[0] + "': " + std::strerror(spawned);
    return -1;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
  {
    if (errno != EINTR)
    {
      error = "cannot wait for '" + argv[0] + "': " + std::strerror(errno);
      return -1;
    }
  }
  if (WIFEXITED(status))
    return WEXITSTATUS(status);
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
}

std::string CommandText(const std::vector<std::string>& argv)
{
  std::string text;
  for (const std::string& a : argv)
  {
    std::string quoted = "'";
    for (char c : a)
      quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    text += (text.empty() ? "" : " ") + quoted + "'";
  }
  return text;
}

} // namespace translucency_app
