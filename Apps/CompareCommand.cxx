// `translucency compare`: every selected solver on one problem (mesh,
// material, lights), side by side: a table (stdout and JSON), a radiance
// picture per solver, a relative-error map per solver but the reference on
// its own symmetric scale plus one overview of them all on a shared scale,
// a plot of error against wall time for the iterative solvers (not the
// reference), and a .vtm multiblock.
// With the diffuse-optics options (sources, detectors, time gates): every
// solver's detector readings, and with --time-gates one TPSF plot overlaying
// the solvers (CompareTpsf.h), a measured curve (--measured, CompareMeasured.h)
// and the closed form where it applies (CompareClosedForm.h).

#include "CompareClosedForm.h"
#include "CompareMeasured.h"
#include "CompareTpsf.h"
#include "DiffuseOpticsOptions.h"
#include "Options.h"
#include "Pictures.h"
#include "PipelineRender.h"
#include "PowerReport.h"
#include "Provenance.h"
#include "Scene.h"
#include "Utilities.h"

#include "DiffusionSolverFactory.h"
#include "Error.h"
#include "Strings.h"

#include "vtkOutgoingRadiance.h"
#include "vtkSolveDiffusion.h"

#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkExecutive.h>
#include <vtkDoubleArray.h>
#include <vtkIdTypeArray.h>
#include <vtkImageAppend.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLMultiBlockDataWriter.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

namespace translucency_app
{

namespace
{
using json = nlohmann::json;

struct CompareOptions
{
  SceneOptions Scene;
  RadianceImageOptions Image;
  std::string SolverList = "divergence,fem";
  std::string Reference = "fem";
  std::string OutputDir, JsonPath;
  double GridSpacing = 0.0, RelTol = 1e-8;
  long long Photons = 1000000;
  int Seed = 1;
  bool NoPictures = false;
  RadianceReadoutOption Readout;
  const CLI::App* App = nullptr; ///< for the provenance of the JSON
  DiffuseOpticsOptions Optics;   ///< --source, --detector, --time-gates, ...
  std::string MeasuredPath;      ///< --measured: a measured TPSF per detector (CSV)
  std::string MeasuredNormalise = "area"; ///< --measured-normalise area|peak|none
  bool NoClosedForm = false;     ///< --no-closed-form
};

struct SolverResult
{
  std::string Name;
  vtkSmartPointer<vtkUnstructuredGrid> Volume;
  vtkSmartPointer<vtkPolyData> Surface;
  json Stats;
  double WallMs = 0.0;
};

std::vector<std::string> SplitList(const std::string& text)
{
  std::vector<std::string> items;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ','))
  {
    if (!item.empty())
      items.push_back(item);
  }
  return items;
}

/// Per-point relative error |x - r| / max(|r|, floor), floor = 1 % of the
/// reference's largest value in that channel (so shadowed points, where the
/// reference is ~0, do not dominate). Returns max and RMS over points and
/// channels; `perPoint` gets the largest channel error of each point.
void RelativeError(vtkDataArray* x, vtkDataArray* r, double& maxError, double& rmsError,
  std::vector<double>* perPoint = nullptr)
{
  const vtkIdType n = r->GetNumberOfTuples();
  double floor[3];
  for (int c = 0; c < 3; ++c)
  {
    double range[2];
    r->GetRange(range, c);
    floor[c] = 0.01 * std::max(std::abs(range[0]), std::abs(range[1]));
    if (floor[c] <= 0)
      floor[c] = 1e-300;
  }
  maxError = 0.0;
  double sum = 0.0;
  if (perPoint)
    perPoint->assign(static_cast<size_t>(n), 0.0);
  for (vtkIdType i = 0; i < n; ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double ref = r->GetComponent(i, c);
      const double e = std::abs(x->GetComponent(i, c) - ref) / std::max(std::abs(ref), floor[c]);
      maxError = std::max(maxError, e);
      sum += e * e;
      if (perPoint)
        (*perPoint)[i] = std::max((*perPoint)[i], e);
    }
  }
  rmsError = n > 0 ? std::sqrt(sum / (3.0 * n)) : 0.0;
}

/// The radiance a solver gives on the surface: eq. 3 from its fluence, or the
/// tallied exitant radiance for Monte Carlo.
vtkSmartPointer<vtkDataArray> SurfaceRadiance(const SolverResult& result)
{
  vtkDataArray* tallied = result.Volume->GetPointData()->GetArray("MonteCarloRadiance");
  if (!tallied)
  {
    return result.Surface->GetPointData()->GetArray("Radiance");
  }
  auto* ids = vtkIdTypeArray::SafeDownCast(
    result.Surface->GetPointData()->GetArray("vtkOriginalPointIds"));
  auto radiance = vtkSmartPointer<vtkDoubleArray>::New();
  radiance->SetName("Radiance");
  radiance->SetNumberOfComponents(3);
  radiance->SetNumberOfTuples(ids->GetNumberOfTuples());
  for (vtkIdType k = 0; k < ids->GetNumberOfTuples(); ++k)
  {
    double v[3];
    tallied->GetTuple(ids->GetValue(k), v);
    radiance->SetTuple(k, v);
  }
  return radiance;
}

SolverResult RunSolver(const std::string& name, vtkUnstructuredGrid* lit, double relTol,
  int maxIter, double gridSpacing, long long photons, int seed, bool paperReadout,
  const DiffuseOpticsOptions& optics)
{
  MessageCollector messages;
  vtkNew<vtkSolveDiffusion> solve;
  messages.Watch(solve, "solving with " + name);
  if (!solve->SetSolverByName(name.c_str()))
    throw UsageError(messages.Last());
  solve->SetInputData(lit);
  solve->SetRelTol(relTol);
  solve->SetMaxIter(maxIter);
  solve->SetWarmStart(false);
  solve->SetGridSpacing(gridSpacing);
  solve->SetNumberOfPhotons(photons);
  solve->SetSeed(seed);
  optics.Apply(solve);
  const auto start = Clock::now();
  solve->Update();
  if (!messages.Errors.empty())
    throw translucency::Error(name + ": " + messages.Last());
  SolverResult result;
  result.Name = name;
  result.WallMs = MillisecondsSince(start);
  result.Volume = solve->GetOutput();
  vtkNew<vtkOutgoingRadiance> radiance;
  messages.Watch(radiance);
  radiance->SetInputData(result.Volume);
  radiance->SetRadianceReadout(
    paperReadout ? vtkOutgoingRadiance::PAPER : vtkOutgoingRadiance::ENERGY_CONSERVING);
  radiance->Update();
  if (!messages.Errors.empty())
    throw translucency::Error(name + ": " + messages.Last());
  result.Surface = radiance->GetOutput();
  // No exit 0 with NaN: every array of the results must be finite.
  RequireFiniteResult(result.Volume, "the " + name + " solution");
  RequireFiniteResult(result.Surface, "the " + name + " surface radiance");
  json& s = result.Stats;
  s["solver"] = name;
  s["linear_solver"] = solve->GetLinearSolverUsed();
  s["unknowns"] = solve->GetNumberOfUnknowns();
  s["nonzeros"] = solve->GetNumberOfNonZeros();
  s["memory_bytes"] = solve->GetMemoryBytes();
  s["setup_ms"] = solve->GetAssemblyTime();
  s["solve_ms"] = solve->GetSolveTime();
  s["topology_ms"] = solve->GetTopologyTime();
  for (int c = 0; c < 3; ++c)
  {
    s["iterations"].push_back(solve->GetNumberOfIterations(c));
    s["relative_residual"].push_back(solve->GetFinalResidual(c));
    s["converged"].push_back(solve->GetConverged(c));
  }
  s["power_W"] = PowerBalanceJson(solve);
  // Sources, detector readings (and each detector's TPSF), as render reports them.
  optics.Report(solve, s);
  return result;
}

/// Per-channel relative error of `x` against `r` (as RelativeError, one
/// channel at a time): {"R": {"max", "rms"}, "G": ..., "B": ...}.
json ChannelErrors(vtkDataArray* x, vtkDataArray* r)
{
  static const char* names[3] = { "R", "G", "B" };
  json errors;
  const vtkIdType n = r->GetNumberOfTuples();
  for (int c = 0; c < 3; ++c)
  {
    double range[2];
    r->GetRange(range, c);
    double floor = 0.01 * std::max(std::abs(range[0]), std::abs(range[1]));
    if (floor <= 0)
      floor = 1e-300;
    double maxError = 0.0, sum = 0.0;
    for (vtkIdType i = 0; i < n; ++i)
    {
      const double ref = r->GetComponent(i, c);
      const double e = std::abs(x->GetComponent(i, c) - ref) / std::max(std::abs(ref), floor);
      maxError = std::max(maxError, e);
      sum += e * e;
    }
    errors[names[c]] = { { "max", maxError }, { "rms", n > 0 ? std::sqrt(sum / n) : 0.0 } };
  }
  return errors;
}

/**
 * A solver's boundary fluence against Monte Carlo's, weighted by the
 * reported standard error: per channel, over the points whose relative
 * standard error is at most `maxRelativeSE` (the rest are masked: too few
 * photons there to judge), the z-scores z = (x - mc) / se (RMS and the
 * fraction with |z| > 3) and the relative RMS difference.
 */
json AgainstMonteCarlo(vtkDataArray* x, const SolverResult& mc, double maxRelativeSE)
{
  static const char* names[3] = { "R", "G", "B" };
  vtkDataArray* se = mc.Volume->GetPointData()->GetArray("FluenceStandardError");
  auto* ids =
    vtkIdTypeArray::SafeDownCast(mc.Surface->GetPointData()->GetArray("vtkOriginalPointIds"));
  vtkDataArray* phi = mc.Surface->GetPointData()->GetArray("Fluence");
  json result;
  result["max_relative_standard_error"] = maxRelativeSE;
  for (int c = 0; c < 3; ++c)
  {
    long long used = 0, masked = 0, beyond3 = 0;
    double z2 = 0.0, r2 = 0.0;
    for (vtkIdType k = 0; k < ids->GetNumberOfTuples(); ++k)
    {
      const double m = phi->GetComponent(k, c);
      const double e = se->GetComponent(ids->GetValue(k), c);
      if (!(m > 0) || !(e > 0) || e > maxRelativeSE * m)
      {
        ++masked;
        continue;
      }
      const double d = x->GetComponent(k, c) - m;
      const double z = d / e;
      z2 += z * z;
      r2 += (d / m) * (d / m);
      beyond3 += std::abs(z) > 3.0;
      ++used;
    }
    result[names[c]] = { { "points", used }, { "masked", masked },
      { "z_rms", used ? std::sqrt(z2 / used) : 0.0 },
      { "fraction_abs_z_above_3", used ? static_cast<double>(beyond3) / used : 0.0 },
      { "relative_rms", used ? std::sqrt(r2 / used) : 0.0 } };
  }
  return result;
}

/// Signed relative error (x - r) / max(|r|, floor) of one channel, in percent
/// (floor as in RelativeError), as the point array "SignedRelativeRadianceError".
vtkSmartPointer<vtkDoubleArray> SignedError(vtkDataArray* x, vtkDataArray* r, int c)
{
  double range[2];
  r->GetRange(range, c);
  double floor = 0.01 * std::max(std::abs(range[0]), std::abs(range[1]));
  if (floor <= 0)
    floor = 1e-300;
  auto error = vtkSmartPointer<vtkDoubleArray>::New();
  error->SetName("SignedRelativeRadianceError");
  error->SetNumberOfTuples(r->GetNumberOfTuples());
  for (vtkIdType i = 0; i < r->GetNumberOfTuples(); ++i)
  {
    const double ref = r->GetComponent(i, c);
    error->SetValue(i, 100.0 * (x->GetComponent(i, c) - ref) / std::max(std::abs(ref), floor));
  }
  return error;
}

/// The relative standard error above which a Monte Carlo point is masked:
/// in the z-scores (AgainstMonteCarlo) and in the error maps (grey).
constexpr double MaxMonteCarloRelativeSE = 0.1;

/**
 * Masks (sets to NaN, drawn grey) the points of `error` where a Monte Carlo
 * result among `results` (the solver's own or the reference's) has a
 * relative standard error of its fluence above MaxMonteCarloRelativeSE in
 * channel `c`: too few photons there to judge any difference. Returns the
 * number of points masked.
 */
long long MaskNoisyMonteCarloPoints(
  vtkDoubleArray* error, std::initializer_list<const SolverResult*> results, int c)
{
  std::vector<bool> masked(static_cast<size_t>(error->GetNumberOfTuples()), false);
  for (const SolverResult* r : results)
  {
    vtkDataArray* se = r->Volume->GetPointData()->GetArray("FluenceStandardError");
    auto* ids =
      vtkIdTypeArray::SafeDownCast(r->Surface->GetPointData()->GetArray("vtkOriginalPointIds"));
    vtkDataArray* phi = r->Surface->GetPointData()->GetArray("Fluence");
    if (!se || !ids || !phi || ids->GetNumberOfTuples() != error->GetNumberOfTuples())
      continue;
    for (vtkIdType k = 0; k < ids->GetNumberOfTuples(); ++k)
    {
      const double m = phi->GetComponent(k, c);
      const double e = se->GetComponent(ids->GetValue(k), c);
      if (!(m > 0) || !(e >= 0) || e > MaxMonteCarloRelativeSE * m)
        masked[static_cast<size_t>(k)] = true;
    }
  }
  long long count = 0;
  for (size_t k = 0; k < masked.size(); ++k)
    if (masked[k])
    {
      error->SetValue(static_cast<vtkIdType>(k), std::nan(""));
      ++count;
    }
  return count;
}

/// The 99th percentile of |value| over the finite values of `error` (0 if none).
double AbsolutePercentile99(vtkDoubleArray* error)
{
  std::vector<double> values;
  for (vtkIdType i = 0; i < error->GetNumberOfTuples(); ++i)
    if (std::isfinite(error->GetValue(i)))
      values.push_back(std::abs(error->GetValue(i)));
  if (values.empty())
    return 0.0;
  const size_t k = 99 * (values.size() - 1) / 100;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

/// Error against the reference after k iterations, k = 1, 2, 4, ... until
/// converged: relative error of boundary fluence against wall time. The
/// solves stopped early do not converge by design: their warnings are
/// dropped and counted in `unconverged` (one summary line instead).
/// ErrorVersusTime: one doubling of the iteration limit moved the RMS error
/// from `before` to `after` by less than 1 % of it.
bool PlateauStep(double before, double after)
{
  return std::abs(after - before) < 0.01 * std::max(std::abs(before), std::abs(after));
}

PlotSeries ErrorVersusTime(const std::string& name, vtkUnstructuredGrid* lit,
  vtkDataArray* referenceFluence, double gridSpacing, const DiffuseOpticsOptions& optics,
  int& unconverged)
{
  PlotSeries series;
  series.Name = name;
  MessageCollector messages;
  for (int k = 1; k <= 8192; k *= 2)
  {
    vtkNew<vtkSolveDiffusion> solve;
    solve->SetSolverByName(name.c_str());
    solve->SetInputData(lit);
    solve->SetRelTol(1e-8);
    solve->SetMaxIter(k);
    solve->SetWarmStart(false);
    solve->AcceptUnconvergedOn(); // the study of early-stopped solves (never a result)
    solve->SetGridSpacing(gridSpacing);
    optics.Apply(solve); // the same sources (never time gates or a frequency: see Compare)
    // Not converging is the point here: the warnings are ignored, not logged.
    solve->AddObserver(vtkCommand::WarningEvent, messages.IgnoreCallback);
    solve->AddObserver(vtkCommand::ErrorEvent, messages.IgnoreCallback);
    solve->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, messages.IgnoreCallback);
    const auto start = Clock::now();
    solve->Update();
    const double ms = MillisecondsSince(start);
    vtkNew<vtkOutgoingRadiance> radiance;
    radiance->AddObserver(vtkCommand::WarningEvent, messages.IgnoreCallback);
    radiance->AddObserver(vtkCommand::ErrorEvent, messages.IgnoreCallback);
    radiance->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, messages.IgnoreCallback);
    radiance->SetInputData(solve->GetOutput());
    radiance->Update();
    vtkDataArray* fluence = radiance->GetOutput()->GetPointData()->GetArray("Fluence");
    if (!fluence)
      break;
    double maxError, rmsError;
    RelativeError(fluence, referenceFluence, maxError, rmsError);
    series.X.push_back(ms);
    series.Y.push_back(rmsError);
    if (solve->GetConverged(0) && solve->GetConverged(1) && solve->GetConverged(2))
      break;
    ++unconverged;
    // The curve has reached the model's error floor when two doublings in a
    // row moved it by less than 1 % (relative): more iterations change the
    // solve, not its error against the reference (a 45k-tet bunny's
    // quadgraph spent 68 of its sweep's 110 s there, at 1e-8).
    const size_t n = series.Y.size();
    if (n >= 3 && PlateauStep(series.Y[n - 3], series.Y[n - 2]) &&
      PlateauStep(series.Y[n - 2], series.Y[n - 1]))
      break;
  }
  return series;
}

void WriteJson(const std::string& path, const json& j)
{
  std::string error;
  EnsureParentDirectory(path);
  if (!WriteText(path, j.dump(2) + "\n", error))
    throw translucency::Error(error);
}

/// What the phases of Compare share: the options, the lit mesh, the solvers
/// in order (the reference first), their results and the error table.
struct CompareRun
{
  explicit CompareRun(CompareOptions& options)
    : Options(options)
  {
  }
  CompareOptions& Options;
  std::vector<std::string> Order;
  vtkSmartPointer<vtkUnstructuredGrid> Lit;
  std::map<std::string, SolverResult> Results;
  bool TimeResolved = false; ///< time gates and detectors: a TPSF per solver
  TpsfTable Tpsf;
  json Table = json::array(); ///< one row of statistics per solver
  double ErrorScale = 0.0;    ///< percent, for the error pictures
  const SolverResult* MonteCarlo = nullptr;
};

/// Compare: the checks that can fail before minutes of solving (options, the
/// outputs, the measured curves, the picture display) and the order of the
/// solvers (the reference first). `plan` holds the output locks: the caller
/// keeps it for the whole run.
std::vector<std::string> CheckAndOrder(
  CompareOptions& o, OutputPlan& plan, MeasuredFile& measured)
{
  SceneOptions& scene = o.Scene;
  const std::string& outputDir = o.OutputDir;
  scene.InteriorSources = !o.Optics.Sources.empty();
  scene.Finish("compare");
  if (outputDir.empty())
    throw UsageError("compare needs --output DIR");
  // Before any work: no output may be an input or another output; one lock
  // (DIR/compare.lock) per output folder (OutputFiles.h).
  scene.AddInputs(plan);
  plan.Input(o.MeasuredPath, "--measured");
  plan.Output(outputDir + "/compare.vtm", "--output");
  plan.Output(o.JsonPath, "--json", false);
  {
    std::error_code ec;
    const auto pieces = std::filesystem::symlink_status(outputDir + "/compare", ec);
    if (std::filesystem::exists(pieces) && !std::filesystem::is_directory(pieces))
      throw UsageError("--output " + outputDir + ": '" + outputDir +
        "/compare' exists and is not a folder (compare writes the pieces of compare.vtm "
        "there): move it or choose another --output");
  }
  plan.Check();
  std::vector<std::string> solvers = SplitList(o.SolverList);
  if (solvers.empty())
    throw UsageError("--solvers lists no solver");
  // The measured curves, read before minutes of solving (fail fast).
  if (!o.MeasuredPath.empty())
  {
    if (o.Optics.TimeGates.Count == 0 || o.Optics.Detectors.empty())
      throw UsageError("--measured needs --time-gates and at least one --detector");
    measured = ReadMeasuredTpsf(o.MeasuredPath, o.Optics.Detectors.size());
  }
  // Before minutes of solving: the pictures need an X server (one
  // connection held for the whole run, see Pictures.h).
  if (!o.NoPictures)
    RequirePictureDisplay("--no-png");
  // The names were checked while parsing (DiffusionSolverCheck).
  std::vector<std::string> order = { o.Reference };
  for (const std::string& name : solvers)
    if (name != o.Reference)
      order.push_back(name);
  // One problem for every solver: the default collimated model is the core
  // table's for divergence and fem only (vtkSolveDiffusion), so with any
  // other diffusion solver every solver solves the surface model.
  if (scene.Collimated == "default")
  {
    for (const std::string& name : order)
    {
      const auto& traits = translucency::GetDiffusionSolverRegistry().Get(name).Properties;
      if (!traits.UnknownsAtVertices && !traits.IsStochastic)
      {
        scene.Collimated = "surface";
        std::cerr << "translucency: note: the collimated model is surface for every solver "
                     "(the default by light kind is for divergence and fem; " +
            name + " solves the surface model)\n";
        break;
      }
    }
  }
  return order;
}

/// Compare: QuadGraph's eq. 5 does not conserve light on graded meshes
/// (issue 22, Documentation/Solvers.md): say so when this command grades the
/// mesh.
void WarnGradedQuadGraph(const SceneOptions& scene, const std::vector<std::string>& order)
{
  const std::string extension =
    translucency::ToLower(std::filesystem::path(scene.MeshPath).extension().string());
  const bool surface =
    extension == ".ply" || extension == ".stl" || extension == ".obj" || extension == ".vtp";
  if (surface && !scene.UniformSizing &&
    std::find(order.begin(), order.end(), "quadgraph") != order.end())
    std::cerr << "translucency: warning: quadgraph on a graded mesh (cells near the surface "
                 "smaller than inside): its eq. 5 does not conserve light there and its error "
                 "stalls (25-29 % on a sphere, vs 7-10 % on uniform meshes); add --uniform-size "
                 "(Documentation/Solvers.md)\n";
}

/// Compare: every solver on the lit mesh, the reference first.
void SolveAll(CompareRun& run)
{
  const CompareOptions& o = run.Options;
  for (size_t k = 0; k < run.Order.size(); ++k)
  {
    const std::string& name = run.Order[k];
    Progress("solving with " + name + " (" + std::to_string(k + 1) + " of " +
      std::to_string(run.Order.size()) + ")...");
    run.Results[name] = RunSolver(name, run.Lit, o.RelTol, 20000, o.GridSpacing, o.Photons,
      o.Seed, o.Readout.IsPaper(), o.Optics);
  }
}

/// Compare, with time gates and detectors: the TPSF of every solver at every
/// detector on the same gates, the measured curves and the closed form.
void CollectCompareTpsf(CompareRun& run, const MeasuredFile& measured)
{
  const CompareOptions& o = run.Options;
  run.TimeResolved = o.Optics.TimeGates.Count > 0 && !o.Optics.Detectors.empty();
  if (!run.TimeResolved)
    return;
  TpsfTable& tpsf = run.Tpsf;
  std::vector<vtkUnstructuredGrid*> volumes;
  std::vector<std::string> specs;
  for (const std::string& name : run.Order)
    volumes.push_back(run.Results[name].Volume);
  for (const DetectorSpec& d : o.Optics.Detectors)
    specs.push_back(d.Spec);
  tpsf = CollectTpsf(run.Order, volumes, specs);
  if (!o.MeasuredPath.empty())
    AddMeasured(tpsf, measured, o.MeasuredNormalise, o.Reference, o.Image.Channel);
  if (!o.NoClosedForm)
  {
    AddClosedForm(tpsf, run.Lit, run.Results[o.Reference].Volume, o.Optics.Sources,
      o.Optics.TimeGates);
    if (!tpsf.ClosedForm.SkipReason.empty())
      std::cout << "closed form not drawn: " << tpsf.ClosedForm.SkipReason << "\n";
    else
      for (size_t d = 0; d < tpsf.ClosedForm.DetectorSkipReasons.size(); ++d)
        if (!tpsf.ClosedForm.DetectorSkipReasons[d].empty())
          std::cout << "closed form not drawn for detector " << d + 1 << " (" << specs[d]
                    << "): " << tpsf.ClosedForm.DetectorSkipReasons[d] << "\n";
  }
}

/// Compare, Monte Carlo: the mean relative standard error of its boundary
/// fluence (`se` its per-point standard error on the volume).
double MeanRelativeStandardError(const SolverResult& r, vtkDataArray* se)
{
  auto* ids =
    vtkIdTypeArray::SafeDownCast(r.Surface->GetPointData()->GetArray("vtkOriginalPointIds"));
  vtkDataArray* phi = r.Surface->GetPointData()->GetArray("Fluence");
  double sum = 0.0;
  long long count = 0;
  for (vtkIdType k = 0; k < ids->GetNumberOfTuples(); ++k)
    for (int c = 0; c < 3; ++c)
      if (phi->GetComponent(k, c) > 0)
      {
        sum += se->GetComponent(ids->GetValue(k), c) / phi->GetComponent(k, c);
        ++count;
      }
  return count ? sum / count : 0.0;
}

/// Compare: every solver's errors against the reference (boundary points,
/// all channels) into its statistics, its error arrays and the table; the
/// error pictures' scale (99th percentile of |error| over the solvers).
void CompareWithReference(CompareRun& run)
{
  const std::string& reference = run.Options.Reference;
  const SolverResult& ref = run.Results[reference];
  vtkDataArray* refFluence = ref.Surface->GetPointData()->GetArray("Fluence");
  vtkSmartPointer<vtkDataArray> refRadiance = SurfaceRadiance(ref);
  for (const std::string& name : run.Order)
  {
    SolverResult& r = run.Results[name];
    double fMax, fRms, lMax, lRms;
    std::vector<double> perPoint;
    vtkDataArray* fluence = r.Surface->GetPointData()->GetArray("Fluence");
    RelativeError(fluence, refFluence, fMax, fRms);
    vtkSmartPointer<vtkDataArray> radiance = SurfaceRadiance(r);
    RelativeError(radiance, refRadiance, lMax, lRms, &perPoint);
    vtkNew<vtkDoubleArray> errorArray;
    errorArray->SetName("RelativeRadianceError");
    errorArray->SetNumberOfTuples(static_cast<vtkIdType>(perPoint.size()));
    std::copy(perPoint.begin(), perPoint.end(), errorArray->GetPointer(0));
    r.Surface->GetPointData()->AddArray(errorArray);
    if (name != reference)
    {
      // The error map: signed, Monte Carlo's noisy points masked, on the
      // solver's own symmetric scale (99th percentile of |error|); the
      // overview puts every map on the largest of these scales.
      vtkSmartPointer<vtkDoubleArray> signedError =
        SignedError(radiance, refRadiance, run.Options.Image.Channel);
      const long long masked =
        MaskNoisyMonteCarloPoints(signedError, { &r, &ref }, run.Options.Image.Channel);
      r.Surface->GetPointData()->AddArray(signedError);
      const double scale = AbsolutePercentile99(signedError);
      run.ErrorScale = std::max(run.ErrorScale, scale);
      r.Stats["error_map"] = { { "picture", name + "_error.png" },
        { "channel", std::string(1, "RGB"[run.Options.Image.Channel]) },
        { "scale_percent", scale }, { "masked_points", masked },
        { "points", static_cast<long long>(signedError->GetNumberOfTuples()) } };
    }
    r.Stats["fluence_relative_error"] = { { "max", fMax }, { "rms", fRms } };
    r.Stats["radiance_relative_error"] = { { "max", lMax }, { "rms", lRms } };
    r.Stats["fluence_relative_error_per_channel"] = ChannelErrors(fluence, refFluence);
    r.Stats["radiance_relative_error_per_channel"] = ChannelErrors(radiance, refRadiance);
    r.Stats["wall_ms"] = r.WallMs;
    r.Stats["reference"] = reference;
    if (vtkDataArray* se = r.Volume->GetPointData()->GetArray("FluenceStandardError"))
      r.Stats["fluence_mean_relative_standard_error"] = MeanRelativeStandardError(r, se);
    run.Table.push_back(r.Stats);
  }
  for (json& row : run.Table)
    if (row.contains("error_map"))
      row["error_map"]["shared_scale_percent"] = run.ErrorScale;
}

/// Compare: against Monte Carlo, when it ran, z-scores by its standard error.
void CompareWithMonteCarlo(CompareRun& run)
{
  const SolverResult* monteCarlo = nullptr;
  for (const std::string& name : run.Order)
    if (run.Results[name].Volume->GetPointData()->GetArray("FluenceStandardError"))
      monteCarlo = &run.Results[name];
  if (monteCarlo)
    for (json& s : run.Table)
      if (s["solver"] != monteCarlo->Name)
        s["fluence_against_montecarlo"] = AgainstMonteCarlo(
          run.Results[s["solver"].get<std::string>()].Surface->GetPointData()->GetArray(
            "Fluence"),
          *monteCarlo, MaxMonteCarloRelativeSE);
  run.MonteCarlo = monteCarlo;
}

/// Compare, on stdout: the table of errors and costs, then the power balance.
void PrintErrorTable(const CompareRun& run)
{
  std::cout << "mesh: " << run.Lit->GetNumberOfPoints() << " points, "
            << run.Lit->GetNumberOfCells() << " tets; reference: " << run.Options.Reference
            << "\n";
  std::cout << LightsLine(run.Options.Scene) << "\n\n";
  std::cout << "  solver      unknowns      nnz  memory(MB)  setup(ms)  solve(ms)  iters(R)"
               "  fluence err max/rms   radiance err max/rms\n";
  for (const json& s : run.Table)
  {
    std::cout << "  " << std::left << std::setw(10) << s["solver"].get<std::string>() << std::right
              << std::setw(10) << s["unknowns"].get<long long>() << std::setw(10)
              << s["nonzeros"].get<long long>() << std::fixed << std::setprecision(1)
              << std::setw(11) << s["memory_bytes"].get<double>() / 1048576.0 << std::setw(11)
              << s["setup_ms"].get<double>() << std::setw(11) << s["solve_ms"].get<double>()
              << std::setw(10) << s["iterations"][0].get<int>() << std::setprecision(2)
              << std::setw(10) << 100 * s["fluence_relative_error"]["max"].get<double>() << "%/"
              << std::setw(6) << 100 * s["fluence_relative_error"]["rms"].get<double>() << "%"
              << std::setw(11) << 100 * s["radiance_relative_error"]["max"].get<double>() << "%/"
              << std::setw(6) << 100 * s["radiance_relative_error"]["rms"].get<double>() << "%"
              << std::defaultfloat;
    if (s.contains("fluence_mean_relative_standard_error"))
      std::cout << "  (MC standard error " << std::setprecision(2)
                << 100 * s["fluence_mean_relative_standard_error"].get<double>() << "%)";
    std::cout << "\n";
  }
  std::cout << "\npower balance (W, channel R; JSON power_W has every channel):\n"
               "    solver              injected     absorbed      escaped  imbalance\n";
  for (const json& s : run.Table)
  {
    if (s["power_W"].is_null())
      continue;
    const json& p = s["power_W"]["R"];
    std::cout << "    " << std::left << std::setw(18) << s["solver"].get<std::string>()
              << std::right << std::scientific << std::setprecision(4) << std::setw(10)
              << p["injected"].get<double>() << std::setw(13) << p["absorbed"].get<double>()
              << std::setw(13) << p["escaped"].get<double>() << std::setprecision(2)
              << std::setw(11) << p["imbalance"].get<double>() << std::defaultfloat << "\n";
  }
}

/// Compare, on stdout, when Monte Carlo ran: the table against it.
void PrintMonteCarloTable(const CompareRun& run)
{
  const SolverResult* monteCarlo = run.MonteCarlo;
  if (!monteCarlo)
    return;
  std::cout << "\n  against " << monteCarlo->Name
            << " (boundary fluence; points with its relative standard error > 10 % masked):\n"
               "  solver      z RMS R/G/B          |z| > 3 R/G/B        rel. RMS R/G/B\n";
  for (const json& s : run.Table)
  {
    if (!s.contains("fluence_against_montecarlo"))
      continue;
    const json& a = s["fluence_against_montecarlo"];
    std::cout << "  " << std::left << std::setw(10) << s["solver"].get<std::string>()
              << std::right << std::fixed << std::setprecision(2);
    for (const char* key : { "z_rms", "fraction_abs_z_above_3", "relative_rms" })
    {
      std::cout << "  ";
      for (const char* c : { "R", "G", "B" })
        std::cout << std::setw(6) << a[c][key].get<double>() * (key[0] == 'z' ? 1.0 : 100.0)
                  << (key[0] == 'z' ? " " : "%");
    }
    std::cout << std::defaultfloat << "\n";
  }
  if (run.Options.Readout.IsPaper())
    std::cout << "  note: radiance against " << monteCarlo->Name
              << " with --radiance-readout paper differs by about eta^2 by the read-out\n"
                 "  convention (TransCut eq. 3), not by an error (Documentation/Solvers.md)\n";
}

/// Compare: the JSON report (provenance, mesh, the table, the TPSF).
json CompareReport(const CompareRun& run)
{
  const CompareOptions& o = run.Options;
  json report;
  report["provenance"] = Provenance(o.App);
  report["provenance"]["scene"] = SceneProvenance(o.Scene);
  report["provenance"]["seed"] = o.Seed;
  report["mesh"] = o.Scene.MeshPath;
  report["points"] = run.Lit->GetNumberOfPoints();
  report["tets"] = run.Lit->GetNumberOfCells();
  report["reference"] = o.Reference;
  report["solvers"] = run.Table;
  if (run.TimeResolved)
    report["tpsf"] = TpsfJson(run.Tpsf);
  return report;
}

/// Compare: the multiblock of the results, the volume with every solver's
/// fluence (block 0), then one surface per solver.
vtkSmartPointer<vtkMultiBlockDataSet> CompareBlocks(CompareRun& run)
{
  auto blocks = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  vtkNew<vtkUnstructuredGrid> volume;
  volume->ShallowCopy(run.Lit);
  for (const std::string& name : run.Order)
  {
    vtkDataArray* phi = run.Results[name].Volume->GetPointData()->GetArray("Fluence");
    vtkSmartPointer<vtkDataArray> copy = vtk::TakeSmartPointer(phi->NewInstance());
    copy->DeepCopy(phi);
    copy->SetName(("Fluence_" + name).c_str());
    volume->GetPointData()->AddArray(copy);
  }
  blocks->SetBlock(0, volume);
  blocks->GetMetaData(0u)->Set(vtkMultiBlockDataSet::NAME(), "volume");
  unsigned int block = 1;
  for (const std::string& name : run.Order)
  {
    blocks->SetBlock(block, run.Results[name].Surface);
    blocks->GetMetaData(block)->Set(vtkMultiBlockDataSet::NAME(), name.c_str());
    ++block;
  }
  return blocks;
}

/// Compare: DIR/compare.vtm and its folder of pieces. The .vtm refers to a
/// folder of pieces next to it: write both into a staging folder of a unique
/// name made by this run (mkdtemp), then move them into place: each piece
/// renamed into DIR/compare/ (over a piece of the same name only), then
/// compare.vtm. Removed: only what this run wrote; whatever else DIR/compare/
/// holds stays.
void WriteStagedMultiblock(vtkMultiBlockDataSet* blocks, const std::string& outputDir)
{
  namespace fs = std::filesystem;
  const unsigned int block = blocks->GetNumberOfBlocks();
  const fs::path dir(outputDir);
  std::string name = (dir / ".compare-XXXXXX").string();
  if (!mkdtemp(&name[0]))
    throw translucency::Error("cannot create a staging folder in '" + outputDir + "': " +
      std::strerror(errno));
  const fs::path staging(name), stagingPieces = staging / "compare";
  // What the writer makes (compare/compare_<block>.vtu|vtp), for removal on a signal.
  std::vector<int> slots = { RegisterCleanup(staging.string(), true),
    RegisterCleanup(stagingPieces.string(), true),
    RegisterCleanup((staging / "compare.vtm").string()) };
  for (unsigned int b = 0; b < block; ++b)
    for (const char* ext : { ".vtu", ".vtp" })
      slots.push_back(RegisterCleanup(
        (stagingPieces / ("compare_" + std::to_string(b) + ext)).string()));
  std::vector<fs::path> written; // the files this run made in the staging folder
  const auto removeStaging = [&]() {
    std::error_code ec;
    for (const fs::path& f : written)
      fs::remove(f, ec);
    fs::remove(staging / "compare.vtm", ec);
    fs::remove(stagingPieces, ec); // only if empty
    fs::remove(staging, ec);       // only if empty
    for (int slot : slots)
      UnregisterCleanup(slot);
  };
  vtkNew<vtkXMLMultiBlockDataWriter> writer;
  writer->SetInputData(blocks);
  writer->SetFileName((staging / "compare.vtm").c_str());
  ConfigureXmlWriter(writer);
  const bool wrote = writer->Write() != 0;
  std::error_code ec;
  for (fs::directory_iterator it(stagingPieces, ec), end; !ec && it != end; it.increment(ec))
    written.push_back(it->path());
  if (!wrote)
  {
    removeStaging();
    throw translucency::Error("cannot write '" + outputDir + "/compare.vtm'");
  }
  fs::create_directory(dir / "compare", ec);
  ec.clear();
  for (const fs::path& f : written)
  {
    fs::rename(f, dir / "compare" / f.filename(), ec);
    if (ec)
      break;
  }
  if (!ec)
    fs::rename(staging / "compare.vtm", dir / "compare.vtm", ec);
  if (ec)
  {
    removeStaging();
    throw translucency::Error("cannot move the results into '" + outputDir + "': " + ec.message());
  }
  written.clear();
  removeStaging();
}

/// Compare: the files of the output folder (tpsf.csv with time gates, the
/// .vtm multiblock).
void WriteCompareFiles(CompareRun& run)
{
  const std::string& outputDir = run.Options.OutputDir;
  std::string error;
  if (run.TimeResolved)
  {
    EnsureParentDirectory(outputDir + "/tpsf.csv");
    if (!WriteText(outputDir + "/tpsf.csv", TpsfCsv(run.Tpsf), error))
      throw translucency::Error(error);
  }
  EnsureParentDirectory(outputDir + "/compare.vtm");
  vtkSmartPointer<vtkMultiBlockDataSet> blocks = CompareBlocks(run);
  WriteStagedMultiblock(blocks, outputDir);
}

/// A symmetric error scale (percent) for the pictures: `scale`, or 1 % when
/// the errors are all zero (a picture needs a range).
double PictureScale(double scale)
{
  return scale > 0 ? scale : 1.0;
}

/// Compare, pictures: side by side in one PNG (the overview), `pngs` read
/// back and appended left to right; the parts are removed.
void AppendPictures(const std::vector<std::string>& pngs, const std::string& fileName)
{
  vtkNew<vtkImageAppend> append;
  append->SetAppendAxis(0);
  for (const std::string& png : pngs)
  {
    vtkNew<vtkPNGReader> reader;
    reader->SetFileName(png.c_str());
    reader->Update();
    vtkNew<vtkImageData> image;
    image->DeepCopy(reader->GetOutput());
    append->AddInputData(image);
  }
  append->Update();
  const std::string temporary = fileName + ".part.png";
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(temporary.c_str());
  writer->SetInputConnection(append->GetOutputPort());
  writer->Write();
  std::error_code ec;
  for (const std::string& png : pngs)
    std::filesystem::remove(png, ec);
  std::filesystem::rename(temporary, fileName, ec);
  if (ec || writer->GetErrorCode() != 0)
    throw translucency::Error("cannot write " + fileName);
}

/// Compare, pictures: the radiance of every solver on one exposure (the
/// reference's); the error map of every other solver against the reference
/// on its own symmetric scale (the 99th percentile of its |error|: a small
/// error is not flat grey beside a large one), Monte Carlo's noisy points
/// grey; and errors_overview.png, every error map side by side on the
/// shared scale (the largest of them). The reference gets no error map.
void WriteSolverPictures(CompareRun& run)
{
  const CompareOptions& o = run.Options;
  const RadianceImageOptions& image = o.Image;
  const std::string& reference = o.Reference;
  const std::string& outputDir = o.OutputDir;
  std::string error;
  vtkNew<vtkPolyData> refSurface;
  refSurface->ShallowCopy(run.Results[reference].Surface);
  const double exposure = ToneMapRadiance(refSurface, image.Exposure);
  RadianceImageOptions shared = image;
  shared.Exposure = exposure;
  const double sharedScale = PictureScale(run.ErrorScale);
  static const char* channelNames[3] = { "R", "G", "B" };
  const std::string channel = channelNames[image.Channel];
  std::vector<std::string> overview;
  for (const std::string& name : run.Order)
  {
    SolverResult& r = run.Results[name];
    vtkNew<vtkPolyData> surface;
    surface->ShallowCopy(r.Surface);
    vtkSmartPointer<vtkDataArray> radiance = SurfaceRadiance(r);
    surface->GetPointData()->AddArray(radiance); // the tallied one for Monte Carlo
    surface->GetPointData()->RemoveArray("RadianceRGB");
    if (!WriteRadiancePNG(surface, shared, outputDir + "/" + name + "_radiance.png", error))
      throw translucency::Error(error);
    if (name == reference)
      continue;
    const json& map = r.Stats["error_map"];
    const double own = PictureScale(map["scale_percent"].get<double>());
    const long long masked = map["masked_points"].get<long long>();
    // Short captions: the pictures may be small (--size 320x240).
    const std::string maskNote = masked > 0 ? "; grey: noisy MC" : std::string();
    const std::string quantity = "radiance " + channel + " error, " + name + " - " + reference;
    std::ostringstream caption;
    caption << name << " vs " << reference << ", own scale" << maskNote;
    const std::string part = outputDir + "/" + name + "_error_shared.part.png";
    if (!WriteScalarMapPNG(surface, "SignedRelativeRadianceError", -own, own, quantity, "%",
          caption.str(), image, outputDir + "/" + name + "_error.png", error) ||
      !WriteScalarMapPNG(surface, "SignedRelativeRadianceError", -sharedScale, sharedScale,
        quantity, "%", name + " vs " + reference + ", shared scale" + maskNote, image,
        part, error))
      throw translucency::Error(error);
    overview.push_back(part);
  }
  if (!overview.empty())
    AppendPictures(overview, outputDir + "/errors_overview.png");
  if (run.TimeResolved)
  {
    const TpsfTable& tpsf = run.Tpsf;
    std::ostringstream caption;
    caption << "TPSF per detector, " << o.Optics.TimeGates.Count << " gates of "
            << (o.Optics.TimeGates.End - o.Optics.TimeGates.Start) / o.Optics.TimeGates.Count
            << " ns; lines: diffusion, markers: Monte Carlo";
    if (!tpsf.ClosedForm.Name.empty() && tpsf.ClosedForm.SkipReason.empty())
      caption << ", grey dashed: closed form";
    if (!tpsf.Measured.Series.empty())
      caption << ", black: measured";
    if (!WriteTpsfPNG(tpsf, image.Channel, caption.str(), outputDir + "/tpsf.png", error))
      throw translucency::Error(error);
  }
}

/// Compare, pictures: the error against wall time of the deterministic
/// solvers (a plot, and the curves added to the JSON report, written again).
void WriteErrorVersusTime(CompareRun& run, json& report)
{
  const CompareOptions& o = run.Options;
  vtkDataArray* refFluence =
    run.Results[o.Reference].Surface->GetPointData()->GetArray("Fluence");
  std::string error;
  std::vector<PlotSeries> curves;
  int unconverged = 0;
  // A stochastic solver has no error-vs-tolerance curve; a time-resolved or
  // frequency-domain run has none either (the iteration limit of its many
  // solves is not a measure of its cost).
  const bool steady = o.Optics.TimeGates.Count == 0 && o.Optics.Frequency == 0.0;
  // The reference is left out: its error against itself is 0 by definition
  // (drawn at the plot's floor, it squashed the other curves).
  for (const std::string& name : run.Order)
    if (steady && name != o.Reference &&
      !translucency::GetDiffusionSolverRegistry().Get(name).Properties.IsStochastic)
    {
      Progress("error against time: " + name + "...");
      curves.push_back(
        ErrorVersusTime(name, run.Lit, refFluence, o.GridSpacing, o.Optics, unconverged));
    }
  if (unconverged > 0)
    Progress("error against time: " + std::to_string(unconverged) +
      " solves stopped before convergence on purpose (iteration limits 1, 2, 4, ...)");
  if (!curves.empty() &&
    !WritePlotPNG(curves, "wall time (ms)", "RMS relative error of boundary fluence",
      o.OutputDir + "/error_vs_time.png", error))
    throw translucency::Error(error);
  json plot;
  for (const PlotSeries& c : curves)
    plot[c.Name] = { { "ms", c.X }, { "rms_error", c.Y } };
  for (json& s : report["solvers"])
    if (plot.contains(s["solver"].get<std::string>()))
      s["error_vs_time"] = plot[s["solver"].get<std::string>()];
  if (!o.JsonPath.empty())
    WriteJson(o.JsonPath, report);
}

int Compare(CompareOptions& o)
{
  CompareRun run(o);
  OutputPlan plan; // its locks last until the end of the run
  MeasuredFile measured;
  run.Order = CheckAndOrder(o, plan, measured);
  WarnGradedQuadGraph(o.Scene, run.Order);
  std::vector<Stage> stages;
  double topologyMs = 0.0;
  run.Lit = BuildLitMesh(o.Scene, stages, topologyMs);
  SolveAll(run);
  CollectCompareTpsf(run, measured);
  CompareWithReference(run);
  CompareWithMonteCarlo(run);

  // Table first, flushed (a pipe buffers it otherwise), then the JSON: both
  // before the pictures, so a failure there loses neither.
  PrintErrorTable(run);
  PrintMonteCarloTable(run);
  std::cout.flush();
  json report = CompareReport(run);
  if (!o.JsonPath.empty())
    WriteJson(o.JsonPath, report);

  WriteCompareFiles(run);
  if (!o.NoPictures)
  {
    Progress("writing the pictures...");
    WriteSolverPictures(run);
    WriteErrorVersusTime(run, report);
  }
  return 0;
}

} // namespace

Command AddCompareCommand(CLI::App& app)
{
  auto o = std::make_shared<CompareOptions>();
  CLI::App* c =
    app.add_subcommand("compare", "Run several solvers on the same problem and lay the results side by side."
    "\n\nusage: translucency compare --mesh FILE [scene options] --output DIR [options]");
  o->App = c;
  AddSceneOptions(c, o->Scene);
  c->add_option("--solvers", o->SolverList, "from " + WrapNames(translucency::GetDiffusionSolverNames()))
    ->type_name("A,B,...")
    ->capture_default_str()
    ->check(DiffusionSolverCheck("--solvers"));
  c->add_option("--reference", o->Reference,
     "the solver the others are measured against (montecarlo\n"
     "for the ground truth); run even if not listed")
    ->type_name("NAME")
    ->capture_default_str()
    ->check(DiffusionSolverCheck("--reference"));
  AddGridAndPhotonOptions(c, o->GridSpacing, o->Photons);
  AddNumber(c, "--seed", o->Seed, "random seed of montecarlo", "S");
  AddNumber(c, "--rel-tol", o->RelTol, "relative residual of the iterative solvers", "T",
    [](double t) { return t > 0 && t < 1; }, "--rel-tol must be in (0, 1)");
  c->add_option("--output", o->OutputDir,
     "<solver>_radiance.png, <solver>_error.png (every solver but\n"
     "the reference, on its own scale), errors_overview.png (all\n"
     "error maps on one scale), error_vs_time.png,\n"
     "compare.vtm (needs X for the PNGs: xvfb-run -a); with\n"
     "--time-gates and --detector: tpsf.png (every solver's TPSF\n"
     "per detector, channel --channel) and tpsf.csv (its data)")
    ->type_name("DIR");
  c->add_flag("--no-png", o->NoPictures, "skip the pictures and the plot (no X needed)");
  AddRadianceReadoutOption(c, o->Readout);
  c->add_option("--json", o->JsonPath,
     "the table as JSON (with provenance), written before the\n"
     "pictures and again with the error-vs-time curves")->type_name("FILE");
  AddImageOptions(c, o->Image);
  AddDiffuseOpticsOptions(c, o->Optics);
  c->add_option("--measured", o->MeasuredPath,
     "a measured TPSF to overlay (CSV: header t_ns or t_ps, then\n"
     "one column per --detector, in their order; needs\n"
     "--time-gates); on tpsf.png and in tpsf.csv and the JSON")
    ->type_name("FILE");
  c->add_option("--measured-normalise", o->MeasuredNormalise,
     "scale the measured curves to the reference solver's exitance\n"
     "(channel --channel) over the gates they overlap: area, peak,\n"
     "or none (as in the file)")
    ->type_name("MODE")
    ->capture_default_str()
    ->check(CLI::IsMember({ "area", "peak", "none" }));
  c->add_flag("--no-closed-form", o->NoClosedForm,
    "leave the closed form (Patterson et al. 1989) off the TPSF plot");
  return { c, [o]() { return Compare(*o); } };
}

} // namespace translucency_app
