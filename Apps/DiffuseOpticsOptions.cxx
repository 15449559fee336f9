#include "DiffuseOpticsOptions.h"

#include "Options.h"
#include "Utilities.h"

#include "vtkSolveDiffusion.h"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace translucency_app
{
namespace
{

std::vector<std::string> SplitColons(const std::string& spec)
{
  std::vector<std::string> parts;
  std::stringstream ss(spec);
  std::string part;
  while (std::getline(ss, part, ':'))
  {
    parts.push_back(part);
  }
  return parts;
}

std::array<double, 3> Triple(const std::string& text, const std::string& option,
  const std::string& spec, const char* what)
{
  const std::vector<double> v = ParseNumbers(text, option + " " + spec);
  if (v.size() != 3)
  {
    throw UsageError(option + " " + spec + ": the " + what + " needs three comma-separated numbers");
  }
  return { v[0], v[1], v[2] };
}

std::array<double, 3> Power(const std::string& text, const std::string& spec)
{
  const std::vector<double> v = ParseNumbers(text, "--source " + spec);
  if (v.size() != 1 && v.size() != 3)
  {
    throw UsageError("--source " + spec + ": the power is one number (W, every channel) or three");
  }
  std::array<double, 3> power = v.size() == 1 ? std::array<double, 3>{ v[0], v[0], v[0] }
                                              : std::array<double, 3>{ v[0], v[1], v[2] };
  for (double p : power)
  {
    if (!(p >= 0.0) || !std::isfinite(p))
    {
      throw UsageError("--source " + spec + ": the power must be finite and >= 0 W");
    }
  }
  return power;
}

} // namespace

SourceSpec ParseSource(const std::string& spec)
{
  SourceSpec source;
  source.Spec = spec;
  const std::vector<std::string> parts = SplitColons(spec);
  if (parts.empty())
  {
    throw UsageError("empty --source (point:x,y,z[:P] or pencil:x,y,z:dx,dy,dz[:P])");
  }
  if (parts[0] == "point")
  {
    if (parts.size() < 2 || parts.size() > 3)
    {
      throw UsageError("--source point needs x,y,z[:P]: '" + spec + "'");
    }
    source.Position = Triple(parts[1], "--source", spec, "position");
    if (parts.size() == 3)
    {
      source.Power = Power(parts[2], spec);
    }
  }
  else if (parts[0] == "pencil")
  {
    if (parts.size() < 3 || parts.size() > 4)
    {
      throw UsageError("--source pencil needs x,y,z:dx,dy,dz[:P]: '" + spec + "'");
    }
    source.Pencil = true;
    source.Position = Triple(parts[1], "--source", spec, "entry point");
    source.Direction = Triple(parts[2], "--source", spec, "direction");
    if (source.Direction[0] == 0 && source.Direction[1] == 0 && source.Direction[2] == 0)
    {
      throw UsageError("--source " + spec + ": the direction is zero");
    }
    if (parts.size() == 4)
    {
      source.Power = Power(parts[3], spec);
    }
  }
  else
  {
    throw UsageError("unknown source type '" + parts[0] + "' in --source " + spec +
      " (point:x,y,z[:P] or pencil:x,y,z:dx,dy,dz[:P])");
  }
  return source;
}

DetectorSpec ParseDetector(const std::string& spec)
{
  DetectorSpec detector;
  detector.Spec = spec;
  const std::vector<std::string> parts = SplitColons(spec);
  if (parts.empty() || parts.size() > 2)
  {
    throw UsageError("--detector needs x,y,z[:r]: '" + spec + "'");
  }
  detector.Position = Triple(parts[0], "--detector", spec, "position");
  if (parts.size() == 2)
  {
    const std::vector<double> r = ParseNumbers(parts[1], "--detector " + spec);
    if (r.size() != 1 || !(r[0] >= 0.0) || !std::isfinite(r[0]))
    {
      throw UsageError("--detector " + spec + ": the fibre radius is one number >= 0 (mm)");
    }
    detector.Radius = r[0];
  }
  return detector;
}

void DiffuseOpticsOptions::Apply(vtkSolveDiffusion* solve) const
{
  solve->RemoveAllSources();
  for (const SourceSpec& s : this->Sources)
  {
    if (s.Pencil)
    {
      solve->AddPencilBeam(s.Position[0], s.Position[1], s.Position[2], s.Direction[0],
        s.Direction[1], s.Direction[2], s.Power[0], s.Power[1], s.Power[2]);
    }
    else
    {
      solve->AddPointSource(
        s.Position[0], s.Position[1], s.Position[2], s.Power[0], s.Power[1], s.Power[2]);
    }
  }
  solve->RemoveAllDetectors();
  for (const DetectorSpec& d : this->Detectors)
  {
    solve->AddDetector(d.Position[0], d.Position[1], d.Position[2], d.Radius);
  }
  solve->SetModulationFrequency(this->Frequency);
}

void DiffuseOpticsOptions::Print(vtkSolveDiffusion* solve) const
{
  const bool phase = this->Frequency > 0.0;
  for (std::size_t k = 0; k < this->Detectors.size(); ++k)
  {
    const int d = static_cast<int>(k);
    std::cout << "detector " << this->Detectors[k].Spec << ": fluence" << (phase ? " amplitude" : "")
              << " (" << std::scientific << std::setprecision(4);
    for (int c = 0; c < 3; ++c)
      std::cout << solve->GetDetectorFluence(d, c) << (c < 2 ? ", " : "");
    std::cout << ") W/mm^2, exitance (";
    for (int c = 0; c < 3; ++c)
      std::cout << solve->GetDetectorExitance(d, c) << (c < 2 ? ", " : "");
    std::cout << ") W/mm^2" << std::defaultfloat;
    if (phase)
    {
      std::cout << ", fluence phase (" << std::setprecision(4);
      for (int c = 0; c < 3; ++c)
        std::cout << solve->GetDetectorFluencePhase(d, c) << (c < 2 ? ", " : "");
      std::cout << ") rad";
    }
    std::cout << std::setprecision(6) << "\n";
  }
}

void DiffuseOpticsOptions::Report(vtkSolveDiffusion* solve, nlohmann::json& j) const
{
  if (this->Frequency > 0.0)
  {
    j["frequency_hz"] = this->Frequency;
  }
  for (const SourceSpec& s : this->Sources)
  {
    nlohmann::json source = { { "spec", s.Spec }, { "type", s.Pencil ? "pencil" : "point" },
      { "position_mm", s.Position }, { "power_w", s.Power } };
    if (s.Pencil)
    {
      source["direction"] = s.Direction;
    }
    j["sources"].push_back(source);
  }
  static const char* channel[3] = { "R", "G", "B" };
  for (std::size_t k = 0; k < this->Detectors.size(); ++k)
  {
    const int d = static_cast<int>(k);
    double surface[3];
    solve->GetDetectorSurfacePosition(d, surface);
    nlohmann::json detector = { { "spec", this->Detectors[k].Spec },
      { "position_mm", this->Detectors[k].Position },
      { "surface_position_mm", { surface[0], surface[1], surface[2] } },
      { "radius_mm", this->Detectors[k].Radius } };
    for (int c = 0; c < 3; ++c)
    {
      detector["fluence_w_mm2"][channel[c]] = solve->GetDetectorFluence(d, c);
      detector["exitance_w_mm2"][channel[c]] = solve->GetDetectorExitance(d, c);
      if (this->Frequency > 0.0)
      {
        detector["fluence_phase_rad"][channel[c]] = solve->GetDetectorFluencePhase(d, c);
        detector["exitance_phase_rad"][channel[c]] = solve->GetDetectorExitancePhase(d, c);
      }
    }
    j["detectors"].push_back(detector);
  }
}

void AddDiffuseOpticsOptions(CLI::App* command, DiffuseOpticsOptions& options)
{
  const std::string group = "Diffuse optics (divergence and fem solvers)";
  DiffuseOpticsOptions* o = &options;
  command
    ->add_option_function<std::vector<std::string>>(
      "--source",
      [o](const std::vector<std::string>& specs) {
        for (const std::string& spec : specs)
          o->Sources.push_back(ParseSource(spec));
      },
      "a source inside the object (may repeat; with only --source\n"
      "options no default light is added):\n"
      "point:x,y,z[:P]             isotropic point source at x,y,z mm\n"
      "pencil:x,y,z:dx,dy,dz[:P]   pencil beam entering at the surface\n"
      "                            point x,y,z along dx,dy,dz (Farrell\n"
      "                            et al. 1992 equivalent source)\n"
      "P: W, one value or R,G,B (1)")
    ->type_name("SPEC")
    ->group(group);
  command
    ->add_option_function<std::vector<std::string>>(
      "--detector",
      [o](const std::vector<std::string>& specs) {
        for (const std::string& spec : specs)
          o->Detectors.push_back(ParseDetector(spec));
      },
      "x,y,z[:r]: a detector on the surface (mm), optional fibre\n"
      "radius r mm; reports fluence and exitance per channel (may repeat)")
    ->type_name("SPEC")
    ->group(group);
  AddNumber(command, "--frequency", options.Frequency,
    "modulation frequency (Hz): solve the frequency-domain equation;\n"
    "FluenceAmplitude and FluencePhase point arrays, detector phases",
    "HZ", [](double f) { return f > 0; }, "--frequency must be > 0 Hz")
    ->group(group);
}

} // namespace translucency_app
