#include "CompareMeasured.h"

#include "Error.h"
#include "InputFiles.h"
#include "Strings.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace translucency_app
{
namespace
{

std::string Trim(const std::string& text)
{
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos)
  {
    return "";
  }
  const auto last = text.find_last_not_of(" \t\r\n");
  return text.substr(first, last - first + 1);
}

std::vector<std::string> SplitCells(const std::string& line)
{
  std::vector<std::string> cells;
  std::stringstream stream(line);
  std::string cell;
  while (std::getline(stream, cell, ','))
  {
    cells.push_back(Trim(cell));
  }
  if (!line.empty() && line.back() == ',')
  {
    cells.push_back("");
  }
  return cells;
}

std::string Number(double value)
{
  std::ostringstream text;
  text << value;
  return text.str();
}

/// The time unit a header cell names: "ns", "ps" or "".
std::string TimeUnitOf(const std::string& header)
{
  const std::string h = translucency::ToLower(header);
  for (const char* unit : { "ns", "ps" })
  {
    const std::string u(unit);
    if (h == "t_" + u || h == "time_" + u || h == "t (" + u + ")" || h == "time (" + u + ")")
    {
      return u;
    }
  }
  return "";
}

} // namespace

MeasuredFile ReadMeasuredTpsf(const std::string& path, std::size_t detectors)
{
  const std::string where = "--measured " + path;
  // A regular file within the size bound (not a FIFO or /dev/zero); a
  // missing file is reported below with the system's reason.
  std::error_code missing;
  if (std::filesystem::exists(path, missing))
    translucency::CheckInputFile(path, "--measured file");
  std::ifstream in(path);
  if (!in)
  {
    throw translucency::Error(
      where + ": cannot open the file (" + std::string(std::strerror(errno)) + ")");
  }
  MeasuredFile file;
  file.Path = path;
  std::string line;
  int lineNumber = 0;
  std::vector<std::string> header;
  std::vector<int> rowLines;
  std::string previousTime;
  while (std::getline(in, line))
  {
    ++lineNumber;
    if (lineNumber == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0)
    {
      line.erase(0, 3); // a UTF-8 byte-order mark (spreadsheet exports)
    }
    const std::string trimmed = Trim(line);
    if (trimmed.empty() || trimmed[0] == '#')
    {
      continue;
    }
    std::vector<std::string> cells = SplitCells(trimmed);
    if (header.empty())
    {
      header = cells;
      file.TimeUnit = TimeUnitOf(header[0]);
      if (file.TimeUnit.empty())
      {
        throw translucency::Error(where + " line " + std::to_string(lineNumber) +
          ": the first column's header '" + translucency::Abbreviate(header[0], 40) +
          "' names no time unit (expected t_ns or t_ps, then one column per --detector)");
      }
      if (header.size() - 1 != detectors)
      {
        throw translucency::Error(where + ": " + std::to_string(header.size() - 1) +
          " detector column(s) after the time column, but " + std::to_string(detectors) +
          " --detector option(s): one column per detector, in the order of --detector");
      }
      for (std::size_t k = 1; k < header.size(); ++k)
      {
        file.Columns.push_back(header[k].empty() ? "column " + std::to_string(k + 1) : header[k]);
      }
      file.Values.resize(detectors);
      continue;
    }
    if (cells.size() != header.size())
    {
      throw translucency::Error(where + " line " + std::to_string(lineNumber) + ": " +
        std::to_string(cells.size()) + " cells, the header has " +
        std::to_string(header.size()));
    }
    for (std::size_t k = 0; k < cells.size(); ++k)
    {
      const char* begin = cells[k].c_str();
      char* end = nullptr;
      errno = 0;
      const double value = std::strtod(begin, &end);
      if (cells[k].empty() || *end != '\0' || !std::isfinite(value) || errno == ERANGE)
      {
        throw translucency::Error(where + " line " + std::to_string(lineNumber) + ", column " +
          std::to_string(k + 1) + " (" + translucency::Abbreviate(header[k], 40) + "): '" +
          translucency::Abbreviate(cells[k], 40) + "' is not a finite number");
      }
      if (k == 0)
      {
        const double t = file.TimeUnit == "ps" ? 1e-3 * value : value;
        if (!file.Times.empty() && !(t > file.Times.back()))
        {
          throw translucency::Error(where + " line " + std::to_string(lineNumber) + ": time " +
            cells[k] + " " + file.TimeUnit + " is not after " + previousTime + " " +
            file.TimeUnit + " on line " + std::to_string(rowLines.back()) +
            "; times must increase");
        }
        file.Times.push_back(t);
        previousTime = cells[k];
      }
      else
      {
        file.Values[k - 1].push_back(value);
      }
    }
    rowLines.push_back(lineNumber);
  }
  if (header.empty())
  {
    throw translucency::Error(where + ": no header row (expected t_ns or t_ps, then one column "
                                      "per --detector)");
  }
  if (file.Times.size() < 2)
  {
    throw translucency::Error(where + ": " + std::to_string(file.Times.size()) +
      " data row(s); a curve needs at least 2");
  }
  return file;
}

void AddMeasured(TpsfTable& table, const MeasuredFile& file, const std::string& normalise,
  const std::string& reference, int channel)
{
  MeasuredOverlay& overlay = table.Measured;
  overlay.File = file.Path;
  overlay.TimeUnit = file.TimeUnit;
  overlay.Normalise = normalise;
  overlay.Reference = reference;
  overlay.Channel = channel;
  overlay.Series.clear();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::string where = "--measured " + file.Path;
  for (std::size_t d = 0; d < file.Columns.size(); ++d)
  {
    MeasuredSeries series;
    series.Detector = static_cast<int>(d);
    series.Column = file.Columns[d];
    series.Times = file.Times;
    series.Raw = file.Values[d];
    const TpsfSeries* solver = nullptr;
    for (const TpsfSeries& s : table.Series)
    {
      if (s.Solver == reference && s.Detector == static_cast<int>(d))
      {
        solver = &s;
      }
    }
    // Linear interpolation to the gate centres within the measured times.
    std::vector<double> interpolated(table.GateCentres.size(), nan);
    double measuredSum = 0.0, referenceSum = 0.0, measuredPeak = -1.0, referencePeak = -1.0;
    int overlap = 0;
    for (std::size_t g = 0; g < table.GateCentres.size(); ++g)
    {
      const double t = table.GateCentres[g];
      if (t < series.Times.front() || t > series.Times.back())
      {
        continue;
      }
      const std::size_t i = static_cast<std::size_t>(
        std::upper_bound(series.Times.begin(), series.Times.end(), t) - series.Times.begin());
      const std::size_t hi = std::min(i, series.Times.size() - 1), lo = hi - 1;
      const double w = (t - series.Times[lo]) / (series.Times[hi] - series.Times[lo]);
      interpolated[g] = (1.0 - w) * series.Raw[lo] + w * series.Raw[hi];
      ++overlap;
      measuredSum += interpolated[g];
      measuredPeak = std::max(measuredPeak, interpolated[g]);
      if (solver)
      {
        const double value = solver->Exitance[g][channel];
        referenceSum += value;
        referencePeak = std::max(referencePeak, value);
      }
    }
    const std::string name = "detector " + std::to_string(d + 1) + "'s column '" +
      series.Column + "'";
    if (overlap == 0)
    {
      throw translucency::Error(where + ": no gate centre lies within its times (" +
        Number(series.Times.front()) + " to " + Number(series.Times.back()) +
        " ns); choose --time-gates that overlap them");
    }
    if (normalise == "area")
    {
      if (!(measuredSum > 0.0))
      {
        throw translucency::Error(where + ": " + name +
          " has no positive area over the gates it overlaps (sum " + Number(measuredSum) +
          "); use --measured-normalise none");
      }
      series.Scale = referenceSum / measuredSum;
    }
    else if (normalise == "peak")
    {
      if (!(measuredPeak > 0.0))
      {
        throw translucency::Error(where + ": " + name +
          " has no positive value at the gates it overlaps; use --measured-normalise none");
      }
      series.Scale = referencePeak / measuredPeak;
    }
    series.AtGates = interpolated;
    for (double& value : series.AtGates)
    {
      value *= series.Scale; // NaN stays NaN
    }
    overlay.Series.push_back(std::move(series));
  }
}

} // namespace translucency_app
