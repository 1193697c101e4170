#pragma once
// Periodic full-state status (procman style): every service publishes a service_status_t on
// IDRIG/STATUS/<service> about once a second, with the transport's counters and its own state
// as JSON, so a restarted peer or an lcm-spy window catches up from a single message.
#include <idrig/service_status_t.hpp>
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

std::string HostName();

}  // namespace idrig
