#pragma once
// idrig-rig-sim: a simulated rig. A linear plant (idrig.model/1, discretised exactly by ZOH at
// the commanded sample rate) plus white output noise applies signed actuator commands and
// publishes measurement blocks on IDRIG/<rig>/MEAS. It refuses unsigned, forged and replayed
// commands and commands beyond its amplitude/rate limits (the experiment is then aborted and
// the safe input applied), and goes to the safe input when commands stop (watchdog).
// A real rig's driver speaks the same messages (docs/services.md).
#include <deque>
#include <idrig/actuator_command_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/measurement_block_t.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <string>

#include "core/numeric/gap/effects.h"
#include "core/numeric/model/lti_model.h"
#include "core/transport/auth.h"
#include "core/transport/signing.h"
#include "services/rig_sim/rig_journal.h"
#include "core/transport/status.h"
#include "core/transport/transport.h"

namespace idrig {

struct RigSimConfig {
  std::string rig_id = "sim1";
  LtiModel plant;          // SISO plant
  double noise_std = 0.0;  // output noise standard deviation [output units]
  uint64_t seed = 1;
  double max_abs = 10.0;            // refused above |u| [actuator units]; 0: unchecked
  double max_rate = 0.0;            // refused above |du/dt| [units/s]; 0: unchecked
  double watchdog_s = 1.0;          // no command for this long -> safe input, experiment aborted
  double safe_input = 0.0;          // [actuator units]
  int block_samples = 100;          // samples per measurement block (< 60 KB)
  int keep_experiments = 4;         // experiments whose blocks are kept for re-sending
  std::map<int32_t, HmacKey> keys;  // accepted keys by key id
  double status_period_s = 0.5;
  // Limits of the rig, checked on the first command of an experiment and on every sample.
  double min_sample_rate_hz = 0.01, max_sample_rate_hz = 20000.0;
  int64_t max_samples = 10000000;
  // A command of an experiment the rig has not seen start, beyond this sample, is refused (the
  // rig cannot know the plant's state there: it would invent samples 0 .. first-1).
  int64_t max_late_start_samples = 100;
  // Replay marks of commands and the journal of published blocks (RigJournal); "" = memory only.
  std::string state_dir;
  // An unmodelled effect of the gap-diagnosis library on the plant (docs/gap.md); none by
  // default. Needs a continuous plant. Config key "effect": {"effect": name, "params": {…}}.
  Effect effect;
  // Keys: "rig_id", "model_file" or "model" (idrig.model/1), "noise_std", "seed", "max_abs",
  // "max_rate", "watchdog_s", "safe_input", "block_samples", "key_file" + "key_id", "effect", "state_dir",
  // "min_sample_rate_hz", "max_sample_rate_hz", "max_samples", "max_late_start_samples".
  static RigSimConfig FromJson(const nlohmann::json& config);
  // std::invalid_argument naming what the rig cannot run (no key, a MIMO plant, an effect it
  // cannot simulate, block_samples); the constructor calls it.
  void Validate() const;
};

class RigSim {
 public:
  RigSim(Transport& transport, RigSimConfig config);
  void Poll(int timeout_ms);
  void Tick();
  double applied_input() const { return last_u_; }
  bool running() const { return experiment_.has_value(); }
  nlohmann::json Details() const;

 private:
  struct Experiment {
    experiment_status_t status{};
    StateSpace discrete;
    Eigen::VectorXd x;
    std::deque<double> delay_line;  // whole-sample input delay
    std::optional<EffectSimulator> with_effect;  // the plant with its effect, when configured
    int64_t next_sample = 0;
    int64_t block_seq = 0;
    int64_t last_command_us = 0;
    std::vector<double> block_u, block_y;
    int64_t block_first = 0;
    int64_t command_gaps = 0;  // samples held because commands were lost
  };
  void OnCommand(const uint8_t* data, size_t size);
  void OnReplayRequest(const uint8_t* data, size_t size);
  void StartExperiment(const actuator_command_t& command);
  void ApplySample(double u);
  void FlushBlock();
  void End(int32_t state, const std::string& message);
  void Recover();
  void RefuseUnknown(const actuator_command_t& command, const std::string& why);

  Transport& transport_;
  RigSimConfig config_;
  StatusReporter reporter_;
  RigJournal journal_;  // before command_marks_: it creates the state directory
  ReplayStore command_marks_;
  CommandVerifier verifier_;
  std::string meas_channel_;
  ExperimentStatusPublisher status_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  std::optional<Experiment> experiment_;
  std::map<int64_t, bool> ended_ids_;
  // Encoded blocks of the recent experiments, re-sent when the logger reports a loss.
  std::map<int64_t, std::vector<std::vector<uint8_t>>> sent_blocks_;
  int64_t resent_blocks_ = 0;
  double last_u_ = 0.0;
  std::string last_refusal_;
};

}  // namespace idrig
