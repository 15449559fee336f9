/**
 * @file Process.h
 * @brief Running another program without a shell (posix_spawnp): the plot
 * script and the MPI run of `bench --linear-solvers`.
 */
#pragma once

#include <string>
#include <vector>

namespace translucency_app
{

/// This process's environment ("NAME=value" each) without the variables
/// whose names start with one of `dropPrefixes`, followed by `extra`.
std::vector<std::string> FilteredEnvironment(const std::vector<std::string>& dropPrefixes,
  const std::vector<std::string>& extra = {});

/// Run `argv` (argv[0] looked up on PATH) with `environment`, wait for it and
/// return its exit status (128 + the signal if one ended it). Its standard
/// output and error go to `logPath` (created or truncated), or to ours if
/// `logPath` is empty. Returns -1 with `error` set if it could not start.
int RunProgram(const std::vector<std::string>& argv, const std::vector<std::string>& environment,
  const std::string& logPath, std::string& error);

/// `argv` as one line, each argument quoted as a shell would need it (for messages).
std::string CommandText(const std::vector<std::string>& argv);

} // namespace translucency_app
