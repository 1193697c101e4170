#include "services/worker/worker_service.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_claim_t.hpp>
#include <idrig/replay_done_t.hpp>
#include <idrig/replay_request_t.hpp>
#include <idrig/result_ack_t.hpp>
#include <spdlog/spdlog.h>
#include <thread>

#include "core/io/model_json.h"
#include "core/methods/registry.h"
#include "core/numeric/validation.h"
#include "core/transport/channels.h"
#include "core/transport/service_util.h"
#include "core/transport/signing.h"

namespace idrig {

WorkerConfig WorkerConfig::FromJson(const nlohmann::json& c) {
  WorkerConfig config;
  config.worker_id = ConfigValue<std::string>(c, "worker_id", config.worker_id);
  config.claim_retry_s = ConfigValue<double>(c, "claim_retry_s", config.claim_retry_s);
  config.renew_s = ConfigValue<double>(c, "renew_s", config.renew_s);
  config.result_retry_s = ConfigValue<double>(c, "result_retry_s", config.result_retry_s);
  config.replay_retry_s = ConfigValue<double>(c, "replay_retry_s", config.replay_retry_s);
  config.data_timeout_s = ConfigValue<double>(c, "data_timeout_s", config.data_timeout_s);
  config.debug_delay_s = ConfigValue<double>(c, "debug_delay_s", config.debug_delay_s);
  config.cache_experiments = ConfigValue<int>(c, "cache_experiments", config.cache_experiments);
  config.keys = KeyRing::FromConfig(c);
  config.state_dir = ConfigValue<std::string>(c, "state_dir", config.state_dir);
  config.auth_window_s = ConfigValue<double>(c, "auth_window_s", config.auth_window_s);
  return config;
}

void WorkerConfig::Validate() const {
  if (!keys.Has(kServiceRole))
    throw std::invalid_argument(
        "idrig-worker needs the service key (service_key_file): claims and results are signed");
}

IoRecord AssembleRecord(const std::map<int64_t, measurement_block_t>& blocks,
                        int64_t blocks_total) {
  if (blocks_total <= 0) throw std::invalid_argument("the experiment has no measurement blocks");
  int64_t samples = 0;
  int inputs = -1, outputs = -1;
  double ts = 0.0;
  for (int64_t seq = 0; seq < blocks_total; ++seq) {
    auto it = blocks.find(seq);
    if (it == blocks.end())
      throw std::invalid_argument("block " + std::to_string(seq) + " is missing");
    const measurement_block_t& b = it->second;
    if (b.first_sample != samples)
      throw std::invalid_argument("block " + std::to_string(seq) + " starts at sample " +
                                  std::to_string(b.first_sample) + ", expected " +
                                  std::to_string(samples));
    if (inputs < 0) {
      inputs = b.n_inputs;
      outputs = b.n_outputs;
      ts = b.sample_time_s;
    } else if (b.n_inputs != inputs || b.n_outputs != outputs || b.sample_time_s != ts) {
      throw std::invalid_argument("block " + std::to_string(seq) + " changes channels or Ts");
    }
    samples += b.n_samples;
  }
  Eigen::MatrixXd u(samples, inputs), y(samples, outputs);
  for (int64_t seq = 0; seq < blocks_total; ++seq) {
    const measurement_block_t& b = blocks.at(seq);
    for (int i = 0; i < b.n_samples; ++i) {
      for (int c = 0; c < inputs; ++c) u(b.first_sample + i, c) = b.u[i][c];
      for (int c = 0; c < outputs; ++c) y(b.first_sample + i, c) = b.y[i][c];
    }
  }
  return MakeIoRecord(u, y, ts);
}

std::string RecordHash(const IoRecord& record) {
  std::vector<double> data;
  data.reserve(1 + record.u.size() + record.y.size());
  data.push_back(record.sample_time);
  for (int r = 0; r < record.u.rows(); ++r)
    for (int c = 0; c < record.u.cols(); ++c) data.push_back(record.u(r, c));
  for (int r = 0; r < record.y.rows(); ++r)
    for (int c = 0; c < record.y.cols(); ++c) data.push_back(record.y(r, c));
  return Sha256Hex(data.data(), data.size() * sizeof(double));
}

namespace {
std::string DefaultWorkerId() { return "worker-" + HostName() + "-" + std::to_string(getpid()); }
int64_t Us(double seconds) { return static_cast<int64_t>(seconds * 1e6); }
constexpr double kUnansweredClaimS = 3.0;

// Runs in the compute thread: no transport access here.
model_result_t Compute(identify_request_t request, IoRecord record, std::string worker_id,
                       int attempt, double debug_delay_s, nlohmann::json record_lineage) {
  model_result_t r{};
  r.request_id = request.request_id;
  r.rig_id = request.rig_id;
  r.experiment_id = request.experiment_id;
  r.worker_id = worker_id;
  r.attempt = attempt;
  r.method = request.method;
  r.options_json = request.options_json.empty() ? "{}" : request.options_json;
  r.software_version = IDRIG_VERSION;
  r.data_end_utime = NowMicros();
  r.n_samples = record.NumSamples();
  r.sample_time_s = record.sample_time;
  r.report_json = "{}";
  const auto start = std::chrono::steady_clock::now();
  try {
    r.data_hash = RecordHash(record);
    nlohmann::json options = nlohmann::json::parse(r.options_json);
    options.erase("segment");  // the worker's option (which samples), not the method's
    MethodReport report = RunMethod(request.method, record, options);
    nlohmann::json json = report.json;
    json["record"] = record_lineage;  // which samples were used, and the experiment's end
    // The same measure for every method: simulation fit 100·(1 − NRMSE) of the model on the
    // whole record (core/numeric/validation.h), so models of different methods compare.
    try {
      const Eigen::MatrixXd simulated =
          SimulateModelJson(json.at("model"), record.u, record.sample_time);  // about its operating point
      json["record_fit_percent"] = FitPercent(record.y, simulated)(0);
    } catch (const std::exception&) {
      // a model that cannot be simulated on the record has no record fit
    }
    std::string text = json.dump();
    if (text.size() > 50000 && json.contains("details")) {
      json["details"] = {{"trimmed", "details above 50 KB are not sent over LCM"}};
      text = json.dump();
    }
    r.ok = true;
    r.report_json = text;
    r.message = json.value("message", "");
  } catch (const std::exception& e) {
    r.ok = false;
    r.message = std::string("identification failed: ") + e.what();
  }
  if (debug_delay_s > 0) std::this_thread::sleep_for(std::chrono::microseconds(Us(debug_delay_s)));
  r.compute_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}
}  // namespace

WorkerService::WorkerService(Transport& transport, WorkerConfig config)
    : transport_(transport),
      config_([&] {
        if (config.worker_id.empty()) config.worker_id = DefaultWorkerId();
        return std::move(config);
      }()),
      reporter_(transport, "worker", config_.worker_id),
      verifier_(config_.keys,
                config_.state_dir.empty() ? "" : config_.state_dir + "/" + config_.worker_id + ".hwm",
                config_.auth_window_s, "idrig-worker") {
  config_.Validate();
  signer_.emplace(kServiceRole, *config_.keys.Find(kServiceRole), config_.worker_id);
  auto signed_subscribe = [this](ChannelKind kind,
                                 void (WorkerService::*handler)(const std::string&, const uint8_t*,
                                                                size_t)) {
    transport_.Subscribe(
        AnyRigChannel(kind),
        [this, handler](const std::string& c, const uint8_t* d, size_t n) {
          (this->*handler)(c, d, n);
        },
        1000);
  };
  auto subscribe = [this](ChannelKind kind, void (WorkerService::*handler)(const uint8_t*, size_t),
                          int capacity) {
    transport_.Subscribe(
        AnyRigChannel(kind),
        [this, handler](const std::string&, const uint8_t* d, size_t n) { (this->*handler)(d, n); },
        capacity);
  };
  signed_subscribe(ChannelKind::kIdentifyRequest, &WorkerService::OnRequest);
  signed_subscribe(ChannelKind::kClaim, &WorkerService::OnClaim);
  signed_subscribe(ChannelKind::kAck, &WorkerService::OnAck);
  subscribe(ChannelKind::kMeasurement, &WorkerService::OnBlock, 100000);
  subscribe(ChannelKind::kReplay, &WorkerService::OnBlock, 100000);
  subscribe(ChannelKind::kExperimentStatus, &WorkerService::OnStatus, 1000);
  subscribe(ChannelKind::kReplayDone, &WorkerService::OnReplayDone, 1000);
}

WorkerService::~WorkerService() {
  if (job_ && job_->future.valid()) job_->future.wait();
}

void WorkerService::OnRequest(const std::string& channel, const uint8_t* data, size_t size) {
  identify_request_t request;
  // From the command line (operator key, when this worker holds it) or re-offered by the
  // catalogue (service key). Without the operator key the worker waits for the re-offer.
  std::vector<std::string> roles = {kServiceRole};
  if (config_.keys.Has(kOperatorRole)) roles.push_back(kOperatorRole);
  if (!verifier_.Open(channel, data, size, roles, &request, nullptr, &transport_.counters()))
    return;
  // The claim goes to Channel(request.rig_id) from Tick(), outside any handler: a rig id that
  // is not the channel's made Channel() throw there and stopped the worker process.
  if (!IsRigOfChannel(request.rig_id, channel)) return;
  if (finished_.count(request.request_id)) return;
  if (job_ && job_->request.request_id == request.request_id) return;
  offers_.emplace(request.request_id, request);
}

void WorkerService::SendClaim(const identify_request_t& request) {
  identify_claim_t claim{};
  claim.utime = NowMicros();
  claim.seq = claim_seq_++;
  claim.request_id = request.request_id;
  claim.rig_id = request.rig_id;
  claim.kind = identify_claim_t::KIND_CLAIM;
  claim.worker_id = config_.worker_id;
  signer_->Publish(transport_, Channel(request.rig_id, ChannelKind::kClaim), claim);
}

void WorkerService::OnClaim(const std::string& channel, const uint8_t* data, size_t size) {
  identify_claim_t claim;
  if (!verifier_.Open(channel, data, size, {kServiceRole}, &claim, nullptr, &transport_.counters()))
    return;
  if (claim.kind == identify_claim_t::KIND_CLAIM) return;  // other workers' claims
  const int64_t id = claim.request_id;
  const bool mine = claim.worker_id == config_.worker_id;
  if (claim.kind == identify_claim_t::KIND_DONE) {
    finished_.insert(id);
    offers_.erase(id);
    if (claiming_ == id) claiming_ = 0;
    if (job_ && job_->request.request_id == id && job_->phase != Phase::kPublishing &&
        job_->phase != Phase::kComputing)
      job_.reset();  // someone else finished it
    return;
  }
  if (job_ && job_->request.request_id == id) {
    if (!mine) {  // our lease went to another worker: drop the job
      last_message_ = "lost the lease of job " + std::to_string(id) + " to " + claim.worker_id;
      if (job_->phase != Phase::kComputing) job_.reset();
    }
    return;
  }
  if (claiming_ != id) {
    if (!mine) offers_.erase(id);  // granted to someone else
    return;
  }
  claiming_ = 0;
  if (claim.kind == identify_claim_t::KIND_GRANT && mine && !job_) {
    auto offer = offers_.find(id);
    if (offer == offers_.end()) return;
    Job job;
    job.request = offer->second;
    job.attempt = claim.attempt;
    job.start_us = NowMicros();
    job.last_renew_us = job.start_us;
    offers_.erase(offer);
    job_ = std::move(job);
    last_message_ = "running job " + std::to_string(id) + " (" + job_->request.method + ")";
    if (HaveCompleteRecord(*job_))
      StartCompute();
    else
      RequestReplay();
  } else {
    offers_.erase(id);  // denied: the holder has it; the catalogue re-offers if it vanishes
  }
}

void WorkerService::OnBlock(const uint8_t* data, size_t size) {
  measurement_block_t block;
  if (!Decode(data, size, &block, &transport_.counters(), 65536)) return;
  const ExperimentKey key{block.rig_id, block.experiment_id};
  auto it = cache_.find(key);
  if (it == cache_.end()) {
    // Keep only the blocks of recent experiments, plus the one our job needs.
    while (static_cast<int>(cache_order_.size()) >= config_.cache_experiments) {
      const ExperimentKey old = cache_order_.front();
      cache_order_.pop_front();
      if (job_ && old == ExperimentKey{job_->request.rig_id, job_->request.experiment_id}) {
        cache_order_.push_back(old);
        if (cache_order_.size() == 1) break;
        continue;
      }
      cache_.erase(old);
    }
    cache_order_.push_back(key);
    it = cache_.emplace(key, std::map<int64_t, measurement_block_t>()).first;
  }
  it->second.emplace(block.seq, std::move(block));
}

void WorkerService::OnStatus(const uint8_t* data, size_t size) {
  experiment_status_t status;
  if (!Decode(data, size, &status, &transport_.counters(), 65536)) return;
  if (status.source != "rig" || status.state == experiment_status_t::STATE_RUNNING) return;
  blocks_total_[{status.rig_id, status.experiment_id}] = status.blocks_total;
  ends_[{status.rig_id, status.experiment_id}] = status;
  while (ends_.size() > 64) ends_.erase(ends_.begin());
}

bool WorkerService::HaveCompleteRecord(const Job& job) const {
  const ExperimentKey key{job.request.rig_id, job.request.experiment_id};
  auto total = blocks_total_.find(key);
  auto blocks = cache_.find(key);
  if (total == blocks_total_.end() || blocks == cache_.end() || total->second <= 0) return false;
  for (int64_t seq = 0; seq < total->second; ++seq)
    if (!blocks->second.count(seq)) return false;
  return true;
}

void WorkerService::RequestReplay() {
  Job& job = *job_;
  replay_request_t request{};
  request.utime = NowMicros();
  request.replay_id = (static_cast<int64_t>(getpid()) << 32) + (++replay_counter_);
  request.requester = config_.worker_id;
  request.rig_id = job.request.rig_id;
  request.experiment_id = job.request.experiment_id;
  auto blocks = cache_.find({job.request.rig_id, job.request.experiment_id});
  if (blocks != cache_.end())
    for (const auto& [seq, block] : blocks->second) request.have_seqs.push_back(seq);
  request.n_have = static_cast<int32_t>(request.have_seqs.size());
  job.replay_id = request.replay_id;
  job.last_replay_us = request.utime;
  ++job.replays;
  transport_.PublishMessage(Channel(job.request.rig_id, ChannelKind::kReplayRequest), request);
}

void WorkerService::OnReplayDone(const uint8_t* data, size_t size) {
  replay_done_t done;
  if (!Decode(data, size, &done, &transport_.counters(), 65536)) return;
  if (!job_ || job_->phase != Phase::kFetching || done.replay_id != job_->replay_id) return;
  replayed_blocks_ += done.n_sent;
  if (done.ended) blocks_total_[{done.rig_id, done.experiment_id}] = done.blocks_total;
  job_->logger_complete = done.complete;
  if (done.ended && !done.complete)
    last_message_ = "the logger's record of experiment " + std::to_string(done.experiment_id) +
                    " lacks " + std::to_string(done.n_missing) +
                    " block(s) (it is recovering them)";
  if (HaveCompleteRecord(*job_)) StartCompute();
  // Otherwise Tick() asks again after replay_retry_s (experiment still running, or replayed
  // blocks lost on the way).
}

void WorkerService::StartCompute() {
  Job& job = *job_;
  const ExperimentKey key{job.request.rig_id, job.request.experiment_id};
  IoRecord record;
  try {
    record = AssembleRecord(cache_.at(key), blocks_total_.at(key));
  } catch (const std::exception& e) {
    Fail(std::string("cannot assemble the record: ") + e.what());
    return;
  }
  // A record that did not end as planned (interrupted by a rig restart, failed, stopped) is
  // only used when the request asks for what was measured: {"segment": "longest_complete"}.
  nlohmann::json lineage = {{"first_sample", 0}, {"samples_used", record.NumSamples()},
                            {"experiment_state", "done"}};
  auto end = ends_.find(key);
  if (end != ends_.end() && end->second.state != experiment_status_t::STATE_DONE) {
    static const char* names[] = {"pending", "running", "done", "stopped", "failed", "interrupted"};
    const int32_t state = end->second.state;
    const std::string state_name = state >= 0 && state <= 5 ? names[state] : "unknown";
    const nlohmann::json options = nlohmann::json::parse(job.request.options_json, nullptr, false);
    if (!options.is_object() || options.value("segment", "") != "longest_complete") {
      Fail("experiment " + std::to_string(job.request.experiment_id) + " " + state_name + " (" +
           end->second.message + "): the record is incomplete; ask with "
           "{\"segment\": \"longest_complete\"} to identify from samples 0.." +
           std::to_string(record.NumSamples() - 1));
      return;
    }
    lineage["experiment_state"] = state_name;
    lineage["rig_message"] = end->second.message;
  }
  if (config_.compute_inline) {
    job.result = Compute(job.request, std::move(record), config_.worker_id, job.attempt,
                         config_.debug_delay_s, lineage);
    job.phase = Phase::kPublishing;
    job.last_publish_us = 0;
    return;
  }
  job.phase = Phase::kComputing;
  job.future = std::async(std::launch::async, Compute, job.request, std::move(record),
                          config_.worker_id, job.attempt, config_.debug_delay_s, lineage);
}

void WorkerService::Fail(const std::string& message) {
  Job& job = *job_;
  model_result_t r{};
  r.request_id = job.request.request_id;
  r.rig_id = job.request.rig_id;
  r.experiment_id = job.request.experiment_id;
  r.worker_id = config_.worker_id;
  r.attempt = job.attempt;
  r.ok = false;
  r.method = job.request.method;
  r.options_json = job.request.options_json;
  r.software_version = IDRIG_VERSION;
  r.message = message;
  r.report_json = "{}";
  job.result = r;
  job.phase = Phase::kPublishing;
  job.last_publish_us = 0;
  last_message_ = message;
  spdlog::warn("job {} failed: {}", job.request.request_id, message);
}

void WorkerService::OnAck(const std::string& channel, const uint8_t* data, size_t size) {
  result_ack_t ack;
  if (!verifier_.Open(channel, data, size, {kServiceRole}, &ack, nullptr, &transport_.counters()))
    return;
  if (!job_ || job_->phase != Phase::kPublishing || ack.request_id != job_->request.request_id)
    return;
  FinishJob();
}

void WorkerService::FinishJob() {
  finished_.insert(job_->request.request_id);
  ++jobs_done_;
  last_message_ = "job " + std::to_string(job_->request.request_id) + " acknowledged";
  job_.reset();
}

void WorkerService::Tick() {
  const int64_t now = NowMicros();
  if (job_) {
    Job& job = *job_;
    if (now - job.last_renew_us >= Us(config_.renew_s)) {
      job.last_renew_us = now;
      SendClaim(job.request);  // lease renewal
    }
    if (job.phase == Phase::kFetching) {
      if (HaveCompleteRecord(job))
        StartCompute();
      else if (now - job.start_us > Us(config_.data_timeout_s))
        Fail("no complete record of experiment " + std::to_string(job.request.experiment_id) +
             " within " + std::to_string(config_.data_timeout_s) + " s");
      else if (now - job.last_replay_us >= Us(config_.replay_retry_s))
        RequestReplay();
    }
    if (job_ && job_->phase == Phase::kComputing &&
        job_->future.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
      job_->result = job_->future.get();
      job_->phase = Phase::kPublishing;
      job_->last_publish_us = 0;
    }
    if (job_ && job_->phase == Phase::kPublishing &&
        now - job_->last_publish_us >= Us(config_.result_retry_s)) {
      job_->last_publish_us = now;
      job_->result.utime = now;
      signer_->Publish(transport_, Channel(job_->request.rig_id, ChannelKind::kResult),
                       job_->result);
    }
  } else if (!offers_.empty()) {
    // One claim at a time, oldest offer first; re-sent until the catalogue answers.
    auto offer = offers_.begin();
    if (claiming_ != 0 && offers_.count(claiming_)) offer = offers_.find(claiming_);
    if (claiming_ == offer->first && now - claim_start_us_ > Us(kUnansweredClaimS)) {
      // The catalogue does not know the job (it refused the request, or has not heard it):
      // drop the offer; the catalogue offers the job again if it accepts it later.
      offers_.erase(offer);
      claiming_ = 0;
    } else if (claiming_ != offer->first || now - last_claim_us_ >= Us(config_.claim_retry_s)) {
      if (claiming_ != offer->first) claim_start_us_ = now;
      claiming_ = offer->first;
      last_claim_us_ = now;
      SendClaim(offer->second);
    }
  }
  if (reporter_.Due()) reporter_.Maybe(job_ ? "busy" : "running", Details().dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), true);
}

nlohmann::json WorkerService::Details() const {
  nlohmann::json d;
  d["worker_id"] = config_.worker_id;
  d["jobs_done"] = jobs_done_;
  d["offers"] = offers_.size();
  d["replayed_blocks"] = replayed_blocks_;
  d["message"] = last_message_;
  d["auth"] = verifier_.Details();
  if (job_) {
    static const char* phases[] = {"fetching", "computing", "publishing"};
    d["job"] = {{"request_id", job_->request.request_id},         {"method", job_->request.method},
                {"experiment_id", job_->request.experiment_id},   {"attempt", job_->attempt},
                {"phase", phases[static_cast<int>(job_->phase)]}, {"replays", job_->replays}};
  }
  return d;
}

void WorkerService::Poll(int timeout_ms) {
  // While the compute thread runs, look at it every millisecond (no message would wake us).
  transport_.Handle(job_ && job_->phase == Phase::kComputing ? std::min(timeout_ms, 1)
                                                             : timeout_ms);
  Tick();
}

}  // namespace idrig
