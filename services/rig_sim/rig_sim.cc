#include "services/rig_sim/rig_sim.h"

#include <cmath>
#include <idrig/replay_request_t.hpp>
#include <set>

#include "core/io/gap_json.h"
#include "core/io/model_json.h"
#include "core/transport/channels.h"
#include "core/transport/service_util.h"
#include <spdlog/spdlog.h>

namespace idrig {

RigSimConfig RigSimConfig::FromJson(const nlohmann::json& c) {
  RigSimConfig config;
  config.rig_id = ConfigValue<std::string>(c, "rig_id", config.rig_id);
  const std::string model_file = ConfigValue<std::string>(c, "model_file", "");
  if (!model_file.empty())
    config.plant = ReadModelFile(model_file);
  else if (c.contains("model"))
    config.plant = ModelFromJson(c["model"]);
  else
    throw std::invalid_argument("idrig-rig-sim needs a plant: config 'model_file' or 'model'");
  config.noise_std = ConfigValue<double>(c, "noise_std", config.noise_std);
  config.seed = ConfigValue<uint64_t>(c, "seed", config.seed);
  config.max_abs = ConfigValue<double>(c, "max_abs", config.max_abs);
  config.max_rate = ConfigValue<double>(c, "max_rate", config.max_rate);
  config.watchdog_s = ConfigValue<double>(c, "watchdog_s", config.watchdog_s);
  config.safe_input = ConfigValue<double>(c, "safe_input", config.safe_input);
  config.block_samples = ConfigValue<int>(c, "block_samples", config.block_samples);
  config.keep_experiments = ConfigValue<int>(c, "keep_experiments", config.keep_experiments);
  config.status_period_s = ConfigValue<double>(c, "status_period_s", config.status_period_s);
  config.min_sample_rate_hz = ConfigValue<double>(c, "min_sample_rate_hz", config.min_sample_rate_hz);
  config.max_sample_rate_hz = ConfigValue<double>(c, "max_sample_rate_hz", config.max_sample_rate_hz);
  config.max_samples = ConfigValue<int64_t>(c, "max_samples", config.max_samples);
  config.max_late_start_samples =
      ConfigValue<int64_t>(c, "max_late_start_samples", config.max_late_start_samples);
  config.state_dir = ConfigValue<std::string>(c, "state_dir", config.state_dir);
  if (c.contains("effect")) config.effect = EffectFromJson(c["effect"]);
  const std::string key_file = ConfigValue<std::string>(c, "key_file", "");
  if (!key_file.empty()) config.keys[ConfigValue<int32_t>(c, "key_id", 1)] = ReadKeyFile(key_file);
  return config;
}

void RigSimConfig::Validate() const {
  if (keys.empty()) throw std::invalid_argument("idrig-rig-sim needs an HMAC key (key_file)");
  const StateSpace ss = ToStateSpace(plant);
  if (ss.NumInputs() != 1 || ss.NumOutputs() != 1)
    throw std::invalid_argument("idrig-rig-sim simulates SISO plants only");
  if (effect.kind != EffectKind::kNone &&
      !(std::holds_alternative<TransferFunction>(plant) &&
        !std::get<TransferFunction>(plant).IsDiscrete()))
    throw std::invalid_argument("idrig-rig-sim: an effect needs a continuous transfer-function plant");
  if (effect.kind == EffectKind::kParameterMismatch)
    throw std::invalid_argument("idrig-rig-sim: parameter_mismatch is a different plant, not an effect: "
                                "change the model instead");
  ValidateEffect(effect);
  if (block_samples < 1 || block_samples > 3000)
    throw std::invalid_argument("block_samples must be in 1..3000 (one block < 60 KB)");
}

RigSim::RigSim(Transport& transport, RigSimConfig config)
    : transport_(transport),
      config_(std::move(config)),
      reporter_(transport, "rig_sim", "rig_sim-" + config_.rig_id),
      journal_(config_.state_dir),
      command_marks_(config_.state_dir.empty() ? "" : config_.state_dir + "/commands.hwm"),
      meas_channel_(Channel(config_.rig_id, ChannelKind::kMeasurement)),
      status_(transport, Channel(config_.rig_id, ChannelKind::kExperimentStatus),
              config_.status_period_s),
      rng_(config_.seed) {
  config_.Validate();
  for (const auto& [id, key] : config_.keys) verifier_.AddKey(id, key);
  verifier_.UseStore(&command_marks_);
  last_u_ = config_.safe_input;
  Recover();
  transport_.Subscribe(
      Channel(config_.rig_id, ChannelKind::kCommand),
      [this](const std::string&, const uint8_t* d, size_t n) { OnCommand(d, n); }, 10000);
  transport_.Subscribe(
      Channel(config_.rig_id, ChannelKind::kRigReplayRequest),
      [this](const std::string&, const uint8_t* d, size_t n) { OnReplayRequest(d, n); }, 100);
}

// After a restart: experiments the journal shows unfinished were interrupted. Their blocks are
// kept for re-sending, their end is published as STATE_INTERRUPTED naming what is missing, and
// late commands for them are refused (never adopted: the plant's state is unknown).
void RigSim::Recover() {
  for (auto& e : journal_.Load()) {
    int64_t samples = 0;
    for (const auto& bytes : e.blocks) {
      measurement_block_t block;
      if (Decode(bytes.data(), bytes.size(), &block, nullptr)) samples += block.n_samples;
    }
    ended_ids_[e.experiment_id] = true;
    sent_blocks_[e.experiment_id] = std::move(e.blocks);
    if (e.ended) continue;
    experiment_status_t status{};
    status.source = "rig";
    status.rig_id = config_.rig_id;
    status.experiment_id = e.experiment_id;
    status.state = experiment_status_t::STATE_INTERRUPTED;
    status.samples_done = samples;
    status.samples_total = samples;
    status.blocks_total = static_cast<int64_t>(sent_blocks_[e.experiment_id].size());
    status.end_utime = NowMicros();
    status.message = "interrupted: the rig restarted during the experiment; samples 0.." +
                     std::to_string(samples - 1) + " measured, samples from " +
                     std::to_string(samples) + " on missing (not measured)";
    spdlog::warn("experiment {}: {}", e.experiment_id, status.message);
    journal_.End(e.experiment_id, status.message);
    status_.Finished(status);
  }
  while (static_cast<int>(sent_blocks_.size()) > config_.keep_experiments)
    sent_blocks_.erase(sent_blocks_.begin());
}

void RigSim::RefuseUnknown(const actuator_command_t& command, const std::string& why) {
  experiment_status_t status{};
  status.source = "rig";
  status.rig_id = config_.rig_id;
  status.experiment_id = command.experiment_id;
  status.state = experiment_status_t::STATE_INTERRUPTED;
  status.sample_rate_hz = command.sample_rate_hz;
  status.end_utime = NowMicros();
  status.message = why;
  last_refusal_ = "experiment " + std::to_string(command.experiment_id) + " refused: " + why;
  spdlog::warn("{}", last_refusal_);
  ended_ids_[command.experiment_id] = true;
  journal_.End(command.experiment_id, why);
  status_.Finished(status);
}

void RigSim::OnReplayRequest(const uint8_t* data, size_t size) {
  replay_request_t request;
  if (!Decode(data, size, &request, &transport_.counters(), 65536)) return;
  auto sent = sent_blocks_.find(request.experiment_id);
  if (request.rig_id != config_.rig_id || sent == sent_blocks_.end()) return;
  const std::set<int64_t> have(request.have_seqs.begin(), request.have_seqs.end());
  for (size_t seq = 0; seq < sent->second.size(); ++seq) {
    if (have.count(static_cast<int64_t>(seq))) continue;
    transport_.Publish(meas_channel_, sent->second[seq].data(), sent->second[seq].size());
    ++resent_blocks_;
  }
}

void RigSim::OnCommand(const uint8_t* data, size_t size) {
  actuator_command_t command;
  if (!Decode(data, size, &command, &transport_.counters(), 65536)) return;
  TransportCounters& counters = transport_.counters();
  const CommandCheck check = verifier_.Verify(command);
  if (check != CommandCheck::kOk) {
    if (check == CommandCheck::kForged)
      ++counters.forged;
    else if (check == CommandCheck::kReplayed)
      ++counters.replayed;
    else
      ++counters.unsigned_count;
    last_refusal_ =
        std::string("command seq ") + std::to_string(command.seq) + " refused: " + ToString(check);
    const int64_t refused = counters.forged + counters.replayed + counters.unsigned_count;
    if (refused <= 20 || refused % 1000 == 0)
      spdlog::warn("{} [{} refused so far]", last_refusal_, refused);
    return;
  }
  if (command.rig_id != config_.rig_id) return;
  if (ended_ids_.count(command.experiment_id)) return;  // late commands of an ended experiment
  // Limits, checked on every sample before any is applied.
  double previous = (experiment_ && experiment_->status.experiment_id == command.experiment_id)
                        ? last_u_
                        : config_.safe_input;
  for (int i = 0; i < command.n_samples; ++i) {
    const double u = command.u[i];
    const double rate = std::abs(u - previous) * command.sample_rate_hz;
    std::string why;
    if (!std::isfinite(u))
      why = "non-finite input";
    else if (config_.max_abs > 0 && std::abs(u) > config_.max_abs)
      why = "|u| = " + std::to_string(std::abs(u)) + " above the rig's limit " +
            std::to_string(config_.max_abs);
    else if (config_.max_rate > 0 && rate > config_.max_rate)
      why = "|du/dt| = " + std::to_string(rate) + " above the rig's limit " +
            std::to_string(config_.max_rate);
    if (!why.empty()) {
      ++counters.over_limit;
      last_refusal_ = "command seq " + std::to_string(command.seq) + " refused: " + why;
      spdlog::warn("{}", last_refusal_);
      if (experiment_ && experiment_->status.experiment_id == command.experiment_id)
        End(experiment_status_t::STATE_FAILED, last_refusal_ + "; safe input applied");
      else
        last_u_ = config_.safe_input;
      return;
    }
    previous = u;
  }
  if (!experiment_ || experiment_->status.experiment_id != command.experiment_id) {
    if (experiment_)
      End(experiment_status_t::STATE_FAILED,
          "superseded by experiment " + std::to_string(command.experiment_id));
    if (command.flags & actuator_command_t::FLAG_STOP) return;
    const double fs = command.sample_rate_hz;
    if (!(fs >= config_.min_sample_rate_hz && fs <= config_.max_sample_rate_hz))
      return RefuseUnknown(command, "sample rate " + std::to_string(fs) +
                                        " Hz outside the rig's range [" +
                                        std::to_string(config_.min_sample_rate_hz) + ", " +
                                        std::to_string(config_.max_sample_rate_hz) + "] Hz");
    if (command.first_sample > config_.max_late_start_samples)
      return RefuseUnknown(command, "the rig did not see samples 0.." +
                                        std::to_string(command.first_sample - 1) +
                                        " of this experiment (restarted or joined late): "
                                        "not adopted, no sample invented");
    StartExperiment(command);
  }
  Experiment& e = *experiment_;
  e.last_command_us = NowMicros();
  if (command.flags & actuator_command_t::FLAG_STOP) {
    End(experiment_status_t::STATE_STOPPED, "stopped by command");
    return;
  }
  // Checked before any sample of the command is applied: a signed command starting at sample
  // 4·10^18 made the hold loop below run for ever (the rig hung; found by fuzz_handlers).
  if (command.first_sample > config_.max_samples ||
      command.first_sample + command.n_samples > config_.max_samples + 1)
    return End(experiment_status_t::STATE_FAILED,
               "command for samples from " + std::to_string(command.first_sample) +
                   ", beyond the rig's maximum of " + std::to_string(config_.max_samples) +
                   " samples; safe input applied");
  // Lost commands: hold the last input over the missing samples (a real actuator would too) —
  // but no longer than the watchdog allows: commands missing for longer would have put the rig
  // to its safe input, so a command further ahead is not a lost-command gap (fuzz_handlers
  // timeout-46135f21: a signed command 10^7 samples ahead held the input for minutes).
  const int64_t allowed_gap =
      static_cast<int64_t>(std::ceil(config_.watchdog_s * e.status.sample_rate_hz)) + config_.block_samples;
  if (command.first_sample - e.next_sample > allowed_gap)
    return End(experiment_status_t::STATE_FAILED,
               "command for samples from " + std::to_string(command.first_sample) + " while at sample " +
                   std::to_string(e.next_sample) + ": a gap longer than the watchdog's " +
                   std::to_string(config_.watchdog_s) + " s; safe input applied");
  while (e.next_sample < command.first_sample) {
    ++e.command_gaps;
    ApplySample(last_u_);
  }
  for (int i = 0; i < command.n_samples; ++i) {
    const int64_t k = command.first_sample + i;
    if (k < e.next_sample) continue;  // already applied (duplicate)
    ApplySample(command.u[i]);
  }
  e.status.samples_done = e.next_sample;
  if (e.next_sample > config_.max_samples)
    return End(experiment_status_t::STATE_FAILED,
               "more than the rig's maximum of " + std::to_string(config_.max_samples) +
                   " samples; safe input applied");
  if (command.flags & actuator_command_t::FLAG_FINAL)
    End(experiment_status_t::STATE_DONE,
        e.command_gaps ? std::to_string(e.command_gaps) + " samples held over lost commands" : "");
}

void RigSim::StartExperiment(const actuator_command_t& command) {
  Experiment e;
  const double ts = 1.0 / command.sample_rate_hz;
  StateSpace ss = ToStateSpace(config_.plant);
  if (ss.IsDiscrete()) {
    if (std::abs(ss.sample_time - ts) > 1e-9 * ts)
      throw std::invalid_argument("discrete plant Ts differs from the commanded 1/fs");
    e.discrete = ss;
  } else {
    e.discrete = DiscretizeZoh(ss, ts);
  }
  const int delay = static_cast<int>(std::lround(e.discrete.delay_s / ts));
  e.delay_line.assign(static_cast<size_t>(delay), config_.safe_input);
  e.x = Eigen::VectorXd::Zero(e.discrete.Order());  // the simulated rig starts at rest
  if (config_.effect.kind != EffectKind::kNone)
    e.with_effect.emplace(std::get<TransferFunction>(config_.plant), config_.effect, ts);
  e.status.source = "rig";
  e.status.rig_id = config_.rig_id;
  e.status.experiment_id = command.experiment_id;
  e.status.state = experiment_status_t::STATE_RUNNING;
  e.status.sample_rate_hz = command.sample_rate_hz;
  e.status.start_utime = NowMicros();
  e.block_first = 0;
  journal_.Prune(config_.keep_experiments);
  journal_.Begin(command.experiment_id);
  spdlog::info("experiment {} started at {} Hz", command.experiment_id, command.sample_rate_hz);
  experiment_ = std::move(e);
  status_.Publish(experiment_->status);
}

void RigSim::ApplySample(double u) {
  Experiment& e = *experiment_;
  double u_plant = u;
  if (!e.delay_line.empty()) {
    e.delay_line.push_back(u);
    u_plant = e.delay_line.front();
    e.delay_line.pop_front();
  }
  // x[k+1] = A x[k] + B u[k], y[k] = C x[k] + D u[k] (+ noise); or the plant with its effect
  // (which carries its own delay line: it gets the commanded u).
  double y;
  if (e.with_effect) {
    y = e.with_effect->Step(u);
  } else {
    y = (e.discrete.C * e.x)(0) + e.discrete.D(0, 0) * u_plant;
    e.x = e.discrete.A * e.x + e.discrete.B.col(0) * u_plant;
  }
  if (config_.noise_std > 0) y += config_.noise_std * noise_(rng_);
  if (e.block_u.empty()) e.block_first = e.next_sample;
  e.block_u.push_back(u);
  e.block_y.push_back(y);
  ++e.next_sample;
  last_u_ = u;
  if (static_cast<int>(e.block_u.size()) >= config_.block_samples) FlushBlock();
}

void RigSim::FlushBlock() {
  Experiment& e = *experiment_;
  if (e.block_u.empty()) return;
  measurement_block_t block{};
  block.utime = NowMicros();
  block.rig_id = config_.rig_id;
  block.experiment_id = e.status.experiment_id;
  block.seq = e.block_seq++;
  block.first_sample = e.block_first;
  block.sample_time_s = 1.0 / e.status.sample_rate_hz;
  block.n_samples = static_cast<int32_t>(e.block_u.size());
  block.n_inputs = 1;
  block.n_outputs = 1;
  block.u.resize(e.block_u.size());
  block.y.resize(e.block_y.size());
  for (size_t i = 0; i < e.block_u.size(); ++i) {
    block.u[i] = {e.block_u[i]};
    block.y[i] = {e.block_y[i]};
  }
  std::vector<uint8_t> bytes(block.getEncodedSize());
  block.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  transport_.Publish(meas_channel_, bytes.data(), bytes.size());
  journal_.Append(block.experiment_id, bytes);
  auto& kept = sent_blocks_[block.experiment_id];
  kept.push_back(std::move(bytes));
  while (static_cast<int>(sent_blocks_.size()) > config_.keep_experiments)
    sent_blocks_.erase(sent_blocks_.begin());  // experiment ids grow with time
  e.block_u.clear();
  e.block_y.clear();
}

void RigSim::End(int32_t state, const std::string& message) {
  FlushBlock();
  Experiment& e = *experiment_;
  e.status.state = state;
  e.status.samples_done = e.next_sample;
  e.status.samples_total = e.next_sample;
  e.status.blocks_total = e.block_seq;
  e.status.end_utime = NowMicros();
  e.status.message = message;
  last_u_ = config_.safe_input;  // safe input after every experiment
  journal_.End(e.status.experiment_id, message);  // on disk before it is announced
  status_.Finished(e.status);
  static const char* names[] = {"pending", "running", "done", "stopped", "failed", "interrupted"};
  spdlog::log(state == experiment_status_t::STATE_DONE ? spdlog::level::info : spdlog::level::warn,
              "experiment {} ended {}: {} samples, {} blocks; {}", e.status.experiment_id,
              state >= 0 && state <= 5 ? names[state] : "?", e.next_sample, e.block_seq, message);
  ended_ids_[e.status.experiment_id] = true;
  experiment_.reset();
}

void RigSim::Tick() {
  const int64_t now = NowMicros();
  if (experiment_ &&
      now - experiment_->last_command_us > static_cast<int64_t>(config_.watchdog_s * 1e6))
    End(experiment_status_t::STATE_FAILED, "watchdog: no command for " +
                                               std::to_string(config_.watchdog_s) +
                                               " s; safe input applied");
  if (status_.Due()) {
    if (experiment_) status_.Publish(experiment_->status);
    for (const auto& s : status_.recent()) status_.Publish(s);  // full snapshot of the recent ones
  }
  if (reporter_.Due()) reporter_.Maybe(experiment_ ? "busy" : "running", Details().dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), true);
}

nlohmann::json RigSim::Details() const {
  nlohmann::json d;
  d["rig_id"] = config_.rig_id;
  d["applied_input"] = last_u_;
  d["safe"] = !experiment_.has_value();
  d["last_refusal"] = last_refusal_;
  d["resent_blocks"] = resent_blocks_;
  d["effect"] = EffectToJson(config_.effect);
  if (experiment_)
    d["experiment"] = {{"experiment_id", experiment_->status.experiment_id},
                       {"samples", experiment_->next_sample},
                       {"blocks", experiment_->block_seq}};
  d["recent"] = status_.RecentJson(true);
  return d;
}

void RigSim::Poll(int timeout_ms) {
  transport_.Handle(timeout_ms);
  Tick();
}

}  // namespace idrig
