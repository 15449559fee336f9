#include "CompareTpsf.h"

#include "Error.h"

#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace translucency_app
{
namespace
{
const char* const ChannelNames[3] = { "R", "G", "B" };

std::vector<std::array<double, 3>> ReadTriples(vtkDataArray* array)
{
  std::vector<std::array<double, 3>> values;
  if (!array || array->GetNumberOfComponents() != 3)
  {
    return values;
  }
  values.resize(static_cast<size_t>(array->GetNumberOfTuples()));
  for (vtkIdType g = 0; g < array->GetNumberOfTuples(); ++g)
  {
    array->GetTuple(g, values[static_cast<size_t>(g)].data());
  }
  return values;
}
} // namespace

TpsfTable CollectTpsf(const std::vector<std::string>& solvers,
  const std::vector<vtkUnstructuredGrid*>& volumes, const std::vector<std::string>& detectorSpecs)
{
  TpsfTable table;
  table.DetectorSpecs = detectorSpecs;
  for (size_t s = 0; s < solvers.size(); ++s)
  {
    vtkFieldData* fields = volumes[s]->GetFieldData();
    vtkDataArray* centres = fields->GetArray("TimeGateCentres");
    if (!centres)
    {
      throw translucency::Error(solvers[s] + ": no time gates in its output (TimeGateCentres)");
    }
    std::vector<double> gates(static_cast<size_t>(centres->GetNumberOfTuples()));
    for (vtkIdType g = 0; g < centres->GetNumberOfTuples(); ++g)
    {
      gates[static_cast<size_t>(g)] = centres->GetComponent(g, 0);
    }
    if (s == 0)
    {
      table.GateCentres = gates;
    }
    else if (gates != table.GateCentres)
    {
      throw translucency::Error(solvers[s] + ": its time gates differ from " + solvers[0] + "'s");
    }
    for (size_t d = 0; d < detectorSpecs.size(); ++d)
    {
      TpsfSeries series;
      series.Solver = solvers[s];
      series.Detector = static_cast<int>(d);
      const std::string k = std::to_string(d);
      series.Fluence = ReadTriples(fields->GetArray(("DetectorFluenceTPSF" + k).c_str()));
      series.Exitance = ReadTriples(fields->GetArray(("DetectorExitanceTPSF" + k).c_str()));
      series.FluenceError =
        ReadTriples(fields->GetArray(("DetectorFluenceTPSFStandardError" + k).c_str()));
      series.ExitanceError =
        ReadTriples(fields->GetArray(("DetectorExitanceTPSFStandardError" + k).c_str()));
      if (series.Fluence.size() != gates.size() || series.Exitance.size() != gates.size())
      {
        throw translucency::Error(solvers[s] + ": no TPSF for detector " +
          std::to_string(d + 1) + " (" + detectorSpecs[d] + ") in its output");
      }
      if (series.FluenceError.size() != gates.size() ||
        series.ExitanceError.size() != gates.size())
      {
        series.FluenceError.clear();
        series.ExitanceError.clear();
      }
      table.Series.push_back(std::move(series));
    }
  }
  return table;
}

std::string TpsfCsv(const TpsfTable& table)
{
  std::ostringstream csv;
  csv << "t_ns";
  for (const TpsfSeries& s : table.Series)
  {
    for (const char* quantity : { "fluence", "exitance" })
    {
      for (int c = 0; c < 3; ++c)
      {
        const std::string column = s.Solver + "_d" + std::to_string(s.Detector + 1) + "_" +
          quantity + "_" + ChannelNames[c];
        csv << "," << column;
        if (!s.FluenceError.empty())
        {
          csv << "," << column << "_se";
        }
      }
    }
  }
  for (const MeasuredSeries& m : table.Measured.Series)
  {
    csv << ",measured_d" << m.Detector + 1;
  }
  const ClosedFormOverlay& closed = table.ClosedForm;
  for (size_t d = 0; d < closed.Fluence.size(); ++d)
  {
    if (closed.Fluence[d].empty())
    {
      continue;
    }
    for (const char* quantity : { "fluence", "exitance" })
    {
      for (int c = 0; c < 3; ++c)
      {
        csv << ",closedform_d" << d + 1 << "_" << quantity << "_" << ChannelNames[c];
      }
    }
  }
  csv << "\n" << std::setprecision(10);
  for (size_t g = 0; g < table.GateCentres.size(); ++g)
  {
    csv << table.GateCentres[g];
    for (const TpsfSeries& s : table.Series)
    {
      for (int q = 0; q < 2; ++q)
      {
        const auto& values = q == 0 ? s.Fluence : s.Exitance;
        const auto& errors = q == 0 ? s.FluenceError : s.ExitanceError;
        for (int c = 0; c < 3; ++c)
        {
          csv << "," << values[g][c];
          if (!errors.empty())
          {
            csv << "," << errors[g][c];
          }
        }
      }
    }
    for (const MeasuredSeries& m : table.Measured.Series)
    {
      if (std::isfinite(m.AtGates[g]))
      {
        csv << "," << m.AtGates[g];
      }
      else
      {
        csv << ",nan";
      }
    }
    for (size_t d = 0; d < closed.Fluence.size(); ++d)
    {
      if (closed.Fluence[d].empty())
      {
        continue;
      }
      for (int q = 0; q < 2; ++q)
      {
        const auto& values = q == 0 ? closed.Fluence[d] : closed.Exitance[d];
        for (int c = 0; c < 3; ++c)
        {
          csv << "," << values[g][c];
        }
      }
    }
    csv << "\n";
  }
  return csv.str();
}

nlohmann::json TpsfJson(const TpsfTable& table)
{
  nlohmann::json j;
  j["gate_centres_ns"] = table.GateCentres;
  j["reading"] = "gate averages of the fluence rate and the exitance, J/(mm^2 ns) per J of pulse";
  j["detectors"] = table.DetectorSpecs;
  j["series"] = nlohmann::json::array();
  for (const TpsfSeries& s : table.Series)
  {
    nlohmann::json entry = { { "solver", s.Solver }, { "detector", s.Detector + 1 },
      { "detector_spec", table.DetectorSpecs[static_cast<size_t>(s.Detector)] } };
    for (int q = 0; q < 2; ++q)
    {
      const auto& values = q == 0 ? s.Fluence : s.Exitance;
      const auto& errors = q == 0 ? s.FluenceError : s.ExitanceError;
      const std::string name = q == 0 ? "fluence" : "exitance";
      for (int c = 0; c < 3; ++c)
      {
        std::vector<double> v, e;
        for (size_t g = 0; g < values.size(); ++g)
        {
          v.push_back(values[g][c]);
          if (!errors.empty())
          {
            e.push_back(errors[g][c]);
          }
        }
        entry[name + "_j_mm2_ns"][ChannelNames[c]] = v;
        if (!errors.empty())
        {
          entry[name + "_standard_error_j_mm2_ns"][ChannelNames[c]] = e;
        }
      }
    }
    j["series"].push_back(entry);
  }
  const MeasuredOverlay& measured = table.Measured;
  if (!measured.Series.empty())
  {
    nlohmann::json m;
    m["file"] = measured.File;
    m["time_unit_in_file"] = measured.TimeUnit;
    m["normalise"] = measured.Normalise;
    m["reference_solver"] = measured.Reference;
    m["channel"] = ChannelNames[measured.Channel];
    m["series"] = nlohmann::json::array();
    for (const MeasuredSeries& series : measured.Series)
    {
      std::vector<nlohmann::json> atGates;
      for (double value : series.AtGates)
      {
        atGates.push_back(std::isfinite(value) ? nlohmann::json(value) : nlohmann::json());
      }
      m["series"].push_back({ { "detector", series.Detector + 1 }, { "column", series.Column },
        { "scale", series.Scale }, { "times_ns", series.Times }, { "values_raw", series.Raw },
        { "scaled_at_gate_centres", atGates } });
    }
    j["measured"] = m;
  }
  const ClosedFormOverlay& closed = table.ClosedForm;
  if (!closed.Name.empty())
  {
    nlohmann::json c;
    c["name"] = closed.Name;
    c["assumption"] = closed.Assumption;
    c["computed"] = closed.SkipReason.empty();
    if (!closed.SkipReason.empty())
    {
      c["skipped_because"] = closed.SkipReason;
    }
    c["detectors"] = nlohmann::json::array();
    for (size_t d = 0; d < closed.Fluence.size() && closed.SkipReason.empty(); ++d)
    {
      nlohmann::json entry = { { "detector", d + 1 } };
      if (closed.Fluence[d].empty())
      {
        entry["skipped_because"] = closed.DetectorSkipReasons[d];
      }
      for (int q = 0; q < 2 && !closed.Fluence[d].empty(); ++q)
      {
        const auto& values = q == 0 ? closed.Fluence[d] : closed.Exitance[d];
        for (int ch = 0; ch < 3; ++ch)
        {
          std::vector<double> v;
          for (const auto& gate : values)
          {
            v.push_back(gate[ch]);
          }
          entry[std::string(q == 0 ? "fluence" : "exitance") + "_j_mm2_ns"][ChannelNames[ch]] = v;
        }
      }
      c["detectors"].push_back(entry);
    }
    j["closed_form"] = c;
  }
  return j;
}

bool WriteTpsfPNG(const TpsfTable& table, int channel, const std::string& caption,
  const std::string& fileName, std::string& error)
{
  std::vector<PlotSeries> curves;
  std::vector<std::string> solvers;
  for (const TpsfSeries& s : table.Series)
  {
    auto found = std::find(solvers.begin(), solvers.end(), s.Solver);
    const int colour = static_cast<int>(found - solvers.begin());
    if (found == solvers.end())
    {
      solvers.push_back(s.Solver);
    }
    PlotSeries curve;
    curve.Name = s.Solver + ", detector " + std::to_string(s.Detector + 1) + " (" +
      table.DetectorSpecs[static_cast<size_t>(s.Detector)] + ")";
    curve.Colour = colour;
    curve.Markers = !s.ExitanceError.empty();
    curve.Dashed = s.Detector % 2 == 1;
    for (size_t g = 0; g < table.GateCentres.size(); ++g)
    {
      const double value = s.Exitance[g][channel];
      if (value > 0.0 && std::isfinite(value))
      {
        curve.X.push_back(table.GateCentres[g]);
        curve.Y.push_back(value);
      }
    }
    curves.push_back(curve);
  }
  const ClosedFormOverlay& closed = table.ClosedForm;
  for (size_t d = 0; d < closed.Exitance.size(); ++d)
  {
    if (closed.Exitance[d].empty())
    {
      continue;
    }
    PlotSeries curve;
    curve.Name = "closed form, detector " + std::to_string(d + 1) + " (" + closed.Assumption +
      "; " + closed.Name + ")";
    curve.Colour = PlotGrey;
    curve.Dashed = true;
    curve.DashDot = d % 2 == 1;
    for (size_t g = 0; g < table.GateCentres.size(); ++g)
    {
      const double value = closed.Exitance[d][g][channel];
      if (value > 0.0 && std::isfinite(value))
      {
        curve.X.push_back(table.GateCentres[g]);
        curve.Y.push_back(value);
      }
    }
    curves.push_back(curve);
  }
  const MeasuredOverlay& measured = table.Measured;
  for (const MeasuredSeries& m : measured.Series)
  {
    PlotSeries curve;
    std::ostringstream name;
    name << "measured, detector " << m.Detector + 1 << " ('" << m.Column << "'), ";
    if (measured.Normalise == "none")
    {
      name << "as in the file";
    }
    else
    {
      name << "scaled to " << measured.Reference << "'s " << measured.Normalise << " (x "
           << std::setprecision(3) << m.Scale << ")";
    }
    curve.Name = name.str();
    curve.Colour = PlotBlack;
    curve.Markers = true;
    curve.Dashed = m.Detector % 2 == 1;
    // Drawn over the gates' span only (the axis is the solvers').
    const size_t n = table.GateCentres.size();
    const double half = n > 1 ? 0.5 * (table.GateCentres[1] - table.GateCentres[0]) : 0.0;
    const double t0 = n ? table.GateCentres.front() - half : 0.0;
    const double t1 = n ? table.GateCentres.back() + half : 0.0;
    for (size_t i = 0; i < m.Times.size(); ++i)
    {
      const double value = m.Scale * m.Raw[i];
      if (value > 0.0 && std::isfinite(value) && m.Times[i] >= t0 && m.Times[i] <= t1)
      {
        curve.X.push_back(m.Times[i]);
        curve.Y.push_back(value);
      }
    }
    curves.push_back(curve);
  }
  return WritePlotPNG(curves, "time t (ns, gate centres)",
    std::string("TPSF: exitance ") + ChannelNames[channel] +
      " per J of pulse (J/(mm^2 ns)), log scale",
    fileName, error, caption);
}

} // namespace translucency_app
