#include "Utilities.h"

#include "Strings.h"

#include <vtkAlgorithm.h>
#include <vtkCommand.h>
#include <vtkExecutive.h>
#include <vtkXMLWriter.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <regex>
#include <sstream>
#include <system_error>

namespace translucency_app
{

double Median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
void PrintStages(const std::vector<Stage>& stages)
{
  std::cout << "\n  stage            time (ms)\n  ---------------- ---------\n";
  double total = 0.0;
  for (const Stage& s : stages)
  {
    std::cout << "  " << std::left << std::setw(16) << s.Name << " " << std::right << std::setw(9)
              << std::fixed << std::setprecision(1) << s.Milliseconds << "\n";
    total += s.Milliseconds;
  }
  std::cout << "  " << std::left << std::setw(16) << "total" << " " << std::right << std::setw(9)
            << total << std::defaultfloat << "\n";
}

std::vector<double> ParseNumbers(const std::string& text, const std::string& what)
{
  std::vector<double> values;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ','))
  {
    // strtod, not std::stod: stod throws out_of_range for denormals (1e-320),
    // which are valid (if tiny) numbers; an overflow gives +-HUGE_VAL.
    const char* begin = item.c_str();
    char* end = nullptr;
    const double value = item.empty() || std::isspace(static_cast<unsigned char>(item[0]))
      ? std::nan("")
      : std::strtod(begin, &end);
    if (item.empty() || end != begin + item.size() || std::isnan(value))
    {
      throw UsageError("'" + item + "' in " + what + " is not a number");
    }
    if (!std::isfinite(value))
    {
      throw UsageError("'" + item + "' in " + what + " is not a finite number (the largest is " +
        "about 1.8e308)");
    }
    values.push_back(value);
  }
  return values;
}

std::string Extension(const std::string& path)
{
  const size_t dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot + 1);
  ext = translucency::ToLower(ext);
  return ext;
}

namespace
{
/// The message of the last vtkErrorMacro / vtkWarningMacro text in `text`:
/// VTK sends "ERROR: In <file>, line <n>\n<class> (<address>): <message>\n\n"
/// ("Warning: In ..." for warnings). The whole <message> is kept, whatever it
/// holds (it may itself contain "): ").
std::string StripVtkHeader(std::string text)
{
  size_t header = text.rfind("ERROR: In ");
  const size_t warning = text.rfind("Warning: In ");
  if (warning != std::string::npos && (header == std::string::npos || warning > header))
  {
    header = warning;
  }
  if (header != std::string::npos)
  {
    const size_t lineEnd = text.find('\n', header);
    text = lineEnd == std::string::npos ? std::string() : text.substr(lineEnd + 1);
  }
  static const std::regex prefix(R"(^[A-Za-z_][A-Za-z0-9_:]* \([^()\n]*\): )");
  std::smatch match;
  if (std::regex_search(text, match, prefix))
  {
    text = match.suffix().str();
  }
  while (!text.empty() && (text.back() == '\n' || text.back() == ' '))
  {
    text.pop_back();
  }
  return text;
}
} // namespace

namespace
{
bool QuietFlag = false;

/// The state of one watched algorithm's progress lines.
struct ProgressState
{
  std::string Label;
  double LastFraction = -1.0;
  translucency::Clock::time_point LastTime;
};
}

void SetQuiet(bool quiet)
{
  QuietFlag = quiet;
}

bool IsQuiet()
{
  return QuietFlag;
}

void Progress(const std::string& text)
{
  if (!QuietFlag)
    std::cerr << "translucency: " << text << std::endl;
}

MessageCollector::MessageCollector()
{
  this->ProgressCallback->SetClientData(this);
  this->ProgressCallback->SetCallback([](vtkObject* caller, unsigned long, void* self, void* data) {
    if (QuietFlag || !data)
      return;
    static std::map<const vtkObject*, ProgressState> states;
    const double fraction = *static_cast<double*>(data);
    ProgressState& state = states[caller];
    state.Label = static_cast<MessageCollector*>(self)->Labels[caller];
    const auto now = translucency::Clock::now();
    if (fraction < state.LastFraction)
      state.LastFraction = -1.0; // a new run of the same filter
    if (fraction < 0.05 || fraction >= 1.0 || fraction - state.LastFraction < 0.1 ||
      (state.LastFraction >= 0 && translucency::MillisecondsSince(state.LastTime) < 2000))
      return;
    state.LastFraction = fraction;
    state.LastTime = now;
    std::cerr << "translucency: " << state.Label << " " << static_cast<int>(100 * fraction)
              << " %" << std::endl;
  });
  this->ErrorCallback->SetClientData(this);
  this->ErrorCallback->SetCallback([](vtkObject*, unsigned long, void* self, void* data) {
    auto* collector = static_cast<MessageCollector*>(self);
    collector->Errors += static_cast<const char*>(data);
  });
  this->WarningCallback->SetCallback([](vtkObject*, unsigned long, void*, void* data) {
    std::cerr << "translucency: warning: " << StripVtkHeader(static_cast<const char*>(data))
              << "\n";
  });
}

void MessageCollector::Watch(vtkObject* object, const std::string& label)
{
  if (!label.empty())
  {
    object->AddObserver(vtkCommand::ProgressEvent, this->ProgressCallback);
    this->Labels[object] = label;
  }
  object->AddObserver(vtkCommand::ErrorEvent, this->ErrorCallback);
  object->AddObserver(vtkCommand::WarningEvent, this->WarningCallback);
  // The executive's "Algorithm ... returned failure for request" follows
  // every filter error, which is already reported: silence it (it would
  // otherwise go to stderr through vtkLogger, whatever the output window).
  if (auto* algorithm = vtkAlgorithm::SafeDownCast(object))
  {
    algorithm->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, this->IgnoreCallback);
  }
}

std::string MessageCollector::Last() const
{
  return StripVtkHeader(this->Errors);
}

bool WriteAtomically(vtkXMLWriter* writer, vtkDataObject* data, const std::string& path,
  std::string& error)
{
  const std::string tmp = path + ".tmp";
  writer->SetInputData(data);
  writer->SetFileName(tmp.c_str());
  writer->SetDataModeToAppended();
  writer->SetCompressorTypeToZLib();
  if (writer->Write() == 0)
  {
    std::remove(tmp.c_str());
    error = "cannot write '" + path + "'";
    return false;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
  {
    std::remove(tmp.c_str());
    error = "cannot rename the temporary file to '" + path + "'";
    return false;
  }
  return true;
}

bool WriteText(const std::string& path, const std::string& text, std::string& error)
{
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    out << text;
    if (!out)
    {
      error = "cannot write '" + path + "'";
      return false;
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
  {
    std::remove(tmp.c_str());
    error = "cannot rename the temporary file to '" + path + "'";
    return false;
  }
  return true;
}

OutputBatch::~OutputBatch()
{
  for (const std::string& path : this->Targets)
  {
    // Only a file (a directory of that name is not ours).
    std::error_code ec;
    if (std::filesystem::is_regular_file(path + ".part", ec))
    {
      std::filesystem::remove(path + ".part", ec);
    }
  }
}

std::string OutputBatch::Add(const std::string& path)
{
  this->Targets.push_back(path);
  return path + ".part";
}

bool OutputBatch::Write(
  vtkXMLWriter* writer, vtkDataObject* data, const std::string& path, std::string& error)
{
  const std::string tmp = this->Add(path);
  writer->SetInputData(data);
  writer->SetFileName(tmp.c_str());
  writer->SetDataModeToAppended();
  writer->SetCompressorTypeToZLib();
  if (writer->Write() == 0 || writer->GetErrorCode() != 0)
  {
    error = "cannot write '" + path + "' (no output changed)";
    return false;
  }
  return true;
}

bool OutputBatch::WriteText(const std::string& path, const std::string& text, std::string& error)
{
  const std::string tmp = this->Add(path);
  std::ofstream out(tmp);
  out << text;
  out.close();
  if (!out)
  {
    error = "cannot write '" + path + "' (no output changed)";
    return false;
  }
  return true;
}

bool OutputBatch::Commit(std::string& error)
{
  for (size_t k = 0; k < this->Targets.size(); ++k)
  {
    const std::string& path = this->Targets[k];
    if (std::rename((path + ".part").c_str(), path.c_str()) != 0)
    {
      std::string done, kept;
      for (size_t i = 0; i < this->Targets.size(); ++i)
      {
        std::string& list = i < k ? done : kept;
        list += (list.empty() ? "'" : ", '") + this->Targets[i] + "'";
      }
      error = "cannot rename '" + path + ".part' to '" + path + "': " +
        (done.empty() ? std::string("no output changed") : "replaced " + done + "; left as they were " + kept);
      this->Targets.erase(this->Targets.begin(), this->Targets.begin() + static_cast<long>(k));
      return false; // the destructor removes the remaining temporaries
    }
  }
  this->Targets.clear();
  return true;
}

void EnsureParentDirectory(const std::string& path)
{
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (dir.empty())
  {
    return;
  }
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
  {
    std::cerr << "translucency: warning: cannot create directory '" << dir.string()
              << "': " << ec.message() << "\n";
  }
}

} // namespace translucency_app
