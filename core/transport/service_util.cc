#include "core/transport/service_util.h"

#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/transport/transport.h"

namespace idrig {

std::unique_ptr<Transport> MakeServiceTransport(const std::string& url, double receive_loss) {
  auto transport = MakeLcmTransport(url);
  if (receive_loss <= 0) return transport;
  return MakeLossyTransport(std::move(transport), receive_loss, static_cast<uint64_t>(getpid()));
}

void SetUpServiceLog(const std::string& service, const std::string& log_file) {
  std::vector<spdlog::sink_ptr> sinks{std::make_shared<spdlog::sinks::stderr_sink_mt>()};
  if (!log_file.empty()) {
    const size_t slash = log_file.find_last_of('/');
    if (slash != std::string::npos && slash > 0) MakeDirectories(log_file.substr(0, slash));
    try {
      sinks.push_back(std::make_shared<spdlog::sinks::basic_file_sink_mt>(log_file, false));
    } catch (const std::exception& e) {
      throw std::invalid_argument("cannot open log file '" + log_file + "': " + e.what());
    }
  }
  auto logger = std::make_shared<spdlog::logger>(service, sinks.begin(), sinks.end());
  logger->set_pattern("%Y-%m-%d %H:%M:%S.%e %n[%P] %l: %v");
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
}

void MakeDirectories(const std::string& path) {
  for (size_t slash = path.find('/', 1); ; slash = path.find('/', slash + 1)) {
    mkdir(path.substr(0, slash).c_str(), 0700);
    if (slash == std::string::npos) break;
  }
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
  std::stringstream text;
  text << in.rdbuf();
  return ParseJsonConfig(text.str(), path);
}

nlohmann::json ParseJsonConfig(const std::string& text, const std::string& path) {
  nlohmann::json config;
  try {
    config = nlohmann::json::parse(text);
  } catch (const std::exception& e) {
    throw std::invalid_argument("config file '" + path + "' is not valid JSON: " + e.what());
  }
  if (!config.is_object())
    throw std::invalid_argument("config file '" + path + "' must hold a JSON object, got " +
                                config.type_name());
  return config;
}

}  // namespace idrig
