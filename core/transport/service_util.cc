#include "core/transport/service_util.h"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <fstream>
#include <stdexcept>

#include "core/transport/transport.h"

namespace idrig {

std::unique_ptr<Transport> MakeServiceTransport(const std::string& url, double receive_loss) {
  auto transport = MakeLcmTransport(url);
  if (receive_loss <= 0) return transport;
  return MakeLossyTransport(std::move(transport), receive_loss, static_cast<uint64_t>(getpid()));
}

namespace {
volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }
}  // namespace

void InstallStopSignals() {
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
}

bool StopRequested() { return g_stop != 0; }

nlohmann::json ReadJsonConfig(const std::string& path) {
  if (path.empty()) return nlohmann::json::object();
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot read config file '" + path + "'");
  try {
    return nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw std::invalid_argument("config file '" + path + "' is not valid JSON: " + e.what());
  }
}

}  // namespace idrig
