/**
 * @file Utilities.h
 * @brief Small helpers every `translucency` command uses: the usage-error
 * type, number lists, timing rows and medians, collecting the filters' error
 * messages, and atomic file writes.
 */
#pragma once

#include "Timer.h"

#include <vtkCallbackCommand.h>
#include <vtkNew.h>

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

/// The lower-case extension of `path`, without the dot ("" if none).
std::string Extension(const std::string& path);

/// Collects vtkErrorMacro text of the filters it watches; prints warnings.
struct MessageCollector
{
  std::string Errors;
  vtkNew<vtkCallbackCommand> ErrorCallback;
  vtkNew<vtkCallbackCommand> WarningCallback;
  vtkNew<vtkCallbackCommand> IgnoreCallback;
  MessageCollector();
  void Watch(vtkObject* algorithm);
  /// The message of the last error, without VTK's "ERROR: In file, line" header.
  std::string Last() const;
};

/// Write `data` with `writer` to a temporary file, then rename it to `path`:
/// a failure leaves any existing `path` untouched.
bool WriteAtomically(vtkXMLWriter* writer, vtkDataObject* data, const std::string& path,
  std::string& error);
/// The same for a text file.
bool WriteText(const std::string& path, const std::string& text, std::string& error);
/// Create the directory holding `path` and its parents (std::filesystem; a
/// failure only warns: the write that follows reports it).
void EnsureParentDirectory(const std::string& path);

} // namespace translucency_app
