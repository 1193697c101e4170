// The config readers on arbitrary text: the key-file text (ParseKeyText, also what `idrig
// --key-file` reads), the JSON config file (ParseJsonConfig), then every service's
// Config::FromJson + Validate (what RunServiceMain does before constructing the service). Each
// returns or throws std::invalid_argument naming the problem; anything else is a crash.
// Paths are the one thing not fuzzed: a string under a "*_file" key is replaced by one of the
// files made in a private directory at start (a good key, a weak one, one readable by others, a
// missing one, a plant model, a file that is not a model), so the readers never open a
// fuzzer-chosen path (/dev/zero, a FIFO) and the checks behind the file are reached.
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "core/transport/service_util.h"
#include "core/transport/signing.h"
#include "services/catalog/catalog_service.h"
#include "services/excite/excite_service.h"
#include "services/logger/logger_service.h"
#include "services/rig_sim/rig_sim.h"
#include "services/worker/worker_service.h"

namespace {

std::string g_dir;

void Write(const std::string& name, const std::string& text, mode_t mode) {
  const std::string path = g_dir + "/" + name;
  std::ofstream(path) << text;
  chmod(path.c_str(), mode);
}

// The prepared file a fuzzed path string stands for.
std::string FileFor(const std::string& value) {
  auto has = [&](const char* part) { return value.find(part) != std::string::npos; };
  if (has("missing")) return g_dir + "/missing";
  if (has("broken")) return g_dir + "/broken.json";
  if (has("json")) return g_dir + "/plant.json";
  if (has("weak")) return g_dir + "/weak.key";
  if (has("open")) return g_dir + "/open.key";
  return g_dir + "/good.key";
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spdlog::set_level(spdlog::level::off);
  char dir[] = "/tmp/idrig-fuzz-config-XXXXXX";
  if (!mkdtemp(dir)) std::abort();
  g_dir = dir;
  const std::string good = "3f9a1c7e55d2b8046e1f0a9c3d7b2e58c4a61f09e7d3b5a2c8f1e04d6b9a7c31\n";
  Write("good.key", good, 0600);
  Write("open.key", good, 0644);
  Write("weak.key", std::string(64, '0') + "\n", 0600);
  Write("plant.json",
        R"({"format":"idrig.model/1","kind":"tf","domain":"continuous","num":[1.0],"den":[1.0,0.4,1.0]})",
        0644);
  Write("broken.json", R"({"format":"idrig.model/1","kind":"tf","num":[1)", 0644);
  // The directory goes when the fuzzer exits normally.
  std::atexit([] { std::system(("rm -rf '" + g_dir + "'").c_str()); });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace idrig;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    ParseKeyText(text, "fuzz.key");
  } catch (const std::invalid_argument&) {
  }
  nlohmann::json config;
  try {
    config = ParseJsonConfig(text, "fuzz.json");
  } catch (const std::invalid_argument&) {
    return 0;
  }
  for (auto& [key, value] : config.items())
    if (key.size() > 5 && key.compare(key.size() - 5, 5, "_file") == 0 && value.is_string() &&
        !value.get<std::string>().empty())
      value = FileFor(value.get<std::string>());
  auto check = [&](auto read) {
    try {
      read();
    } catch (const std::invalid_argument&) {
    }
  };
  check([&] { RigSimConfig::FromJson(config).Validate(); });
  check([&] { ExciteConfig::FromJson(config).Validate(); });
  check([&] { CatalogConfig::FromJson(config).Validate(); });
  check([&] { WorkerConfig::FromJson(config).Validate(); });
  check([&] { LoggerConfig::FromJson(config); });
  return 0;
}
