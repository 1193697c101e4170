#pragma once
// Periodic full-state status (procman style): every service publishes a service_status_t on
// IDRIG/STATUS/<service> about once a second, with the transport's counters and its own state
// as JSON, so a restarted peer or an lcm-spy window catches up from a single message.
#include <deque>
#include <idrig/experiment_status_t.hpp>
#include <idrig/service_status_t.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "core/transport/transport.h"

namespace idrig {

class StatusReporter {
 public:
  StatusReporter(Transport& transport, std::string service, std::string instance_id,
                 double period_s = 1.0);
  // Publishes when the period has elapsed since the last one (or force). Returns true if sent.
  bool Maybe(const std::string& state, const std::string& details_json, bool force = false);
  // True when the period has elapsed (compute the details only then).
  bool Due() const { return NowMicros() - last_utime_ >= static_cast<int64_t>(period_s_ * 1e6); }
  service_status_t Snapshot(const std::string& state, const std::string& details_json) const;
  const std::string& instance_id() const { return instance_id_; }

 private:
  Transport& transport_;
  std::string service_, instance_id_, host_;
  double period_s_;
  int64_t start_utime_, last_utime_ = 0, seq_ = 0;
};

// The experiment status of a rig's side (idrig-excite, idrig-rig-sim) on
// IDRIG/<rig>/EXPERIMENT_STATUS: every copy stamped with the time and this publisher's seq;
// the last 8 finished experiments kept for the periodic full-state snapshot.
class ExperimentStatusPublisher {
 public:
  ExperimentStatusPublisher(Transport& transport, std::string channel, double period_s);
  void Publish(const experiment_status_t& status);
  // Publishes a finished experiment's status and keeps it in recent().
  void Finished(const experiment_status_t& status);
  // True when period_s has elapsed since the last time it returned true (true at first).
  bool Due();
  const std::deque<experiment_status_t>& recent() const { return recent_; }
  // recent() for a service's status details: experiment_id, state, message, and with
  // with_counts also samples (samples_total) and blocks (blocks_total).
  nlohmann::json RecentJson(bool with_counts) const;

 private:
  Transport& transport_;
  std::string channel_;
  double period_s_;
  int64_t seq_ = 0, last_utime_ = 0;
  std::deque<experiment_status_t> recent_;  // newest last
};

std::string HostName();

}  // namespace idrig
