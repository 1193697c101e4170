// idrig: measurement and identification of dynamic systems on test rigs.
#include <CLI/CLI.hpp>

#include <iostream>
#include <stdexcept>

#include "tools/idrig/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"idrig - identify dynamic systems on test rigs (version " IDRIG_VERSION ")"};
  app.require_subcommand(1);
  app.set_version_flag("--version", IDRIG_VERSION);
  idrig::RegisterIdentifyCommand(app);
  idrig::RegisterExampleCommand(app);
  idrig::RegisterSimulateCommand(app);
  idrig::RegisterExciteCommand(app);
  idrig::RegisterDemoCommand(app);
  idrig::RegisterExperimentCommands(app);
  idrig::RegisterModelsCommands(app);
  idrig::RegisterStatusCommand(app);
  idrig::RegisterSpyCommand(app);
  idrig::SetCommandLine(argc, argv);
  idrig::RegisterGapCommand(app);
  idrig::RegisterServeCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::invalid_argument& e) {
    std::cerr << "idrig: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "idrig: failed: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
