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

MessageCollector::MessageCollector()
{
  this->ErrorCallback->SetClientData(this);
  this->ErrorCallback->SetCallback([](vtkObject*, unsigned long, void* self, void* data) {
    auto* collector = static_cast<MessageCollector*>(self);
    collector->Errors += static_cast<const char*>(data);
  });
  this->WarningCallback->SetCallback([](vtkObject*, unsigned long, void*, void* data) {
    std::cerr << "translucency: warning: " << static_cast<const char*>(data) << "\n";
  });
}

void MessageCollector::Watch(vtkObject* object)
{
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
  std::string text = this->Errors;
  // The last message starts after its "ERROR: In file, line N\nvtkX (0x..): "
  // header; the message itself may contain "): ".
  const size_t header = text.rfind("ERROR: In ");
  if (header != std::string::npos)
  {
    text = text.substr(header);
  }
  const size_t pos = header != std::string::npos ? text.find("): ") : text.rfind("): ");
  if (pos != std::string::npos)
  {
    text = text.substr(pos + 3);
  }
  while (!text.empty() && (text.back() == '\n' || text.back() == ' '))
  {
    text.pop_back();
  }
  return text;
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
