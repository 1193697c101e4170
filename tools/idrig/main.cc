// idrig: measurement and identification of dynamic systems on test rigs.
#include <CLI/CLI.hpp>

#include <iostream>
#include <stdexcept>

#include "tools/idrig/commands.h"
#include "tools/idrig/service_client.h"

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
    // --help and --version exit 0; every bad option or value is bad input: status 2.
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << "idrig: error: " << e.what() << "\n";
    return 2;
  } catch (const idrig::CommandFailure& e) {
    // A refusal, a failed job, a service that did not answer: the reason, status 1 (or its own).
    std::cerr << "idrig: " << e.what() << "\n";
    return e.code();
  } catch (const std::exception& e) {
    std::cerr << "idrig: failed: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
