#pragma once
// Each command group of `idrig` registers its subcommands on the top-level app.
#include <CLI/CLI.hpp>

namespace idrig {
void RegisterIdentifyCommand(CLI::App& app);
void RegisterExampleCommand(CLI::App& app);
void RegisterSimulateCommand(CLI::App& app);
void RegisterExciteCommand(CLI::App& app);  // cmd_excite.cc
// cmd_services.cc: demo, experiment, models, status, spy. SetCommandLine keeps argv so that
// `idrig demo` can re-run itself inside a network namespace.
void RegisterServiceCommands(CLI::App& app);
void SetCommandLine(int argc, char** argv);
void RegisterGapCommand(CLI::App& app);     // cmd_gap.cc
void RegisterServeCommand(CLI::App& app);   // cmd_serve.cc: the dashboard
}  // namespace idrig
