// `idrig status` (the services' periodic status) and `idrig spy` (lcm-spy with idrig's types).
#include <unistd.h>

#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <memory>

#include "core/transport/channels.h"
#include "tools/idrig/commands.h"
#include "tools/idrig/model_print.h"
#include "tools/idrig/service_client.h"

#ifndef IDRIG_TYPES_JAR
#define IDRIG_TYPES_JAR ""
#endif

namespace idrig {

void RegisterStatusCommand(CLI::App& app) {
  // ---- status
  {
    struct Args {
      std::string url = DefaultLcmUrl();
      double seconds = 1.5;
    };
    auto args = std::make_shared<Args>();
    auto* cmd = app.add_subcommand("status", "list the running services (their periodic status)");
    cmd->add_option("--url", args->url, "LCM URL");
    cmd->add_option("--seconds", args->seconds, "how long to listen");
    cmd->callback([args] {
      ServiceClient client(args->url);
      client.Spin(static_cast<int>(args->seconds * 1000));
      for (const auto& [id, s] : client.services())
        std::cout << std::left << std::setw(28) << id << std::setw(8) << s.state << " host "
                  << s.host << " pid " << s.pid << " up " << Number(s.uptime_s, 3) << " s  recv "
                  << s.received << " sent " << s.published << " dropped " << s.dropped << " bad "
                  << (s.undecodable + s.foreign + s.oversized) << " refused "
                  << (s.unsigned_count + s.forged + s.replayed + s.over_limit) << "\n    "
                  << s.details_json << "\n";
      if (client.services().empty())
        std::cout << "no service status heard within " << args->seconds << " s\n";
    });
  }
}

void RegisterSpyCommand(CLI::App& app) {
  // ---- spy
  {
    auto url = std::make_shared<std::string>(DefaultLcmUrl());
    auto* cmd = app.add_subcommand(
        "spy",
        "lcm-spy with idrig's message types (java directly: Debian's wrapper fails on Java 17)");
    cmd->add_option("--url", *url, "LCM URL");
    cmd->callback([url] {
      std::string jar = IDRIG_TYPES_JAR;
      if (jar.empty() || access(jar.c_str(), R_OK) != 0)
        jar = ExecutableDir() + "/../share/java/idrig_lcmtypes.jar";
      if (access(jar.c_str(), R_OK) != 0)
        throw std::runtime_error("idrig's types jar is not built (needs a JDK): " + jar);
      const std::string cp = "/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar:" + jar;
      const std::string url_arg = "--lcm-url=" + *url;
      std::vector<std::string> a = {"java", "-cp", cp, "lcm.spy.Spy", url_arg};
      // lcm-spy is a window: without a display, run it under xvfb-run when there is one, else
      // say so in a sentence (not a Java stack trace).
      const char* display = std::getenv("DISPLAY");
      if (!display || !*display) {
        if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0)
          throw CommandFailure(
              "idrig spy needs a display: DISPLAY is not set and xvfb-run is not installed "
              "(apt-get install xvfb, or run it in a desktop session or with ssh -X); "
              "`idrig status` shows the services without one");
        std::cerr << "no DISPLAY: running lcm-spy under xvfb-run (an invisible screen)\n";
        a.insert(a.begin(), {"xvfb-run", "-a"});
      }
      std::vector<char*> argv;
      for (auto& s : a) argv.push_back(s.data());
      argv.push_back(nullptr);
      execvp(a[0].c_str(), argv.data());
      throw std::runtime_error("cannot run java (install default-jre-headless)");
    });
  }
}

}  // namespace idrig
