#include "DiffuseOpticsOptions.h"

#include "Options.h"
#include "Utilities.h"

#include "TimeResolved.h"
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

TimeGatesSpec ParseTimeGates(const std::string& spec)
{
  const std::vector<double> v = ParseNumbers(spec, "--time-gates " + spec);
  if (v.size() != 3)
  {
    throw UsageError("--time-gates " + spec + ": expected T0,T1,N (ns, ns, number of gates)");
  }
  const std::string count = spec.substr(spec.rfind(',') + 1);
  if (!(v[2] == std::floor(v[2])))
  {
    throw UsageError("--time-gates " + spec + ": N = " + count + " is not a whole number of gates");
  }
  if (v[2] > translucency::TimeGates::MaximumTimeGates)
  {
    throw UsageError("--time-gates " + spec + ": N = " + count + " gates is more than the limit of " +
      std::to_string(translucency::TimeGates::MaximumTimeGates));
  }
  translucency::TimeGates gates;
  gates.Start = v[0];
  gates.End = v[1];
  if (v[2] < 1.0)
  {
    throw UsageError("--time-gates " + spec + ": N = " + count + " gates (expected N >= 1)");
  }
  gates.Count = static_cast<int>(v[2]);
  const std::string fault = gates.Check();
  if (!fault.empty())
  {
    throw UsageError("--time-gates " + spec + ": " + fault);
  }
  return { spec, gates.Start, gates.End, gates.Count };
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
  solve->SetTimeGates(this->TimeGates.Start, this->TimeGates.End, this->TimeGates.Count);
  solve->SetTimeStepsPerGate(this->StepsPerGate);
  solve->RemoveAllTimeSnapshots();
  for (int g : this->TimeSnapshots)
  {
    if (g >= this->TimeGates.Count)
    {
      throw UsageError("--time-snapshots: gate " + std::to_string(g) + " (expected 0.." +
        std::to_string(this->TimeGates.Count - 1) + " for --time-gates " + this->TimeGates.Spec +
        "; the gates are numbered from 0)");
    }
    solve->AddTimeSnapshot(g);
  }
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
  const int gates = solve->GetNumberOfTimeGates();
  if (gates == 0)
  {
    return;
  }
  std::cout << "time gates: " << gates << " of "
            << (this->TimeGates.End - this->TimeGates.Start) / gates << " ns from "
            << this->TimeGates.Start << " ns, " << solve->GetTimeStepsPerGateUsed()
            << " time steps per gate; readings above are time integrals (J/mm^2 per J)\n";
  for (std::size_t k = 0; k < this->Detectors.size(); ++k)
  {
    const int d = static_cast<int>(k);
    std::cout << "detector " << this->Detectors[k].Spec
              << ": TPSF, gate averages in J/(mm^2 ns) per J of pulse\n"
              << "  t (ns)       fluence R    fluence G    fluence B    exitance R   exitance G"
                 "   exitance B\n";
    for (int g = 0; g < gates; ++g)
    {
      std::cout << "  " << std::fixed << std::setprecision(5) << std::setw(9)
                << solve->GetTimeGateCentre(g) << std::scientific << std::setprecision(4);
      for (int c = 0; c < 3; ++c)
        std::cout << "  " << std::setw(11) << solve->GetDetectorFluenceTPSF(d, g, c);
      for (int c = 0; c < 3; ++c)
        std::cout << "  " << std::setw(11) << solve->GetDetectorExitanceTPSF(d, g, c);
      std::cout << "\n";
    }
    std::cout << std::defaultfloat << std::setprecision(6);
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
  const int gates = solve->GetNumberOfTimeGates();
  if (gates > 0)
  {
    std::vector<double> centres;
    for (int g = 0; g < gates; ++g)
    {
      centres.push_back(solve->GetTimeGateCentre(g));
    }
    j["time_gates"] = { { "spec", this->TimeGates.Spec }, { "t0_ns", this->TimeGates.Start },
      { "t1_ns", this->TimeGates.End }, { "count", gates },
      { "width_ns", (this->TimeGates.End - this->TimeGates.Start) / gates },
      { "steps_per_gate", solve->GetTimeStepsPerGateUsed() },
      { "gate_centres_ns", centres }, { "snapshots", this->TimeSnapshots },
      { "reading", "gate average" } };
  }
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
    if (gates > 0)
    {
      // fluence_w_mm2 / exitance_w_mm2 above are then the time integrals.
      for (int c = 0; c < 3; ++c)
      {
        std::vector<double> fluence, exitance;
        for (int g = 0; g < gates; ++g)
        {
          fluence.push_back(solve->GetDetectorFluenceTPSF(d, g, c));
          exitance.push_back(solve->GetDetectorExitanceTPSF(d, g, c));
        }
        detector["tpsf"]["fluence_j_mm2_ns"][channel[c]] = fluence;
        detector["tpsf"]["exitance_j_mm2_ns"][channel[c]] = exitance;
      }
    }
    j["detectors"].push_back(detector);
  }
}

void AddDiffuseOpticsOptions(CLI::App* command, DiffuseOpticsOptions& options)
{
  const std::string group =
    "Diffuse optics (divergence, fem; sp3 --frequency; montecarlo but --frequency; --source, "
    "--detector: every "
    "solver)";
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
      "                            et al. 1992 equivalent source;\n"
      "                            montecarlo: the refracted beam)\n"
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
  CLI::Option* frequency = AddNumber(command, "--frequency", options.Frequency,
    "modulation frequency (Hz): solve the frequency-domain equation;\n"
    "FluenceAmplitude and FluencePhase point arrays, detector phases",
    "HZ", [](double f) { return f > 0; }, "--frequency must be > 0 Hz")
    ->group(group);
  CLI::Option* gates =
    command
      ->add_option_function<std::string>(
        "--time-gates", [o](const std::string& spec) { o->TimeGates = ParseTimeGates(spec); },
        "T0,T1,N: time-resolved: the response to a pulse at t = 0 (a\n"
        "source of P W is a pulse of P J), averaged over N equal gates\n"
        "covering [T0, T1] ns (T0 >= 0, N <= " +
          std::to_string(translucency::TimeGates::MaximumTimeGates) +
          "): a TPSF table per detector;\n"
          "Fluence = the time integral (Documentation/DiffuseOptics.md)")
      ->type_name("T0,T1,N")
      ->group(group)
      ->excludes(frequency);
  AddNumber(command, "--steps-per-gate", options.StepsPerGate,
    "time steps per gate (0 = automatic: 4, more where\nmu_a c dt / eta > 0.05)", "K",
    [](double k) { return k >= 0 && k <= translucency::TimeGates::MaximumStepsPerGate; },
    "--steps-per-gate must be 0 (automatic) to " +
      std::to_string(translucency::TimeGates::MaximumStepsPerGate))
    ->group(group)
    ->needs(gates);
  command
    ->add_option_function<std::vector<std::string>>(
      "--time-snapshots",
      [o](const std::vector<std::string>& specs) {
        for (const std::string& spec : specs)
        {
          for (double g : ParseNumbers(spec, "--time-snapshots " + spec))
          {
            if (!(g >= 0.0) || g != std::floor(g) || g > 1e9)
            {
              throw UsageError("--time-snapshots " + spec +
                ": a gate is a whole number >= 0 (gates are numbered from 0)");
            }
            o->TimeSnapshots.push_back(static_cast<int>(g));
          }
        }
      },
      "G[,G...]: add the gate-averaged fluence of these gates\n"
      "(0-based) as point arrays FluenceGate<G> to the .vtu")
    ->type_name("G,...")
    ->group(group)
    ->needs(gates);
}

} // namespace translucency_app
