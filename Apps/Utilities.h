/**
 * @file Utilities.h
 * @brief Small helpers every `translucency` command uses: the usage-error
 * type, number lists, timing rows and medians, collecting the filters' error
 * messages, and atomic file writes.
 */
#pragma once

#include "OutputFiles.h"
#include "Timer.h"

#include <vtkCallbackCommand.h>
#include <vtkNew.h>

#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

class vtkDataObject;
class vtkObject;
class vtkXMLWriter;

namespace translucency_app
{
using translucency::Clock;
using translucency::MillisecondsSince;

/// A mistake in the command line (exit code 2).
struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// One row of the timing table.
struct Stage
{
  std::string Name;
  double Milliseconds;
};

/// The median of `values` (the mean of the two middle ones for an even count).
double Median(std::vector<double> values);

/// Print the timing table (one row per stage, then the total) on stdout.
void PrintStages(const std::vector<Stage>& stages);

/// Comma-separated finite numbers; a UsageError "'x' in <what> is not a number" otherwise.
std::vector<double> ParseNumbers(const std::string& text, const std::string& what);

/// `text` with its control bytes (newline, tab, escape, DEL, ...) written as
/// \n, \t, \r or \xNN: every message the command prints is one line, and a
/// file's bytes quoted in it cannot drive the terminal.
std::string EscapeControl(const std::string& text);

/// The lower-case extension of `path`, without the dot ("" if none).
std::string Extension(const std::string& path);

/// --quiet: no progress lines on stderr (warnings and errors still print).
void SetQuiet(bool quiet);
bool IsQuiet();
/// "translucency: <text>" on stderr unless --quiet (flushed: it is progress).
void Progress(const std::string& text);

/// Collects vtkErrorMacro text of the filters it watches; prints warnings.
struct MessageCollector
{
  std::string Errors;
  vtkNew<vtkCallbackCommand> ErrorCallback;
  vtkNew<vtkCallbackCommand> WarningCallback;
  vtkNew<vtkCallbackCommand> IgnoreCallback;
  /// Prints "translucency: <label> NN %" on stderr at most every 10 % and
  /// 2 s (not under --quiet), for the filters that report progress.
  vtkNew<vtkCallbackCommand> ProgressCallback;
  std::map<const vtkObject*, std::string> Labels; ///< progress label per watched object
  MessageCollector();
  /// Errors collected, warnings printed; progress printed as `label` (none if empty).
  void Watch(vtkObject* algorithm, const std::string& label = std::string());
  /// The message of the last error, without VTK's "ERROR: In file, line" header.
  std::string Last() const;
};

/// Every XML file the command line writes: appended raw binary data (not
/// base64), zlib at level 1 (half the write time of VTK's default level 5,
/// files ~3 % larger; raw: 0.62x the time and 0.75x the bytes of base64).
void ConfigureXmlWriter(vtkXMLWriter* writer);

/// Write `data` with `writer` to a unique temporary next to `path`
/// (TemporaryFile, OutputFiles.h), then rename it to `path`: a failure
/// leaves any existing `path` untouched and removes the temporary.
bool WriteAtomically(vtkXMLWriter* writer, vtkDataObject* data, const std::string& path,
  std::string& error);
/// The same for a text file.
bool WriteText(const std::string& path, const std::string& text, std::string& error);
/**
 * Outputs that must change together (render's .vtu, .vtp, .png and .json):
 * each is written to its own TemporaryFile (a unique name created
 * exclusively next to it, OutputFiles.h) first; Commit() renames them
 * all only once every write succeeded, so a failed write leaves every old
 * output as it was. A batch destroyed without Commit() removes its
 * temporaries (and a signal does, through InstallOutputCleanup). A rename
 * failure inside Commit() (rare: the temporaries sit next to their targets)
 * cannot be undone: the error names the outputs already replaced and those
 * left as they were, and the rest of the temporaries are removed.
 */
class OutputBatch
{
public:
  OutputBatch() = default;
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;
  ~OutputBatch();
  /// The temporary to write instead of `path` (a writer of its own, e.g. a
  /// PNG snapshot); throws translucency::Error if it cannot be created.
  std::string Add(const std::string& path);
  /// Write `data` with `writer` (appended, zlib) to the temporary of `path`.
  bool Write(vtkXMLWriter* writer, vtkDataObject* data, const std::string& path, std::string& error);
  /// Write a text file to the temporary of `path`.
  bool WriteText(const std::string& path, const std::string& text, std::string& error);
  /// Rename every temporary to its target; false with `error` on a failure.
  bool Commit(std::string& error);

private:
  std::vector<std::unique_ptr<TemporaryFile>> Targets;
};

/// Throw translucency::Error if a numeric array of `data` (point, cell and
/// field data; every leaf of a composite data set) holds NaN or inf: "<what>:
/// array 'Fluence' holds a non-finite value (nan at point 12 of 345, component
/// 0): not written". Every command calls it on its results before writing them.
void RequireFiniteResult(vtkDataObject* data, const std::string& what);

/// Create the directory holding `path` and its parents (std::filesystem; a
/// failure only warns: the write that follows reports it).
void EnsureParentDirectory(const std::string& path);

} // namespace translucency_app
