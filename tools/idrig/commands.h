#pragma once
// Each command group of `idrig` registers its subcommands on the top-level app.
#include <CLI/CLI.hpp>

namespace idrig {
void RegisterIdentifyCommand(CLI::App& app);
void RegisterExampleCommand(CLI::App& app);
void RegisterSimulateCommand(CLI::App& app);
void RegisterExciteCommand(CLI::App& app);  // cmd_excite.cc
// The distributed service (docs/services.md). SetCommandLine keeps argv so that `idrig demo`
// can re-run itself inside a network namespace.
void RegisterDemoCommand(CLI::App& app);         // cmd_demo.cc
void SetCommandLine(int argc, char** argv);      // cmd_demo.cc
void RegisterExperimentCommands(CLI::App& app);  // cmd_experiment.cc
void RegisterModelsCommands(CLI::App& app);      // cmd_models.cc
void RegisterStatusCommand(CLI::App& app);       // cmd_status_spy.cc
void RegisterSpyCommand(CLI::App& app);          // cmd_status_spy.cc
void RegisterGapCommand(CLI::App& app);     // cmd_gap.cc
}  // namespace idrig
