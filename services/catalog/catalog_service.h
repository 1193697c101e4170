#pragma once
// idrig-catalog: the single writer of the SQLite catalogue (core/catalog/catalog.h).
//  - identify_request_t -> a job (idempotent by request_id); pending jobs and jobs whose lease
//    expired are offered again every offer_period_s (re-published on IDENT_REQ).
//  - identify_claim_t CLAIM -> GRANT to one worker at a time (lease_s), DENY to others, DONE
//    when the job is finished: each job runs once, and again only if its worker vanished.
//  - model_result_t -> stored once per request_id (committed, synchronous=FULL) -> result_ack_t.
//  - experiment_status_t -> the experiments table (lineage of every model).
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "core/catalog/catalog.h"
#include "core/transport/status.h"
#include "core/transport/transport.h"

namespace idrig {

struct CatalogConfig {
  std::string db_path = "idrig-catalog.db";
  double lease_s = 5.0;         // a worker must renew its claim within this time
  double offer_period_s = 1.0;  // how often open jobs are offered again
  static CatalogConfig FromJson(const nlohmann::json& config);
};

class CatalogService {
 public:
  CatalogService(Transport& transport, CatalogConfig config);
  void Poll(int timeout_ms);
  void Tick();
  Catalog& catalog() { return catalog_; }
  nlohmann::json Details();

 private:
  void OnIdentifyRequest(const uint8_t* data, size_t size);
  void OnClaim(const uint8_t* data, size_t size);
  void OnResult(const uint8_t* data, size_t size);
  void OnExperimentStatus(const uint8_t* data, size_t size);
  void SendClaim(const std::string& rig_id, int64_t request_id, int32_t kind,
                 const std::string& worker_id, int attempt);

  Transport& transport_;
  CatalogConfig config_;
  Catalog catalog_;
  StatusReporter reporter_;
  int64_t claim_seq_ = 0, last_offer_us_ = 0;
  std::map<std::string, std::string> last_experiment_state_;
  int64_t stored_ = 0, duplicates_ = 0, acks_ = 0, grants_ = 0;
};

}  // namespace idrig
