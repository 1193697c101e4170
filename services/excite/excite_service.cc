#include "services/excite/excite_service.h"

#include <cmath>
#include <idrig/actuator_command_t.hpp>
#include <idrig/request_reply_t.hpp>
#include <spdlog/spdlog.h>

#include "core/transport/channels.h"
#include "core/transport/service_util.h"

namespace idrig {

ExciteConfig ExciteConfig::FromJson(const nlohmann::json& c) {
  ExciteConfig config;
  config.rig_id = ConfigValue<std::string>(c, "rig_id", config.rig_id);
  const std::string key_file = ConfigValue<std::string>(c, "key_file", "");
  if (!key_file.empty()) config.key = ReadKeyFile(key_file);
  config.key_id = ConfigValue<int32_t>(c, "key_id", config.key_id);
  config.keys = KeyRing::FromConfig(c);
  config.state_dir = ConfigValue<std::string>(c, "state_dir", config.state_dir);
  config.auth_window_s = ConfigValue<double>(c, "auth_window_s", config.auth_window_s);
  config.max_duration_s = ConfigValue<double>(c, "max_duration_s", config.max_duration_s);
  config.max_samples = ConfigValue<int64_t>(c, "max_samples", config.max_samples);
  config.min_sample_rate_hz = ConfigValue<double>(c, "min_sample_rate_hz", config.min_sample_rate_hz);
  config.max_sample_rate_hz = ConfigValue<double>(c, "max_sample_rate_hz", config.max_sample_rate_hz);
  config.block_samples = ConfigValue<int>(c, "block_samples", config.block_samples);
  config.max_abs = ConfigValue<double>(c, "max_abs", config.max_abs);
  config.max_rate = ConfigValue<double>(c, "max_rate", config.max_rate);
  config.max_speed = ConfigValue<double>(c, "max_speed", config.max_speed);
  config.status_period_s = ConfigValue<double>(c, "status_period_s", config.status_period_s);
  return config;
}

void ExciteConfig::Validate() const {
  if (key.size() < 16)
    throw std::invalid_argument("idrig-excite needs an HMAC key (key_file) of >= 16 bytes");
  if (!keys.Has(kOperatorRole))
    throw std::invalid_argument(
        "idrig-excite needs the operator key (operator_key_file): experiment requests are signed");
  if (block_samples < 1 || block_samples > 4000)
    throw std::invalid_argument("block_samples must be in 1..4000 (one command < 60 KB)");
}

ExciteService::ExciteService(Transport& transport, ExciteConfig config)
    : transport_(transport),
      config_(std::move(config)),
      reporter_(transport, "excite", "excite-" + config_.rig_id),
      command_channel_(Channel(config_.rig_id, ChannelKind::kCommand)),
      status_(transport, Channel(config_.rig_id, ChannelKind::kExperimentStatus),
              config_.status_period_s),
      // Starts at the start time in µs, so seq keeps increasing across restarts (the rig
      // refuses a seq that is not above the last one it accepted).
      command_seq_(NowMicros()),
      verifier_(config_.keys,
                config_.state_dir.empty() ? "" : config_.state_dir + "/excite-requests.hwm",
                config_.auth_window_s, "idrig-excite"),
      reply_channel_(Channel(config_.rig_id, ChannelKind::kRequestReply)) {
  config_.Validate();
  reply_signer_.emplace(kOperatorRole, *config_.keys.Find(kOperatorRole), "excite-" + config_.rig_id);
  transport_.Subscribe(
      Channel(config_.rig_id, ChannelKind::kExperimentRequest),
      [this](const std::string& c, const uint8_t* d, size_t n) { OnRequest(c, d, n); }, 1000);
  transport_.Subscribe(
      Channel(config_.rig_id, ChannelKind::kExperimentStatus),
      [this](const std::string&, const uint8_t* d, size_t n) { OnRigStatus(d, n); }, 1000);
}

void ExciteService::OnRequest(const std::string& channel, const uint8_t* data, size_t size) {
  experiment_request_t request;
  Sender who;
  if (!verifier_.Open(channel, data, size, {kOperatorRole}, &request, &who, &transport_.counters()))
    return;
  if (request.rig_id != config_.rig_id) return;
  auto answered = replies_.find(request.request_id);
  if (answered != replies_.end()) {  // a re-sent request: the same answer again (idempotent)
    Reply(request, answered->second.first, answered->second.second);
    return;
  }
  spdlog::info("request {} from {}: {} experiment {} ({})", request.request_id, who.id,
               request.action == experiment_request_t::ACTION_STOP ? "stop" : "start",
               request.experiment_id, request.signal_spec);
  if (request.action == experiment_request_t::ACTION_START)
    Start(request);
  else if (request.action == experiment_request_t::ACTION_STOP)
    Stop(request);
  else
    Reply(request, request_reply_t::STATE_REFUSED,
          "unknown action " + std::to_string(request.action));
}

void ExciteService::Reply(const experiment_request_t& request, int32_t state,
                          const std::string& message) {
  replies_[request.request_id] = {state, message};
  while (replies_.size() > 256) replies_.erase(replies_.begin());  // ids grow with time
  if (state == request_reply_t::STATE_REFUSED)
    spdlog::warn("request {} refused: {}", request.request_id, message);
  request_reply_t reply{};
  reply.utime = NowMicros();
  reply.request_id = request.request_id;
  reply.rig_id = config_.rig_id;
  reply.experiment_id = request.experiment_id;
  reply.source = "excite";
  reply.state = state;
  reply.message = message;
  reply_signer_->Publish(transport_, reply_channel_, reply);
}

// The rig's word ends an experiment early: interrupted (the rig restarted), failed (a limit,
// the watchdog) or stopped. Excite then stops commanding it. (EXP_STATUS is not signed: a forged
// one can only make excite stop early, which is the safe direction.)
void ExciteService::OnRigStatus(const uint8_t* data, size_t size) {
  experiment_status_t status;
  if (!Decode(data, size, &status, &transport_.counters(), 65536)) return;
  if (status.source != "rig" || !active_ || status.experiment_id != active_->status.experiment_id)
    return;
  if (status.state != experiment_status_t::STATE_INTERRUPTED &&
      status.state != experiment_status_t::STATE_FAILED &&
      status.state != experiment_status_t::STATE_STOPPED)
    return;
  spdlog::warn("experiment {} ended by the rig ({}): {}", status.experiment_id, status.state,
               status.message);
  Finish(status.state, "ended by the rig: " + status.message);
}

void ExciteService::Start(const experiment_request_t& request) {
  experiment_status_t status{};
  status.source = "excite";
  status.rig_id = config_.rig_id;
  status.experiment_id = request.experiment_id;
  status.request_id = request.request_id;
  status.signal_spec = request.signal_spec;
  status.sample_rate_hz = request.sample_rate_hz;
  status.state = experiment_status_t::STATE_FAILED;
  auto fail = [&](const std::string& message) {
    status.message = message;
    status.end_utime = NowMicros();
    status_.Finished(status);
  };
  if (active_) {
    Reply(request, request_reply_t::STATE_REFUSED,
          "rig busy with experiment " + std::to_string(active_->status.experiment_id));
    return fail("rig busy with experiment " + std::to_string(active_->status.experiment_id));
  }
  try {
    const double fs = request.sample_rate_hz;
    if (!(fs > 0 && std::isfinite(fs)))
      throw std::invalid_argument("sample_rate_hz must be > 0");
    if (fs < config_.min_sample_rate_hz || fs > config_.max_sample_rate_hz)
      throw std::invalid_argument("sample rate " + std::to_string(fs) +
                                  " Hz outside this rig's range [" +
                                  std::to_string(config_.min_sample_rate_hz) + ", " +
                                  std::to_string(config_.max_sample_rate_hz) + "] Hz");
    if (!(request.duration_s > 0 && std::isfinite(request.duration_s)))
      throw std::invalid_argument("duration_s must be > 0");
    if (request.duration_s > config_.max_duration_s)
      throw std::invalid_argument("duration " + std::to_string(request.duration_s) +
                                  " s above this rig's maximum " +
                                  std::to_string(config_.max_duration_s) + " s");
    const double samples = request.duration_s * fs;
    if (samples > static_cast<double>(config_.max_samples))
      throw std::invalid_argument(std::to_string(std::llround(samples)) +
                                  " samples above this rig's maximum " +
                                  std::to_string(config_.max_samples));
    if (std::llround(samples) < 1)
      throw std::invalid_argument("duration × sample rate gives no sample");
    const double speed = request.speed > 0 ? request.speed : 1.0;
    if (speed > config_.max_speed)
      throw std::invalid_argument("speed " + std::to_string(speed) + " above this rig's maximum " +
                                  std::to_string(config_.max_speed));
    ExcitationLimits limits;
    limits.max_abs = config_.max_abs;
    if (request.max_abs > 0 && (limits.max_abs <= 0 || request.max_abs < limits.max_abs))
      limits.max_abs = request.max_abs;
    limits.max_rate = config_.max_rate;
    if (request.max_rate > 0 && (limits.max_rate <= 0 || request.max_rate < limits.max_rate))
      limits.max_rate = request.max_rate;
    limits.horizon_s = request.duration_s;
    const ExcitationSpec spec = ParseExcitationSpec(request.signal_spec);
    const AcceptedExcitation accepted = AcceptExcitation(spec, request.sample_rate_hz, limits);
    Active a;
    a.generator = std::make_unique<ExcitationGenerator>(accepted.spec, request.sample_rate_hz);
    a.speed = speed;
    a.start_wall_us = NowMicros();
    status.state = experiment_status_t::STATE_RUNNING;
    status.signal_spec = FormatExcitationSpec(accepted.spec);
    status.samples_total = std::llround(request.duration_s * request.sample_rate_hz);
    status.start_utime = a.start_wall_us;
    status.message =
        "limits |u| <= " + std::to_string(limits.max_abs) +
        (limits.max_rate > 0 ? ", |du/dt| <= " + std::to_string(limits.max_rate) : "") +
        "; peak |u| " + std::to_string(accepted.peak_abs);
    a.status = status;
    active_ = std::move(a);
    status_.Publish(active_->status);
    Reply(request, request_reply_t::STATE_ACCEPTED, status.message);
    spdlog::info("experiment {} started: {} samples at {} Hz, {}", request.experiment_id,
                 status.samples_total, request.sample_rate_hz, status.message);
  } catch (const std::exception& e) {
    Reply(request, request_reply_t::STATE_REFUSED, e.what());
    fail(std::string("refused: ") + e.what());
  }
}

void ExciteService::Stop(const experiment_request_t& request) {
  if (!active_ || active_->status.experiment_id != request.experiment_id) {
    bool ended = false;
    for (const auto& s : status_.recent()) ended |= s.experiment_id == request.experiment_id;
    return Reply(request, request_reply_t::STATE_REFUSED,
                 "experiment " + std::to_string(request.experiment_id) +
                     (ended ? " has already ended" : " is not running") + " on rig " +
                     config_.rig_id);
  }
  Reply(request, request_reply_t::STATE_ACCEPTED, "stopping");
  SendCommand(active_->status.experiment_id, active_->next_sample, active_->status.sample_rate_hz,
              actuator_command_t::FLAG_STOP, {});
  Finish(experiment_status_t::STATE_STOPPED,
         "stopped by request " + std::to_string(request.request_id));
}

void ExciteService::SendCommand(int64_t experiment_id, int64_t first_sample, double fs,
                                int32_t flags, const std::vector<double>& u) {
  actuator_command_t command{};
  command.utime = NowMicros();
  command.seq = ++command_seq_;
  command.key_id = config_.key_id;
  command.rig_id = config_.rig_id;
  command.experiment_id = experiment_id;
  command.first_sample = first_sample;
  command.sample_rate_hz = fs;
  command.flags = flags;
  command.n_samples = static_cast<int32_t>(u.size());
  command.u = u;
  SignCommand(&command, config_.key);
  transport_.PublishMessage(command_channel_, command);
}

void ExciteService::Finish(int32_t state, const std::string& message) {
  active_->status.state = state;
  active_->status.end_utime = NowMicros();
  if (!message.empty()) active_->status.message = message;
  status_.Finished(active_->status);
  active_.reset();
}

void ExciteService::Tick() {
  if (active_) {
    Active& a = *active_;
    const double fs = a.status.sample_rate_hz;
    const int64_t total = a.status.samples_total;
    // Samples due by now: experiment time = wall time · speed.
    const double elapsed_s = 1e-6 * static_cast<double>(NowMicros() - a.start_wall_us) * a.speed;
    const int64_t due = std::min<int64_t>(total, static_cast<int64_t>(elapsed_s * fs) + 1);
    while (a.next_sample < total &&
           (due - a.next_sample >= config_.block_samples || due == total)) {
      const int64_t n = std::min<int64_t>(config_.block_samples, total - a.next_sample);
      std::vector<double> u(static_cast<size_t>(n));
      for (auto& value : u) value = a.generator->Next();
      const bool last = a.next_sample + n == total;
      SendCommand(a.status.experiment_id, a.next_sample, fs,
                  last ? actuator_command_t::FLAG_FINAL : 0, u);
      a.next_sample += n;
      a.status.samples_done = a.next_sample;
    }
    if (a.next_sample >= total) {
      // Two more (empty) final commands, in case the last block is lost on the way.
      for (int i = 0; i < 2; ++i)
        SendCommand(a.status.experiment_id, total, fs, actuator_command_t::FLAG_FINAL, {});
      Finish(experiment_status_t::STATE_DONE, "");
    }
  }
  if (status_.Due()) {
    if (active_) status_.Publish(active_->status);
    if (!status_.recent().empty()) status_.Publish(status_.recent().back());
  }
  // Details hold strings from requests (the last refusal, the SPEC): invalid UTF-8 in one made
  // dump() throw here, outside any handler, and stopped excite (found by fuzz_handlers).
  if (reporter_.Due()) reporter_.Maybe(active_ ? "busy" : "running", Details().dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), true);
}

nlohmann::json ExciteService::Details() const {
  nlohmann::json d;
  d["rig_id"] = config_.rig_id;
  d["command_seq"] = command_seq_;
  if (active_) {
    d["active"] = {{"experiment_id", active_->status.experiment_id},
                   {"samples_done", active_->status.samples_done},
                   {"samples_total", active_->status.samples_total},
                   {"signal_spec", active_->status.signal_spec}};
  }
  d["recent"] = status_.RecentJson(false);
  return d;
}

void ExciteService::Poll(int timeout_ms) {
  transport_.Handle(timeout_ms);
  Tick();
}

}  // namespace idrig
