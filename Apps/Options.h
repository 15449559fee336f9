/**
 * @file Options.h
 * @brief How the `translucency` commands declare their options (CLI11): a
 * command is a subcommand of the one CLI::App plus the function that runs it;
 * number and choice options are declared with their check in one call; the
 * option groups several commands share (scene, picture, solver) are declared
 * by one function each. The help text is generated from these declarations.
 *
 * Checks that fail throw UsageError with a one-line message naming the
 * option (exit code 2), so the message is the same whether the check is a
 * validator (run while parsing) or a check across options after parsing.
 */
#pragma once

#include "Utilities.h"

#include "ResourceLimits.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <type_traits>
#include <vector>

namespace translucency_app
{
struct RadianceImageOptions;
struct SceneOptions;

/// One command: its subcommand of the CLI::App and what runs it (exit code)
/// once the command line is parsed.
struct Command
{
  CLI::App* App = nullptr;
  std::function<int()> Run;
};

/// The commands (one file each: RenderCommand.cxx, CompareCommand.cxx,
/// BenchCommand.cxx, RadiosityCommand.cxx, AcquireCommand.cxx).
Command AddRenderCommand(CLI::App& app);
Command AddCompareCommand(CLI::App& app);
Command AddBenchCommand(CLI::App& app);
Command AddRadiosityCommand(CLI::App& app);
Command AddAcquireCommand(CLI::App& app);

/// A validator: the value is one finite number (else ParseNumbers' message
/// naming `option`) and, if `valid` is given, valid(x) holds (else UsageError(failure)).
CLI::Validator NumberCheck(const std::string& option, std::function<bool(double)> valid = nullptr,
  const std::string& failure = std::string());

/// `value` as T: a double as is; an integer type only if `value` is a whole
/// number in its range (else UsageError naming `option` and the value).
template <class T>
T ToNumber(double value, const std::string& option)
{
  if constexpr (std::is_integral<T>::value)
  {
    try
    {
      return translucency::CheckedInteger<T>(value, option);
    }
    catch (const translucency::Error& e)
    {
      throw UsageError(e.what());
    }
  }
  else
  {
    return static_cast<T>(value);
  }
}

/// A validator: the value is one of `choices` (else UsageError
/// "<option>: 'x' is not a, b or c").
CLI::Validator OneOf(const std::string& option, const std::vector<std::string>& choices);

/// "a, b or c".
std::string JoinOr(const std::vector<std::string>& names);

/// "default" and the names of the core's collimated-model table (the
/// choices of render's and bench --pipeline's --collimated).
std::vector<std::string> CollimatedModelChoices();

/// `names` joined by ", " in lines of at most `width` characters (for help text).
std::string WrapNames(const std::vector<std::string>& names, size_t width = 60);

/// Shortest round-trip text of a default value (1e-6, not 1e-06 or 0.000001).
std::string DefaultText(double value);

/// A one-number option into `target` (double or an integer type: the text is
/// read as a double, so 1e6 is a valid count), its current value shown as the
/// default, checked by NumberCheck(name, valid, failure). For an integer
/// target the value must first be a whole number in the type's range (else
/// UsageError "<name>: <value> is not a whole number from <min> to <max>"):
/// a cast of 1e30 to an integer is undefined behaviour.
template <class T>
CLI::Option* AddNumber(CLI::App* app, const std::string& name, T& target, const std::string& help,
  const std::string& typeName, std::function<bool(double)> valid = nullptr,
  const std::string& failure = std::string())
{
  T* value = &target;
  CLI::Option* option =
    app
      ->add_option_function<std::string>(
        name,
        [value, name](const std::string& text) {
          *value = ToNumber<T>(ParseNumbers(text, name).at(0), name);
        },
        help)
      ->type_name(typeName)
      ->default_str(DefaultText(static_cast<double>(target)));
  if (std::is_integral<T>::value)
  {
    option->check(CLI::Validator(
      [name](std::string& text) {
        const std::vector<double> v = ParseNumbers(text, name);
        if (v.size() == 1)
        {
          ToNumber<T>(v[0], name);
        }
        return std::string();
      },
      ""));
  }
  return option->check(NumberCheck(name, std::move(valid), failure));
}

/// --memory-limit GiB (translucency::SetDefaultMemoryLimit) and --allow-long-runs
/// (translucency::SetLongRunsAllowed) on `command`, for the whole run.
void AddMemoryLimitOption(CLI::App* command);

/// --quiet on `command`: SetQuiet(true) (progress lines off; warnings stay).
void AddQuietOption(CLI::App* command);

/// A comma-separated list of numbers into `target`, with `count` numbers if
/// count > 0 (else UsageError(failure)).
CLI::Option* AddNumberList(CLI::App* app, const std::string& name, std::vector<double>& target,
  const std::string& help, const std::string& typeName, size_t count = 0,
  const std::string& failure = std::string());

/// The scene options of render and compare (group "Scene options"): --mesh,
/// --target-tets, --max-tet-volume, --quality, --material, --material-ids,
/// --light, --no-shadows, --uniform-samples, --paint, --cut-plane, --cut-stroke.
void AddSceneOptions(CLI::App* command, SceneOptions& scene);

/// The picture options of render and compare (group "Picture options"):
/// --view, --up, --size, --exposure.
void AddImageOptions(CLI::App* command, RadianceImageOptions& image);

/// The solver options of render and compare with the same meaning and
/// default: --grid-spacing (grid) and --photons (montecarlo).
void AddGridAndPhotonOptions(CLI::App* command, double& gridSpacing, long long& photons);

/// The radiance read-out of render and compare (translucency::RadianceReadout).
struct RadianceReadoutOption
{
  std::string Name = "energy-conserving"; ///< --radiance-readout
  bool NSquaredLaw = false;               ///< the earlier --n-squared-law flag
  /// True for "paper" (TransCut eq. 3 as printed), false for the default.
  bool IsPaper() const { return this->Name == "paper"; }
};

/// --radiance-readout energy-conserving|paper (default energy-conserving) and
/// the earlier --n-squared-law, kept as a synonym of the default (it excludes
/// --radiance-readout).
void AddRadianceReadoutOption(CLI::App* command, RadianceReadoutOption& readout);

/// A validator: the value (or each of a comma-separated list) names a
/// diffusion solver of translucency::GetDiffusionSolverNames(), any case.
CLI::Validator DiffusionSolverCheck(const std::string& option);

} // namespace translucency_app
