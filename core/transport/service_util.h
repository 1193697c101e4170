#pragma once
// Small helpers shared by the service mains: stop on SIGINT/SIGTERM, JSON config files.
#include <cstdint>
#include <limits>
#include <memory>
#include <type_traits>
#include <nlohmann/json.hpp>
#include <string>

namespace idrig {

class Transport;
// The transport of a service process: LCM on `url`, wrapped to drop the fraction
// `receive_loss` of received messages when it is > 0 (config key "receive_loss", or --loss:
// a lossy network for tests where tc netem is not available). Seeded from the pid.
std::unique_ptr<Transport> MakeServiceTransport(const std::string& url, double receive_loss);

// Makes spdlog's default logger "<service>" write every line to stderr (the journal under
// systemd) and, when log_file is not "", append it to that file; flushed per line, so a kill -9
// loses nothing. Throws std::invalid_argument naming the file when it cannot be opened.
void SetUpServiceLog(const std::string& service, const std::string& log_file);

// mkdir -p with mode 0700 for the directories it creates (state directories). Errors are left
// to the first use of the directory.
void MakeDirectories(const std::string& path);

// Installs SIGINT/SIGTERM handlers that set a flag read by StopRequested().
void InstallStopSignals();
bool StopRequested();

// Reads a JSON config file ("" gives an empty object). Throws std::invalid_argument naming
// the file when it cannot be read or parsed.
nlohmann::json ReadJsonConfig(const std::string& path);
// The text of the config file named `path`: a JSON object, else std::invalid_argument naming the
// file (tests/fuzz/fuzz_config feeds it bytes).
nlohmann::json ParseJsonConfig(const std::string& text, const std::string& path);

// A config value with a default; throws std::invalid_argument naming the key on a wrong type.
// An integer key takes an integral number within T's range (1e19 for a uint64_t or 2.5 for an
// int was a float-to-integer conversion out of range, undefined behaviour: fuzz_config).
template <class T>
T ConfigValue(const nlohmann::json& config, const char* key, const T& fallback) {
  if (!config.is_object() || !config.contains(key) || config[key].is_null()) return fallback;
  const nlohmann::json& value = config[key];
  if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    const bool in_range =
        value.is_number_unsigned()
            ? value.get<uint64_t>() <= static_cast<uint64_t>(std::numeric_limits<T>::max())
        : value.is_number_integer()
            ? value.get<int64_t>() >= static_cast<int64_t>(std::numeric_limits<T>::min()) &&
                  (value.get<int64_t>() < 0 ||
                   static_cast<uint64_t>(value.get<int64_t>()) <=
                       static_cast<uint64_t>(std::numeric_limits<T>::max()))
            : false;
    if (!in_range)
      throw std::invalid_argument(std::string("config key '") + key + "' must be an integer in [" +
                                  std::to_string(std::numeric_limits<T>::min()) + ", " +
                                  std::to_string(std::numeric_limits<T>::max()) + "], got " +
                                  value.dump());
    return value.is_number_unsigned() ? static_cast<T>(value.get<uint64_t>())
                                      : static_cast<T>(value.get<int64_t>());
  }
  try {
    return value.get<T>();
  } catch (const std::exception&) {
    throw std::invalid_argument(std::string("config key '") + key + "' has the wrong type");
  }
}

}  // namespace idrig
