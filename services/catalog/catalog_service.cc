#include "services/catalog/catalog_service.h"

#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_claim_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <idrig/model_result_t.hpp>
#include <idrig/result_ack_t.hpp>

#include "core/transport/channels.h"
#include "core/transport/service_util.h"

namespace idrig {

CatalogConfig CatalogConfig::FromJson(const nlohmann::json& c) {
  CatalogConfig config;
  config.db_path = ConfigValue<std::string>(c, "db_path", config.db_path);
  config.lease_s = ConfigValue<double>(c, "lease_s", config.lease_s);
  config.offer_period_s = ConfigValue<double>(c, "offer_period_s", config.offer_period_s);
  return config;
}

CatalogService::CatalogService(Transport& transport, CatalogConfig config)
    : transport_(transport),
      config_(std::move(config)),
      catalog_(config_.db_path),
      reporter_(transport, "catalog", "catalog-" + HostName()) {
  auto subscribe = [this](ChannelKind kind,
                          void (CatalogService::*handler)(const uint8_t*, size_t)) {
    transport_.Subscribe(
        AnyRigChannel(kind),
        [this, handler](const std::string&, const uint8_t* d, size_t n) { (this->*handler)(d, n); },
        10000);
  };
  subscribe(ChannelKind::kIdentifyRequest, &CatalogService::OnIdentifyRequest);
  subscribe(ChannelKind::kClaim, &CatalogService::OnClaim);
  subscribe(ChannelKind::kResult, &CatalogService::OnResult);
  subscribe(ChannelKind::kExperimentStatus, &CatalogService::OnExperimentStatus);
}

void CatalogService::OnIdentifyRequest(const uint8_t* data, size_t size) {
  identify_request_t request;
  if (!Decode(data, size, &request, &transport_.counters(), 65536)) return;
  if (request.requested_by == "catalog-offer") return;  // our own re-offer
  JobRecord job;
  job.request_id = request.request_id;
  job.rig_id = request.rig_id;
  job.experiment_id = request.experiment_id;
  job.method = request.method;
  job.options_json = request.options_json.empty() ? "{}" : request.options_json;
  job.requested_by = request.requested_by;
  job.created_utime = NowMicros();
  catalog_.AddJob(job);
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
  transport_.PublishMessage(Channel(rig_id, ChannelKind::kClaim), reply);
}

void CatalogService::OnClaim(const uint8_t* data, size_t size) {
  identify_claim_t claim;
  if (!Decode(data, size, &claim, &transport_.counters(), 65536)) return;
  if (claim.kind != identify_claim_t::KIND_CLAIM) return;  // our own replies
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

void CatalogService::OnResult(const uint8_t* data, size_t size) {
  model_result_t result;
  if (!Decode(data, size, &result, &transport_.counters(), 65536)) return;
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
  }
  ack.utime = NowMicros();
  transport_.PublishMessage(Channel(result.rig_id, ChannelKind::kAck), ack);
  ++acks_;
  SendClaim(result.rig_id, result.request_id, identify_claim_t::KIND_DONE, result.worker_id,
            result.attempt);
}

void CatalogService::OnExperimentStatus(const uint8_t* data, size_t size) {
  experiment_status_t status;
  if (!Decode(data, size, &status, &transport_.counters(), 65536)) return;
  ExperimentRecord e;
  e.rig_id = status.rig_id;
  e.experiment_id = status.experiment_id;
  static const char* names[] = {"pending", "running", "done", "stopped", "failed"};
  e.state = status.state >= 0 && status.state <= 4 ? names[status.state] : "unknown";
  e.start_utime = status.start_utime;
  e.end_utime = status.end_utime;
  if (status.source == "excite") {
    e.signal_spec = status.signal_spec;
    e.sample_rate_hz = status.sample_rate_hz;
    if (status.state == experiment_status_t::STATE_DONE) e.state = "running";  // the rig decides
  } else {
    e.samples_total = status.samples_total;
    e.blocks_total = status.blocks_total;
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
        transport_.PublishMessage(Channel(job.rig_id, ChannelKind::kIdentifyRequest), offer);
      }
    } catch (const std::exception&) {
      ++transport_.counters().handler_errors;
    }
  }
  if (reporter_.Due()) reporter_.Maybe("running", Details().dump(), true);
}

nlohmann::json CatalogService::Details() {
  nlohmann::json d;
  d["db_path"] = config_.db_path;
  d["stored"] = stored_;
  d["duplicates"] = duplicates_;
  d["acks"] = acks_;
  d["grants"] = grants_;
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
