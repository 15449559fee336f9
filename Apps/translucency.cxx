// translucency: command-line front end of the Translucency pipeline.
//
//   translucency render --mesh FILE [options]     surface/tet mesh -> fluence -> radiance -> PNG
//   translucency compare --mesh FILE [options]    every solver on one problem, side by side
//   translucency bench [options]                  assembly/solve medians at several mesh sizes
//   translucency radiosity --scene FILE.json ...  translucent radiosity of a scene
//   translucency acquire ...                      inverse diffusion from measured radiance
//   translucency --help | help [COMMAND]
//   translucency --version                        version and source revision
//
// Each command declares its options (CLI11) and runs itself (<Name>Command.cxx);
// this file builds the parser, prints the help and turns errors into exit
// codes: "translucency: error: ..." and 1, or "translucency: usage error: ..."
// and 2 for a mistake in the command line.

#include "Options.h"
#include "OutputFiles.h"
#include "Provenance.h"

#include "Error.h"

#include <vtkOutputWindow.h>

#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace
{
using namespace translucency_app;

/// CLI11's formatter without its "Usage:" line: each command's description
/// ends with its own usage lines, which say more.
class Formatter : public CLI::Formatter
{
public:
  std::string make_usage(const CLI::App*, std::string) const override { return ""; }
};

/// Every command's help, one after the other (what --help prints, whether
/// given alone or after a command).
std::string FullHelp(const std::vector<Command>& commands)
{
  std::string text = "usage: translucency <command> [options]\n"
                     "       translucency help [<command>]   the options of one command\n\n"
                     "Commands:\n";
  for (const Command& c : commands)
  {
    // The first paragraph of the description, indented.
    const std::string description = c.App->get_description();
    std::string summary;
    for (char ch : description.substr(0, description.find("\n\n")))
      summary += ch == '\n' ? std::string("\n") + std::string(13, ' ') : std::string(1, ch);
    text += "  " + c.App->get_name() + std::string(11 - c.App->get_name().size(), ' ') +
      summary + "\n";
  }
  for (const Command& c : commands)
  {
    text += "\n" + std::string(72, '-') + "\n" + c.App->help();
  }
  return text;
}
}

int main(int argc, char* argv[])
{
  // Filter messages are reported through observers, not VTK's output window.
  vtkOutputWindow::GetInstance()->SetDisplayModeToNever();
  // SIGINT/SIGTERM/SIGHUP remove the temporaries and locks of the outputs.
  InstallOutputCleanup();

  CLI::App app("Translucency: light diffusion in translucent objects", "translucency");
  app.formatter(std::make_shared<Formatter>());
  app.get_formatter()->column_width(30);
  app.require_subcommand(0, 1);
  std::vector<Command> commands = { AddRenderCommand(app), AddCompareCommand(app),
    AddBenchCommand(app), AddRadiosityCommand(app), AddAcquireCommand(app) };
  for (const Command& c : commands)
  {
    AddMemoryLimitOption(c.App);
    AddQuietOption(c.App);
  }
  for (const Command& c : commands)
    c.App->get_help_ptr()->group(""); // works, but not listed: every --help prints all
  bool version = false;
  app.add_flag("--version", version, "print the version and source revision");
  SetCommandLine(argc, argv);
  std::string helpTopic;
  CLI::App* help = app.add_subcommand("help", "Print the options of every command, or of one.");
  help->add_option("command", helpTopic, "a command")->check(CLI::IsMember([&commands]() {
    std::vector<std::string> names;
    for (const Command& c : commands)
      names.push_back(c.App->get_name());
    return names;
  }()));

  try
  {
    if (argc < 2)
    {
      std::cout << FullHelp(commands);
      return 2;
    }
    const std::string first = argv[1];
    bool known = first.rfind("-", 0) == 0;
    for (const CLI::App* c : app.get_subcommands({}))
      known = known || c->get_name() == first;
    if (!known)
    {
      throw UsageError(
        "unknown command '" + first + "' (render, compare, bench, radiosity or acquire)");
    }
    try
    {
      app.parse(argc, argv);
    }
    catch (const CLI::CallForHelp&)
    {
      std::cout << FullHelp(commands);
      return 0;
    }
    catch (const CLI::ExtrasError& e)
    {
      throw UsageError(std::string(e.what()) + " (see translucency help" +
        (first.rfind("-", 0) != 0 ? " " + first : std::string()) + ")");
    }
    catch (const CLI::ParseError& e)
    {
      throw UsageError(e.what());
    }
    if (version)
    {
      std::cout << VersionLine() << "\n";
      return 0;
    }
    if (help->parsed() || app.get_subcommands().empty())
    {
      if (helpTopic.empty())
        std::cout << FullHelp(commands);
      else
        std::cout << app.get_subcommand(helpTopic)->help();
      return app.get_subcommands().empty() ? 2 : 0;
    }
    for (const Command& c : commands)
    {
      if (c.App->parsed())
        return c.Run();
    }
    return 2;
  }
  catch (const UsageError& e)
  {
    // One line each, whatever bytes of a file the message quotes.
    std::cerr << "translucency: usage error: " << EscapeControl(e.what()) << "\n";
    return 2;
  }
  catch (const std::exception& e)
  {
    std::cerr << "translucency: error: " << EscapeControl(e.what()) << "\n";
    return 1;
  }
}
