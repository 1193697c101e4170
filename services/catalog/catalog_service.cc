#include "services/catalog/catalog_service.h"

#include <cmath>
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_claim_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <idrig/model_result_t.hpp>
#include <idrig/request_reply_t.hpp>
#include <idrig/result_ack_t.hpp>
#include <spdlog/spdlog.h>

#include "core/methods/registry.h"

#include "core/transport/channels.h"
#include "core/transport/service_util.h"

namespace idrig {

CatalogConfig CatalogConfig::FromJson(const nlohmann::json& c) {
  CatalogConfig config;
  config.db_path = ConfigValue<std::string>(c, "db_path", config.db_path);
  config.lease_s = ConfigValue<double>(c, "lease_s", config.lease_s);
  config.offer_period_s = ConfigValue<double>(c, "offer_period_s", config.offer_period_s);
  config.keys = KeyRing::FromConfig(c);
  config.state_dir = ConfigValue<std::string>(c, "state_dir", config.state_dir);
  config.auth_window_s = ConfigValue<double>(c, "auth_window_s", config.auth_window_s);
  return config;
}

void CatalogConfig::Validate() const {
  for (const char* role : {kOperatorRole, kServiceRole})
    if (!keys.Has(role))
      throw std::invalid_argument(std::string("idrig-catalog needs the ") + role + " key (" + role +
                                  "_key_file): requests, claims and results are signed");
}

CatalogService::CatalogService(Transport& transport, CatalogConfig config)
    : transport_(transport),
      config_(std::move(config)),
      catalog_(config_.db_path),
      reporter_(transport, "catalog", "catalog-" + HostName()),
      start_utime_(NowMicros()),
      verifier_(config_.keys,
                config_.state_dir.empty() ? "" : config_.state_dir + "/catalog-senders.hwm",
                config_.auth_window_s, "idrig-catalog") {
  config_.Validate();
  service_signer_.emplace(kServiceRole, *config_.keys.Find(kServiceRole), reporter_.instance_id());
  operator_signer_.emplace(kOperatorRole, *config_.keys.Find(kOperatorRole), reporter_.instance_id());
  auto subscribe = [this](ChannelKind kind, void (CatalogService::*handler)(
                                                const std::string&, const uint8_t*, size_t)) {
    transport_.Subscribe(
        AnyRigChannel(kind),
        [this, handler](const std::string& c, const uint8_t* d, size_t n) {
          (this->*handler)(c, d, n);
        },
        10000);
  };
  subscribe(ChannelKind::kIdentifyRequest, &CatalogService::OnIdentifyRequest);
  subscribe(ChannelKind::kClaim, &CatalogService::OnClaim);
  subscribe(ChannelKind::kResult, &CatalogService::OnResult);
  subscribe(ChannelKind::kExperimentStatus, &CatalogService::OnExperimentStatus);
}

std::string CatalogService::Refusal(const std::string& rig_id, int64_t experiment_id,
                                    const std::string& method, const std::string& options_json) {
  try {
    FindMethod(method);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  const nlohmann::json options = nlohmann::json::parse(options_json, nullptr, false);
  if (!options.is_object()) return "options must be a JSON object, got '" + options_json + "'";
  for (const ExperimentRecord& e : catalog_.Experiments(rig_id)) {
    if (e.experiment_id != experiment_id) continue;
    if (e.state == "interrupted" && options.value("segment", "") != "longest_complete")
      return "experiment " + std::to_string(experiment_id) + " of rig " + rig_id +
             " was interrupted (samples 0.." + std::to_string(e.samples_total - 1) + " of " +
             std::to_string(e.samples_planned) + " planned measured; " + e.message + "): add \"segment\": \"longest_complete\" to the options to identify from them";
    if (e.state == "failed" || e.state == "stopped")
      if (options.value("segment", "") != "longest_complete")
        return "experiment " + std::to_string(experiment_id) + " of rig " + rig_id + " " + e.state +
               ": add \"segment\": \"longest_complete\" to the options to use what was measured";
    return "";
  }
  return "experiment " + std::to_string(experiment_id) + " of rig " + rig_id +
         " is unknown to the catalogue (no status of it was heard)";
}

void CatalogService::Reply(const std::string& rig_id, int64_t request_id, int64_t experiment_id,
                           int32_t state, int64_t model_id, const std::string& message) {
  request_reply_t reply{};
  reply.utime = NowMicros();
  reply.request_id = request_id;
  reply.rig_id = rig_id;
  reply.experiment_id = experiment_id;
  reply.source = "catalog";
  reply.state = state;
  reply.model_id = model_id;
  reply.message = message;
  operator_signer_->Publish(transport_, Channel(rig_id, ChannelKind::kRequestReply), reply);
}

void CatalogService::ReplyWithJobState(const JobRecord& job) {
  int64_t model_id = 0;
  int32_t state = request_reply_t::STATE_ACCEPTED;
  std::string message = job.message.empty() ? "job " + job.state : job.message;
  if (job.state == "done") {
    state = request_reply_t::STATE_DONE;
    if (auto m = catalog_.ModelForRequest(job.request_id)) model_id = m->model_id;
    message = "by " + job.worker_id + ", attempt " + std::to_string(job.attempts);
  } else if (job.state == "failed") {
    state = request_reply_t::STATE_FAILED;
  }
  Reply(job.rig_id, job.request_id, job.experiment_id, state, model_id, message);
}

void CatalogService::OnIdentifyRequest(const std::string& channel, const uint8_t* data,
                                       size_t size) {
  identify_request_t request;
  Sender who;
  if (!verifier_.Open(channel, data, size, {kOperatorRole, kServiceRole}, &request, &who,
                      &transport_.counters()))
    return;
  if (who.role == kServiceRole) return;  // a re-offer (ours, or another catalogue's)
  if (!IsRigOfChannel(request.rig_id, channel)) return;
  if (auto existing = catalog_.Job(request.request_id)) return ReplyWithJobState(*existing);
  const std::string options = request.options_json.empty() ? "{}" : request.options_json;
  const std::string why = Refusal(request.rig_id, request.experiment_id, request.method, options);
  if (!why.empty() && why.find("unknown to the catalogue") != std::string::npos &&
      NowMicros() - start_utime_ < 3000000) {
    // Just started: the rigs' periodic status of their recent experiments may not have arrived
    // yet. No answer: the command line re-sends, and is answered once we know.
    return;
  }
  if (!why.empty()) {
    ++refused_requests_;
    spdlog::warn("identify request {} from {} refused: {}", request.request_id, who.id, why);
    return Reply(request.rig_id, request.request_id, request.experiment_id,
                 request_reply_t::STATE_REFUSED, 0, why);
  }
  JobRecord job;
  job.request_id = request.request_id;
  job.rig_id = request.rig_id;
  job.experiment_id = request.experiment_id;
  job.method = request.method;
  job.options_json = options;
  job.requested_by = request.requested_by.empty() ? who.id : request.requested_by;
  job.created_utime = NowMicros();
  catalog_.AddJob(job);
  spdlog::info("job {} accepted from {}: {} on experiment {} of rig {}", job.request_id, who.id,
               job.method, job.experiment_id, job.rig_id);
  Reply(request.rig_id, request.request_id, request.experiment_id, request_reply_t::STATE_ACCEPTED,
        0, "job pending");
}

void CatalogService::SendClaim(const std::string& rig_id, int64_t request_id, int32_t kind,
                               const std::string& worker_id, int attempt) {
  identify_claim_t reply{};
  reply.utime = NowMicros();
  reply.seq = claim_seq_++;
  reply.request_id = request_id;
  reply.rig_id = rig_id;
  reply.kind = kind;
  reply.worker_id = worker_id;
  reply.attempt = attempt;
  reply.lease_s = config_.lease_s;
  service_signer_->Publish(transport_, Channel(rig_id, ChannelKind::kClaim), reply);
}

void CatalogService::OnClaim(const std::string& channel, const uint8_t* data, size_t size) {
  identify_claim_t claim;
  Sender who;
  if (!verifier_.Open(channel, data, size, {kServiceRole}, &claim, &who, &transport_.counters()))
    return;
  if (claim.kind != identify_claim_t::KIND_CLAIM) return;  // our own replies
  // The answer goes to Channel(claim.rig_id): a rig id that is not the channel's (e.g. "si`1",
  // found by tests/fuzz/fuzz_handlers) made Channel() throw out of this handler.
  if (!IsRigOfChannel(claim.rig_id, channel)) return;
  if (who.id != claim.worker_id) {
    spdlog::warn("claim for job {} refused: signed by {} for worker {}", claim.request_id, who.id,
                 claim.worker_id);
    return;
  }
  JobRecord job;
  const ClaimOutcome outcome = catalog_.Claim(claim.request_id, claim.worker_id, NowMicros(),
                                              static_cast<int64_t>(config_.lease_s * 1e6), &job);
  switch (outcome) {
    case ClaimOutcome::kGranted:
      ++grants_;
      SendClaim(claim.rig_id, claim.request_id, identify_claim_t::KIND_GRANT, claim.worker_id,
                job.attempts);
      break;
    case ClaimOutcome::kDenied:
      SendClaim(claim.rig_id, claim.request_id, identify_claim_t::KIND_DENY, job.worker_id,
                job.attempts);
      break;
    case ClaimOutcome::kDone:
      SendClaim(claim.rig_id, claim.request_id, identify_claim_t::KIND_DONE, job.worker_id,
                job.attempts);
      break;
    case ClaimOutcome::kUnknown:
      break;  // the request has not reached us yet; the worker asks again
  }
}

void CatalogService::OnResult(const std::string& channel, const uint8_t* data, size_t size) {
  model_result_t result;
  Sender who;
  if (!verifier_.Open(channel, data, size, {kServiceRole}, &result, &who, &transport_.counters()))
    return;
  // Only the worker the catalogue granted the job to may answer it (a request nobody made, or
  // one leased to another worker, is refused: no ack, nothing stored).
  const std::optional<JobRecord> job = catalog_.Job(result.request_id);
  std::string why;
  if (who.id != result.worker_id)
    why = "signed by " + who.id + " for worker " + result.worker_id;
  else if (!job)
    why = "no such job";
  else if (job->worker_id != result.worker_id)
    why = "job leased to " + (job->worker_id.empty() ? std::string("nobody") : job->worker_id) +
          ", not " + result.worker_id;
  else if (job->rig_id != result.rig_id || job->experiment_id != result.experiment_id ||
           job->method != result.method)
    why = "rig, experiment or method differ from the job's";
  if (!why.empty()) {
    ++refused_results_;
    const int64_t n = refused_results_;
    if (n <= 20 || n % 1000 == 0)
      spdlog::warn("result for request {} refused: {} [{} so far]", result.request_id, why, n);
    return;
  }
  result_ack_t ack{};
  ack.request_id = result.request_id;
  ack.rig_id = result.rig_id;
  ack.worker_id = result.worker_id;
  if (result.ok) {
    ModelRecord m;
    m.request_id = result.request_id;
    m.rig_id = result.rig_id;
    m.experiment_id = result.experiment_id;
    m.method = result.method;
    m.options_json = result.options_json;
    m.data_hash = result.data_hash;
    m.software_version = result.software_version;
    m.worker_id = result.worker_id;
    m.n_samples = result.n_samples;
    m.sample_time_s = result.sample_time_s;
    m.created_utime = NowMicros();
    m.compute_s = result.compute_s;
    nlohmann::json report = nlohmann::json::parse(result.report_json, nullptr, false);
    if (report.is_discarded() || !report.contains("model")) {
      ++transport_.counters().undecodable;
      return;  // no ack: a result without a model is not stored
    }
    if (report.contains("fit_percent") && report["fit_percent"].is_number())
      m.fit_percent = report["fit_percent"].get<double>();
    if (report.contains("status") && report["status"].is_string()) m.status = report["status"];
    m.model_json = report["model"].dump();
    m.report_json = result.report_json;
    const auto [model_id, inserted] = catalog_.StoreModel(m, ModelMetrics(report));
    // A gap diagnosis (method gap-diagnose) also goes to the diagnosis reports, with its lineage.
    if (report.contains("details") && report["details"].is_object() &&
        report["details"].value("format", "") == "idrig.gap/1")
      catalog_.StoreDiagnosis(m.request_id, m.rig_id, model_id, m.experiment_id,
                              report["details"].dump(), m.created_utime);
    ack.model_id = model_id;
    ack.duplicate = !inserted;
    inserted ? ++stored_ : ++duplicates_;
  } else {
    catalog_.FailJob(result.request_id, result.worker_id, result.message, NowMicros());
    spdlog::warn("job {} failed on {}: {}", result.request_id, result.worker_id, result.message);
  }
  ack.utime = NowMicros();
  service_signer_->Publish(transport_, Channel(result.rig_id, ChannelKind::kAck), ack);
  if (auto finished = catalog_.Job(result.request_id)) ReplyWithJobState(*finished);
  ++acks_;
  SendClaim(result.rig_id, result.request_id, identify_claim_t::KIND_DONE, result.worker_id,
            result.attempt);
}

void CatalogService::OnExperimentStatus(const std::string&, const uint8_t* data, size_t size) {
  experiment_status_t status;
  if (!Decode(data, size, &status, &transport_.counters(), 65536)) return;
  ExperimentRecord e;
  e.rig_id = status.rig_id;
  e.experiment_id = status.experiment_id;
  static const char* names[] = {"pending", "running", "done", "stopped", "failed", "interrupted"};
  e.state = status.state >= 0 && status.state <= 5 ? names[status.state] : "unknown";
  e.start_utime = status.start_utime;
  e.end_utime = status.end_utime;
  if (status.source == "excite") {
    // Status is unsigned (readers need no key): an implausible one is dropped, with a line that
    // says why, instead of failing the insert (fuzz_handlers crash-417cbf93: a NaN rate).
    if (!std::isfinite(status.sample_rate_hz) || status.sample_rate_hz < 0) {
      spdlog::warn("experiment status of {}/{} from excite dropped: sample rate {} is not a rate",
                   status.rig_id, status.experiment_id, status.sample_rate_hz);
      return;
    }
    e.signal_spec = status.signal_spec;
    e.sample_rate_hz = status.sample_rate_hz;
    e.samples_planned = status.samples_total;
    if (status.state == experiment_status_t::STATE_DONE) e.state = "running";  // the rig decides
  } else {
    e.samples_total = status.samples_total;
    e.blocks_total = status.blocks_total;
    if (status.state != experiment_status_t::STATE_RUNNING) e.message = status.message;
  }
  // Status is re-sent periodically: write only what changed.
  const std::string key = e.rig_id + "/" + std::to_string(e.experiment_id) + "/" + status.source;
  const std::string value = e.state + "/" + std::to_string(status.samples_total) + "/" +
                            std::to_string(status.blocks_total) + "/" + e.signal_spec;
  auto& last = last_experiment_state_[key];
  if (last == value) return;
  last = value;
  catalog_.UpsertExperiment(e);
}

void CatalogService::Tick() {
  const int64_t now = NowMicros();
  if (now - last_offer_us_ >= static_cast<int64_t>(config_.offer_period_s * 1e6)) {
    last_offer_us_ = now;
    try {
      for (const JobRecord& job : catalog_.JobsToOffer(now)) {
        identify_request_t offer{};
        offer.utime = now;
        offer.request_id = job.request_id;
        offer.rig_id = job.rig_id;
        offer.experiment_id = job.experiment_id;
        offer.method = job.method;
        offer.options_json = job.options_json;
        offer.requested_by = "catalog-offer";
        service_signer_->Publish(transport_, Channel(job.rig_id, ChannelKind::kIdentifyRequest),
                                 offer);
      }
    } catch (const std::exception&) {
      ++transport_.counters().handler_errors;
    }
  }
  if (reporter_.Due()) reporter_.Maybe("running", Details().dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), true);
}

nlohmann::json CatalogService::Details() {
  nlohmann::json d;
  d["db_path"] = config_.db_path;
  d["stored"] = stored_;
  d["duplicates"] = duplicates_;
  d["acks"] = acks_;
  d["grants"] = grants_;
  d["refused_requests"] = refused_requests_;
  d["refused_results"] = refused_results_;
  d["auth"] = verifier_.Details();
  try {
    d["models"] = catalog_.CountModels();
    nlohmann::json jobs = nlohmann::json::object();
    for (const auto& j : catalog_.Jobs()) jobs[j.state] = jobs.value(j.state, 0) + 1;
    d["jobs"] = jobs;
  } catch (...) {
  }
  return d;
}

void CatalogService::Poll(int timeout_ms) {
  transport_.Handle(timeout_ms);
  Tick();
}

}  // namespace idrig
