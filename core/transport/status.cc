#include "core/transport/status.h"

#include <unistd.h>

#include "core/transport/channels.h"

namespace idrig {

std::string HostName() {
  char name[256] = {0};
  if (gethostname(name, sizeof(name) - 1) != 0) return "unknown";
  return name;
}

StatusReporter::StatusReporter(Transport& transport, std::string service, std::string instance_id,
                               double period_s)
    : transport_(transport),
      service_(std::move(service)),
      instance_id_(std::move(instance_id)),
      host_(HostName()),
      period_s_(period_s),
      start_utime_(NowMicros()) {}

service_status_t StatusReporter::Snapshot(const std::string& state,
                                          const std::string& details_json) const {
  const TransportCounters& c = transport_.counters();
  service_status_t s;
  s.utime = NowMicros();
  s.seq = seq_;
  s.service = service_;
  s.instance_id = instance_id_;
  s.host = host_;
  s.pid = static_cast<int32_t>(getpid());
  s.state = state;
  s.uptime_s = 1e-6 * static_cast<double>(s.utime - start_utime_);
  s.received = c.received;
  s.published = c.published;
  s.dropped = c.dropped;
  s.undecodable = c.undecodable;
  s.foreign = c.foreign;
  s.oversized = c.oversized;
  s.unsigned_count = c.unsigned_count;
  s.forged = c.forged;
  s.replayed = c.replayed;
  s.over_limit = c.over_limit;
  s.handler_errors = c.handler_errors;
  s.details_json = details_json;
  return s;
}

bool StatusReporter::Maybe(const std::string& state, const std::string& details_json, bool force) {
  const int64_t now = NowMicros();
  if (!force && now - last_utime_ < static_cast<int64_t>(period_s_ * 1e6)) return false;
  last_utime_ = now;
  service_status_t s = Snapshot(state, details_json);
  ++seq_;
  // Details are trimmed so that a status stays one datagram.
  if (s.details_json.size() > 50000) s.details_json = "{\"truncated\":true}";
  transport_.PublishMessage(StatusChannel(service_), s);
  return true;
}

ExperimentStatusPublisher::ExperimentStatusPublisher(Transport& transport, std::string channel,
                                                     double period_s)
    : transport_(transport), channel_(std::move(channel)), period_s_(period_s) {}

void ExperimentStatusPublisher::Publish(const experiment_status_t& status) {
  experiment_status_t s = status;
  s.utime = NowMicros();
  s.seq = seq_++;
  transport_.PublishMessage(channel_, s);
}

void ExperimentStatusPublisher::Finished(const experiment_status_t& status) {
  Publish(status);
  recent_.push_back(status);
  if (recent_.size() > 8) recent_.pop_front();
}

bool ExperimentStatusPublisher::Due() {
  const int64_t now = NowMicros();
  if (now - last_utime_ < static_cast<int64_t>(period_s_ * 1e6)) return false;
  last_utime_ = now;
  return true;
}

nlohmann::json ExperimentStatusPublisher::RecentJson(bool with_counts) const {
  nlohmann::json recent = nlohmann::json::array();
  for (const auto& s : recent_) {
    nlohmann::json j = {
        {"experiment_id", s.experiment_id}, {"state", s.state}, {"message", s.message}};
    if (with_counts) {
      j["samples"] = s.samples_total;
      j["blocks"] = s.blocks_total;
    }
    recent.push_back(j);
  }
  return recent;
}

}  // namespace idrig
