#pragma once
// idrig-catalog: the single writer of the SQLite catalogue (core/catalog/catalog.h).
//  - identify_request_t -> a job (idempotent by request_id); pending jobs and jobs whose lease
//    expired are offered again every offer_period_s (re-published on IDENT_REQ).
//  - identify_claim_t CLAIM -> GRANT to one worker at a time (lease_s), DENY to others, DONE
//    when the job is finished: each job runs once, and again only if its worker vanished.
//  - model_result_t -> stored once per request_id (committed, synchronous=FULL) -> result_ack_t.
//  - experiment_status_t -> the experiments table (lineage of every model).
#include <map>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>

#include "core/catalog/catalog.h"
#include "core/transport/auth.h"
#include "core/transport/status.h"
#include "core/transport/transport.h"

namespace idrig {

struct CatalogConfig {
  std::string db_path = "idrig-catalog.db";
  double lease_s = 5.0;         // a worker must renew its claim within this time
  double offer_period_s = 1.0;  // how often open jobs are offered again
  KeyRing keys;                 // operator (requests, replies) and service (claims, results) keys
  std::string state_dir;        // replay marks ("" = memory only)
  double auth_window_s = 300;
  // Keys "db_path", "lease_s", "offer_period_s", "operator_key_file", "service_key_file",
  // "state_dir", "auth_window_s".
  static CatalogConfig FromJson(const nlohmann::json& config);
  // std::invalid_argument naming a missing key; the constructor calls it.
  void Validate() const;
};

class CatalogService {
 public:
  CatalogService(Transport& transport, CatalogConfig config);
  void Poll(int timeout_ms);
  void Tick();
  Catalog& catalog() { return catalog_; }
  nlohmann::json Details();

 private:
  void OnIdentifyRequest(const std::string& channel, const uint8_t* data, size_t size);
  void OnClaim(const std::string& channel, const uint8_t* data, size_t size);
  void OnResult(const std::string& channel, const uint8_t* data, size_t size);
  void OnExperimentStatus(const std::string& channel, const uint8_t* data, size_t size);
  // Why a new identify request cannot be a job ("" when it can).
  std::string Refusal(const std::string& rig_id, int64_t experiment_id, const std::string& method,
                      const std::string& options_json);
  void Reply(const std::string& rig_id, int64_t request_id, int64_t experiment_id, int32_t state,
             int64_t model_id, const std::string& message);
  void ReplyWithJobState(const JobRecord& job);
  void SendClaim(const std::string& rig_id, int64_t request_id, int32_t kind,
                 const std::string& worker_id, int attempt);

  Transport& transport_;
  CatalogConfig config_;
  Catalog catalog_;
  StatusReporter reporter_;
  int64_t start_utime_;
  EnvelopeVerifier verifier_;
  std::optional<EnvelopeSigner> service_signer_, operator_signer_;
  int64_t refused_requests_ = 0, refused_results_ = 0;
  int64_t claim_seq_ = 0, last_offer_us_ = 0;
  std::map<std::string, std::string> last_experiment_state_;
  int64_t stored_ = 0, duplicates_ = 0, acks_ = 0, grants_ = 0;
};

}  // namespace idrig
