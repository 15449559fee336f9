#include "Utilities.h"

#include "Error.h"
#include "OutputFiles.h"
#include "Strings.h"

#include <vtkAlgorithm.h>
#include <vtkCommand.h>
#include <vtkExecutive.h>
#include <vtkCellData.h>
#include <vtkCompositeDataIterator.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataArray.h>
#include <vtkDataSet.h>
#include <vtkFieldData.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
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
#include <memory>
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

std::string EscapeControl(const std::string& text)
{
  static const char* hex = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (const char ch : text)
  {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (c >= 0x20 && c != 0x7f)
      out += ch;
    else if (c == '\n')
      out += "\\n";
    else if (c == '\t')
      out += "\\t";
    else if (c == '\r')
      out += "\\r";
    else
    {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
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
    std::cerr << "translucency: warning: "
              << EscapeControl(StripVtkHeader(static_cast<const char*>(data))) << "\n";
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

/// Appended raw binary data (not base64: VTK's default encodes it), zlib at
/// level 1: half the write time of VTK's default level 5 for files about 3 %
/// larger (the demo's 213k-tet .vtu: 0.94 s against 1.86 s, 6.1 MB against
/// 5.9 MB, measured on the loaded machine), and raw instead of base64 another
/// 0.62x of the time for 0.75x of the bytes (the demo's 192k-tet .vtu, idle:
/// 130 ms and 4.0 MB against 209 ms and 5.3 MB; Documentation/Performance.md,
/// "End to end at 200k tets"). VTK and ParaView read both forms.
void ConfigureXmlWriter(vtkXMLWriter* writer)
{
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writer->SetCompressorTypeToZLib();
  writer->SetCompressionLevel(1);
}

bool WriteAtomically(vtkXMLWriter* writer, vtkDataObject* data, const std::string& path,
  std::string& error)
{
  TemporaryFile tmp(path);
  if (tmp.Path().empty())
  {
    error = tmp.Error();
    return false;
  }
  writer->SetInputData(data);
  writer->SetFileName(tmp.Path().c_str());
  ConfigureXmlWriter(writer);
  if (writer->Write() == 0 || writer->GetErrorCode() != 0)
  {
    error = "cannot write '" + path + "'";
    return false; // the temporary's destructor removes it
  }
  return tmp.Commit(error);
}

namespace
{
bool WriteTextTo(const std::string& tmp, const std::string& path, const std::string& text,
  std::string& error)
{
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out)
  {
    error = "cannot write '" + path + "' (no output changed)";
    return false;
  }
  return true;
}
} // namespace

bool WriteText(const std::string& path, const std::string& text, std::string& error)
{
  TemporaryFile tmp(path);
  if (tmp.Path().empty())
  {
    error = tmp.Error();
    return false;
  }
  return WriteTextTo(tmp.Path(), path, text, error) && tmp.Commit(error);
}

OutputBatch::~OutputBatch() = default; // each TemporaryFile removes its file

std::string OutputBatch::Add(const std::string& path)
{
  auto tmp = std::make_unique<TemporaryFile>(path);
  if (tmp->Path().empty())
  {
    throw translucency::Error(tmp->Error());
  }
  this->Targets.push_back(std::move(tmp));
  return this->Targets.back()->Path();
}

bool OutputBatch::Write(
  vtkXMLWriter* writer, vtkDataObject* data, const std::string& path, std::string& error)
{
  const std::string tmp = this->Add(path);
  writer->SetInputData(data);
  writer->SetFileName(tmp.c_str());
  ConfigureXmlWriter(writer);
  if (writer->Write() == 0 || writer->GetErrorCode() != 0)
  {
    error = "cannot write '" + path + "' (no output changed)";
    return false;
  }
  return true;
}

bool OutputBatch::WriteText(const std::string& path, const std::string& text, std::string& error)
{
  return WriteTextTo(this->Add(path), path, text, error);
}

bool OutputBatch::Commit(std::string& error)
{
  for (size_t k = 0; k < this->Targets.size(); ++k)
  {
    const std::string path = this->Targets[k]->Target();
    std::string why;
    if (!this->Targets[k]->Commit(why))
    {
      std::string done, kept;
      for (size_t i = 0; i < this->Targets.size(); ++i)
      {
        std::string& list = i < k ? done : kept;
        list += (list.empty() ? "'" : ", '") + this->Targets[i]->Target() + "'";
      }
      error = why + ": " +
        (done.empty() ? std::string("no output changed") : "replaced " + done + "; left as they were " + kept);
      this->Targets.clear(); // the rest of the temporaries are removed
      return false;
    }
  }
  this->Targets.clear();
  return true;
}

namespace
{
void RequireFiniteAttributes(vtkFieldData* fields, const char* element, const std::string& what)
{
  if (!fields)
  {
    return;
  }
  for (int a = 0; a < fields->GetNumberOfArrays(); ++a)
  {
    vtkDataArray* array = fields->GetArray(a);
    if (!array || array->GetDataTypeSize() == 0 || !(array->IsA("vtkFloatArray") ||
          array->IsA("vtkDoubleArray")))
    {
      continue; // integers cannot be NaN
    }
    const int components = array->GetNumberOfComponents();
    for (vtkIdType i = 0; i < array->GetNumberOfTuples(); ++i)
    {
      for (int c = 0; c < components; ++c)
      {
        const double value = array->GetComponent(i, c);
        if (!std::isfinite(value))
        {
          std::ostringstream os;
          os << what << ": array '" << (array->GetName() ? array->GetName() : "") << "' holds "
             << value << " at " << element << " " << i << " of " << array->GetNumberOfTuples()
             << " (component " << c << "): a non-finite result is not written";
          throw translucency::Error(os.str());
        }
      }
    }
  }
}
} // namespace

void RequireFiniteResult(vtkDataObject* data, const std::string& what)
{
  if (auto* composite = vtkCompositeDataSet::SafeDownCast(data))
  {
    vtkSmartPointer<vtkCompositeDataIterator> iter =
      vtk::TakeSmartPointer(composite->NewIterator());
    for (iter->InitTraversal(); !iter->IsDoneWithTraversal(); iter->GoToNextItem())
    {
      RequireFiniteResult(iter->GetCurrentDataObject(), what);
    }
    return;
  }
  if (auto* set = vtkDataSet::SafeDownCast(data))
  {
    RequireFiniteAttributes(set->GetPointData(), "point", what);
    RequireFiniteAttributes(set->GetCellData(), "cell", what);
  }
  if (data)
  {
    RequireFiniteAttributes(data->GetFieldData(), "row", what);
  }
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
