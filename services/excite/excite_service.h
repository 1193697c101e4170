#pragma once
// idrig-excite: takes experiment requests, generates the excitation in real time with the
// excitation library (core/numeric/signal/excitation.h), publishes signed actuator commands in blocks
// of block_samples samples, and publishes experiment status (IDRIG/<rig>/EXP_STATUS).
// Limits are checked before anything moves (AcceptExcitation); the rig checks them again.
#include <deque>
#include <idrig/experiment_request_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>

#include "core/numeric/signal/excitation.h"
#include "core/transport/auth.h"
#include "core/transport/signing.h"
#include "core/transport/status.h"
#include "core/transport/transport.h"

namespace idrig {

struct ExciteConfig {
  std::string rig_id = "sim1";
  HmacKey key;  // command key, shared with the rig
  int32_t key_id = 1;
  KeyRing keys;                // the operator key: experiment requests are signed with it
  std::string state_dir;       // replay marks of request senders ("" = memory only)
  double auth_window_s = 300;  // requests signed further than this from now are refused
  // The rig's limits (a request beyond one is refused at once, naming it).
  double max_duration_s = 3600.0;
  int64_t max_samples = 10000000;
  double min_sample_rate_hz = 0.01, max_sample_rate_hz = 20000.0;
  int block_samples = 10;     // samples per actuator_command_t
  double max_abs = 10.0;      // |u| limit [actuator units] (a request may only lower it)
  double max_rate = 0.0;      // |du/dt| limit [units/s]; 0: unchecked
  double max_speed = 1000.0;  // largest experiment-time / wall-time ratio accepted
  double status_period_s = 0.5;
  // Reads keys "rig_id", "key_file", "key_id", "operator_key_file", "state_dir",
  // "auth_window_s", "block_samples", "max_abs", "max_rate", "max_speed", "max_duration_s",
  // "max_samples", "min_sample_rate_hz", "max_sample_rate_hz", "status_period_s".
  static ExciteConfig FromJson(const nlohmann::json& config);
  // std::invalid_argument naming a missing key or a bad block_samples; the constructor calls it.
  void Validate() const;
};

class ExciteService {
 public:
  ExciteService(Transport& transport, ExciteConfig config);
  // Dispatches messages for up to timeout_ms, then generates what is due and publishes status.
  void Poll(int timeout_ms);
  void Tick();
  bool busy() const { return active_.has_value(); }
  nlohmann::json Details() const;

 private:
  struct Active {
    experiment_status_t status{};
    std::unique_ptr<ExcitationGenerator> generator;
    double speed = 1.0;
    int64_t start_wall_us = 0;
    int64_t next_sample = 0;
  };
  void OnRequest(const std::string& channel, const uint8_t* data, size_t size);
  void OnRigStatus(const uint8_t* data, size_t size);
  void Reply(const experiment_request_t& request, int32_t state, const std::string& message);
  void Start(const experiment_request_t& request);
  void Stop(const experiment_request_t& request);
  void SendCommand(int64_t experiment_id, int64_t first_sample, double fs, int32_t flags,
                   const std::vector<double>& u);
  void Finish(int32_t state, const std::string& message);

  Transport& transport_;
  ExciteConfig config_;
  StatusReporter reporter_;
  std::string command_channel_;
  ExperimentStatusPublisher status_;
  int64_t command_seq_;
  std::optional<Active> active_;
  EnvelopeVerifier verifier_;
  std::optional<EnvelopeSigner> reply_signer_;
  std::map<int64_t, std::pair<int32_t, std::string>> replies_;  // request id -> answer given
  std::string reply_channel_;
};

}  // namespace idrig
