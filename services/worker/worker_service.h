#pragma once
// idrig-worker: runs identification jobs (any number of workers, on any host).
//  1. Hears identify_request_t (from the command line, or re-offered by idrig-catalog), and
//     claims one job at a time (identify_claim_t); idrig-catalog grants each job to one worker
//     and renews the lease while the worker keeps claiming it.
//  2. Gets the record from the measurement blocks it heard; asks idrig-logger to replay what
//     it missed (replay_request_t lists the blocks it holds) until the record is complete.
//  3. Runs the method by name (core/methods/registry.h) in a compute thread, publishes a
//     model_result_t and re-sends it until idrig-catalog acknowledges it (result_ack_t).
// A worker killed mid-job stops renewing its lease; the catalogue then offers the job again.
#include <deque>
#include <future>
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <idrig/measurement_block_t.hpp>
#include <idrig/model_result_t.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>

#include "core/numeric/io_record.h"
#include "core/transport/auth.h"
#include "core/transport/status.h"
#include "core/transport/transport.h"

namespace idrig {

struct WorkerConfig {
  std::string worker_id;         // default: worker-<host>-<pid>
  double claim_retry_s = 0.3;    // re-send an unanswered claim
  double renew_s = 1.0;          // lease renewal period (below the catalogue's lease_s)
  double result_retry_s = 0.5;   // re-send an unacknowledged result
  double replay_retry_s = 0.5;   // ask the logger again for missing blocks
  double data_timeout_s = 60.0;  // no complete record by then: the job fails
  double debug_delay_s = 0.0;    // extra compute time (tests of a worker dying mid-job)
  int cache_experiments = 4;     // experiments whose blocks are kept in memory
  KeyRing keys;                  // service key (claims, results; grants, acks); operator optional
  std::string state_dir;         // replay marks ("" = memory only)
  double auth_window_s = 300;
  // true: the method runs on the caller's thread when the job's record is complete (in the
  // handler or Tick() that completes it) instead of a compute thread; tests and the fuzz target,
  // whose runs must repeat. Not read from the config file.
  bool compute_inline = false;
  // Keys as the fields, plus "operator_key_file", "service_key_file".
  static WorkerConfig FromJson(const nlohmann::json& config);
  // std::invalid_argument naming a missing key; the constructor calls it.
  void Validate() const;
};

// The record of an experiment from its blocks (seq 0..n-1, contiguous samples). Throws
// std::invalid_argument naming the first missing or inconsistent block.
IoRecord AssembleRecord(const std::map<int64_t, measurement_block_t>& blocks, int64_t blocks_total);
// SHA-256 (hex) of Ts, then u, then y (row by row), as native doubles: the data hash of lineage.
std::string RecordHash(const IoRecord& record);

class WorkerService {
 public:
  WorkerService(Transport& transport, WorkerConfig config);
  ~WorkerService();
  void Poll(int timeout_ms);
  void Tick();
  const std::string& worker_id() const { return config_.worker_id; }
  int64_t jobs_done() const { return jobs_done_; }
  bool busy() const { return job_.has_value(); }
  nlohmann::json Details() const;

 private:
  using ExperimentKey = std::pair<std::string, int64_t>;
  enum class Phase { kFetching, kComputing, kPublishing };
  struct Job {
    identify_request_t request{};
    int attempt = 0;
    Phase phase = Phase::kFetching;
    int64_t start_us = 0, last_renew_us = 0, last_replay_us = 0, last_publish_us = 0;
    int64_t replay_id = 0;
    int replays = 0;
    bool logger_complete = false;
    std::future<model_result_t> future;
    model_result_t result{};
  };
  void OnRequest(const std::string& channel, const uint8_t* data, size_t size);
  void OnClaim(const std::string& channel, const uint8_t* data, size_t size);
  void OnBlock(const uint8_t* data, size_t size);
  void OnStatus(const uint8_t* data, size_t size);
  void OnReplayDone(const uint8_t* data, size_t size);
  void OnAck(const std::string& channel, const uint8_t* data, size_t size);
  void SendClaim(const identify_request_t& request);
  void RequestReplay();
  bool HaveCompleteRecord(const Job& job) const;
  void StartCompute();
  void Fail(const std::string& message);
  void FinishJob();

  Transport& transport_;
  WorkerConfig config_;
  StatusReporter reporter_;
  std::map<ExperimentKey, std::map<int64_t, measurement_block_t>> cache_;
  std::deque<ExperimentKey> cache_order_;
  std::map<ExperimentKey, int64_t> blocks_total_;  // from the rig's final status
  std::map<ExperimentKey, experiment_status_t> ends_;  // the rig's final status
  EnvelopeVerifier verifier_;
  std::optional<EnvelopeSigner> signer_;
  std::map<int64_t, identify_request_t> offers_;
  std::set<int64_t> finished_;
  int64_t claiming_ = 0, last_claim_us_ = 0, claim_start_us_ = 0;
  std::optional<Job> job_;
  int64_t claim_seq_ = 0, replay_counter_ = 0, jobs_done_ = 0, replayed_blocks_ = 0;
  std::string last_message_;
};

}  // namespace idrig
