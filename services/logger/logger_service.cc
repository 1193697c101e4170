#include "services/logger/logger_service.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <idrig/actuator_command_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/measurement_block_t.hpp>
#include <idrig/replay_done_t.hpp>
#include <idrig/replay_request_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "core/transport/channels.h"
#include "core/transport/service_util.h"

namespace idrig {

bool PeekMeasurementHeader(const uint8_t* data, size_t size, MeasurementHeader* h) {
  // LCM encoding, big-endian: fingerprint (8), utime (8), rig_id (int32 length incl. NUL, bytes),
  // experiment_id (8), seq (8), first_sample (8), sample_time_s (8), n_samples (4), ...
  size_t pos = 0;
  auto read = [&](int bytes, uint64_t* out) {
    if (pos + bytes > size) return false;
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v = (v << 8) | data[pos + i];
    pos += bytes;
    *out = v;
    return true;
  };
  uint64_t v = 0;
  if (!read(8, &v) || v != static_cast<uint64_t>(measurement_block_t::getHash())) return false;
  if (!read(8, &v)) return false;
  h->utime = static_cast<int64_t>(v);
  if (!read(4, &v) || v < 1 || v > 64 || pos + v > size) return false;
  h->rig_id.assign(reinterpret_cast<const char*>(data + pos), v - 1);
  pos += v;
  if (!read(8, &v)) return false;
  h->experiment_id = static_cast<int64_t>(v);
  if (!read(8, &v)) return false;
  h->seq = static_cast<int64_t>(v);
  if (!read(8, &v)) return false;
  h->first_sample = static_cast<int64_t>(v);
  if (!read(8, &v)) return false;  // sample_time_s
  if (!read(4, &v)) return false;
  h->n_samples = static_cast<int32_t>(v);
  return true;
}

LoggerConfig LoggerConfig::FromJson(const nlohmann::json& c) {
  LoggerConfig config;
  config.db_path = ConfigValue<std::string>(c, "db_path", config.db_path);
  config.queue_capacity = ConfigValue<size_t>(c, "queue_capacity", config.queue_capacity);
  config.lcm_queue_capacity = ConfigValue<int>(c, "lcm_queue_capacity", config.lcm_queue_capacity);
  config.recover_period_s = ConfigValue<double>(c, "recover_period_s", config.recover_period_s);
  config.recover_window_s = ConfigValue<double>(c, "recover_window_s", config.recover_window_s);
  config.lcmlog_path = ConfigValue<std::string>(c, "lcmlog_path", config.lcmlog_path);
  return config;
}

struct LoggerService::Writer {
  explicit Writer(const std::string& db_path) : store(db_path) {}
  ExperimentStore store;
  std::unique_ptr<lcm::LogFile> lcmlog;
  std::chrono::steady_clock::time_point last_summary =
      std::chrono::steady_clock::now() - std::chrono::seconds(10);
};

LoggerService::LoggerService(Transport& transport, LoggerConfig config)
    : transport_(transport),
      config_(std::move(config)),
      reporter_(transport, "logger", "logger-" + HostName()) {
  // Open once here so that a bad path fails at start, not in the writer thread.
  if (config_.writer_thread) {
    ExperimentStore check(config_.db_path);
  } else {
    inline_writer_ = OpenWriter();
  }
  auto subscribe = [this](ChannelKind channel, Kind kind) {
    transport_.Subscribe(
        AnyRigChannel(channel),
        [this, kind](const std::string& channel, const uint8_t* d, size_t n) {
          Enqueue(kind, channel, d, n);
        },
        config_.lcm_queue_capacity);
  };
  subscribe(ChannelKind::kMeasurement, Kind::kMeasurement);
  subscribe(ChannelKind::kCommand, Kind::kCommand);
  subscribe(ChannelKind::kExperimentStatus, Kind::kStatus);
  subscribe(ChannelKind::kReplayRequest, Kind::kReplayRequest);
  if (config_.writer_thread) writer_ = std::thread([this] { WriterLoop(); });
}

LoggerService::~LoggerService() {
  if (!writer_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  writer_.join();
}

void LoggerService::Enqueue(Kind kind, const std::string& channel, const uint8_t* data,
                            size_t size) {
  if (size > 65536) {
    ++transport_.counters().oversized;
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.size() >= config_.queue_capacity) {
      ++transport_.counters().dropped;
      return;
    }
    queue_.push_back({kind, NowMicros(), channel, std::vector<uint8_t>(data, data + size)});
    if (queue_.size() > peak_queue_) peak_queue_ = queue_.size();
    if (queue_.size() > 1) return;  // the writer is awake already (or will look again)
  }
  wake_.notify_one();
}

std::unique_ptr<LoggerService::Writer> LoggerService::OpenWriter() {
  auto writer = std::make_unique<Writer>(config_.db_path);
  if (!config_.lcmlog_path.empty()) {
    // Appended, never truncated: a restart (systemd's Restart=always after a crash) keeps the
    // log of everything recorded before.
    writer->lcmlog = std::make_unique<lcm::LogFile>(config_.lcmlog_path, "a");
    if (!writer->lcmlog->good()) {
      ++transport_.counters().handler_errors;
      spdlog::error("cannot append to the .lcmlog '{}': not written", config_.lcmlog_path);
      writer->lcmlog.reset();
    } else {
      spdlog::info("appending to the .lcmlog '{}'", config_.lcmlog_path);
    }
  }
  return writer;
}

void LoggerService::WriteBatch(Writer& writer, const std::deque<Item>& batch) {
  if (batch.empty()) return;
  ExperimentStore& store = writer.store;
  try {
    store.Begin();
    std::vector<const Item*> replays;
    for (const Item& item : batch) {
      if (item.kind == Kind::kReplayRequest) {
        replays.push_back(&item);
        continue;
      }
      try {  // one message that cannot be stored must not lose the rest of the batch
        Store(store, item);
      } catch (const std::exception& e) {
        ++transport_.counters().handler_errors;
        spdlog::error("a message on {} was not stored: {}", item.channel, e.what());
      }
      if (writer.lcmlog) {
        lcm::LogEvent event;
        event.eventnum = 0;  // numbered by the log file
        event.timestamp = item.recv_utime;
        event.channel = item.channel;
        event.datalen = static_cast<int32_t>(item.bytes.size());
        event.data = const_cast<uint8_t*>(item.bytes.data());
        writer.lcmlog->writeEvent(&event);
      }
    }
    if (writer.lcmlog) fflush(writer.lcmlog->getFilePtr());
    store.Commit();
    // Replays after the commit: they see everything received before them.
    for (const Item* item : replays) Replay(store, *item);
  } catch (const std::exception& e) {
    ++transport_.counters().handler_errors;
    spdlog::error("the writer failed on a batch of {} message(s): {}", batch.size(), e.what());
    try {
      store.Commit();
    } catch (...) {
    }
  }
}

void LoggerService::MaybeRecover(Writer& writer) {
  const auto now = std::chrono::steady_clock::now();
  if (now - writer.last_summary <
      std::chrono::milliseconds(static_cast<int>(config_.recover_period_s * 1000)))
    return;
  writer.last_summary = now;
  try {
    RecoverLosses(writer.store);
    UpdateSummary(writer.store);
  } catch (const std::exception& e) {
    ++transport_.counters().handler_errors;
    spdlog::error("the loss recovery failed: {}", e.what());
  }
}

void LoggerService::WriterLoop() {
  std::unique_ptr<Writer> writer = OpenWriter();
  for (;;) {
    std::deque<Item> batch;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait_for(lock, std::chrono::milliseconds(100),
                     [this] { return stop_ || !queue_.empty(); });
      if (stop_ && queue_.empty()) break;
      batch.swap(queue_);
      in_flight_ = batch.size();
    }
    WriteBatch(*writer, batch);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      in_flight_ = 0;
    }
    drained_.notify_all();
    MaybeRecover(*writer);
  }
}

void LoggerService::WriteQueued() {
  std::deque<Item> batch;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    batch.swap(queue_);
  }
  WriteBatch(*inline_writer_, batch);
}

void LoggerService::Store(ExperimentStore& store, const Item& item) {
  const uint8_t* data = item.bytes.data();
  const size_t size = item.bytes.size();
  if (item.kind == Kind::kMeasurement) {
    // Only the header is read (the samples stay encoded in the BLOB): fast enough for
    // tens of thousands of blocks per second.
    MeasurementHeader h;
    if (!PeekMeasurementHeader(data, size, &h)) {
      measurement_block_t probe;  // classify the failure for the counters
      Decode(data, size, &probe, &transport_.counters());
      return;
    }
    if (!IsRigOfChannel(h.rig_id, item.channel)) return ++wrong_rig_, void();
    StoredBlock b;
    b.seq = h.seq;
    b.first_sample = h.first_sample;
    b.n_samples = h.n_samples;
    b.utime = h.utime;
    b.recv_utime = item.recv_utime;
    b.data = item.bytes;
    if (store.AddBlock(h.rig_id, h.experiment_id, b))
      ++stored_blocks_;
    else
      ++duplicates_;
  } else if (item.kind == Kind::kCommand) {
    actuator_command_t command;
    if (!Decode(data, size, &command, &transport_.counters())) return;
    if (!IsRigOfChannel(command.rig_id, item.channel)) return ++wrong_rig_, void();
    StoredBlock b;
    b.seq = command.seq;
    b.first_sample = command.first_sample;
    b.n_samples = command.n_samples;
    b.utime = command.utime;
    b.recv_utime = item.recv_utime;
    b.data = item.bytes;
    if (store.AddCommand(command.rig_id, command.experiment_id, b)) ++stored_commands_;
  } else if (item.kind == Kind::kStatus) {
    experiment_status_t status;
    if (!Decode(data, size, &status, &transport_.counters())) return;
    if (!IsRigOfChannel(status.rig_id, item.channel)) return ++wrong_rig_, void();
    // SQLite binds NaN as NULL: the insert failed, and with it the rest of the writer's batch
    // (fuzz_worker_logger crash-bfd01bbe; the catalogue's crash-417cbf93).
    if (!std::isfinite(status.sample_rate_hz) || status.sample_rate_hz < 0) {
      spdlog::warn("experiment status of {} experiment {} dropped: sample rate {}", status.rig_id,
                   status.experiment_id, status.sample_rate_hz);
      return;
    }
    StoredExperiment e;
    e.rig_id = status.rig_id;
    e.experiment_id = status.experiment_id;
    e.updated_utime = item.recv_utime;
    if (status.source == "excite") {
      e.signal_spec = status.signal_spec;
      e.sample_rate_hz = status.sample_rate_hz;
    } else if (status.source == "rig") {
      e.sample_rate_hz = status.sample_rate_hz;
      e.ended = status.state != experiment_status_t::STATE_RUNNING &&
                status.state != experiment_status_t::STATE_PENDING;
      if (e.ended) {
        e.blocks_total = status.blocks_total;
        e.samples_total = status.samples_total;
      }
    }
    store.UpdateExperiment(e);
  }
}

void LoggerService::Replay(ExperimentStore& store, const Item& item) {
  replay_request_t request;
  if (!Decode(item.bytes.data(), item.bytes.size(), &request, &transport_.counters())) return;
  // The answer goes to Channel(request.rig_id), which throws on a rig id that is not the
  // channel's (fuzz_worker_logger crash-b2725de8: the batch's replays were lost).
  if (!IsRigOfChannel(request.rig_id, item.channel)) return ++wrong_rig_, void();
  ++replays_;
  const std::set<int64_t> have(request.have_seqs.begin(), request.have_seqs.end());
  const std::string replay_channel = Channel(request.rig_id, ChannelKind::kReplay);
  int sent = 0;
  for (const StoredBlock& b : store.Blocks(request.rig_id, request.experiment_id, have)) {
    transport_.Publish(replay_channel, b.data.data(), b.data.size());
    if (++sent % config_.replay_pause_every == 0)
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  replay_done_t done{};
  done.utime = NowMicros();
  done.replay_id = request.replay_id;
  done.requester = request.requester;
  done.rig_id = request.rig_id;
  done.experiment_id = request.experiment_id;
  StoredExperiment e;
  if (store.FindExperiment(request.rig_id, request.experiment_id, &e)) {
    done.ended = e.ended;
    done.blocks_total = e.blocks_total;
    done.samples_total = e.samples_total;
  }
  done.missing_seqs = store.MissingBlocks(request.rig_id, request.experiment_id, 4000);
  done.n_missing = static_cast<int32_t>(done.missing_seqs.size());
  done.complete = done.ended && done.n_missing == 0;
  done.n_sent = sent;
  transport_.PublishMessage(Channel(request.rig_id, ChannelKind::kReplayDone), done);
}

// Blocks lost between the rig and us: once the rig reports the experiment ended (and so its
// blocks_total), ask the rig to re-send what is missing (it keeps recent experiments).
void LoggerService::RecoverLosses(ExperimentStore& store) {
  const int64_t now = NowMicros();
  for (const StoredExperiment& e : store.Experiments()) {
    if (!e.ended || e.blocks_stored >= e.blocks_total) continue;
    if (now - e.updated_utime > static_cast<int64_t>(config_.recover_window_s * 1e6)) continue;
    replay_request_t request{};
    request.utime = now;
    request.replay_id = ++recovery_requests_;
    request.requester = "logger";
    request.rig_id = e.rig_id;
    request.experiment_id = e.experiment_id;
    for (int64_t seq : store.BlockSeqs(e.rig_id, e.experiment_id)) request.have_seqs.push_back(seq);
    request.n_have = static_cast<int32_t>(request.have_seqs.size());
    transport_.PublishMessage(Channel(e.rig_id, ChannelKind::kRigReplayRequest), request);
  }
}

void LoggerService::UpdateSummary(ExperimentStore& store) {
  nlohmann::json list = nlohmann::json::array();
  auto experiments = store.Experiments();
  const size_t first = experiments.size() > 10 ? experiments.size() - 10 : 0;
  for (size_t i = first; i < experiments.size(); ++i) {
    const StoredExperiment& e = experiments[i];
    const std::vector<int64_t> shown = store.MissingBlocks(e.rig_id, e.experiment_id, 50);
    const int64_t missing_count = store.MissingCount(e.rig_id, e.experiment_id);
    // Commands the logger did not hear (it was down, or they were lost): named by sample range.
    // The measured u in the blocks is what the rig applied, so the record stays consistent.
    nlohmann::json without_command = nlohmann::json::array();
    if (e.ended)
      for (const auto& [first, last] :
           store.SamplesWithoutCommand(e.rig_id, e.experiment_id, e.samples_total))
        if (without_command.size() < 20) without_command.push_back({first, last});
    list.push_back({{"rig_id", e.rig_id},
                    {"experiment_id", e.experiment_id},
                    {"blocks", e.blocks_stored},
                    {"commands", e.commands_stored},
                    {"ended", e.ended},
                    {"blocks_total", e.blocks_total},
                    {"missing_count", missing_count},
                    {"missing", shown},
                    {"samples_without_command", without_command},
                    {"complete", e.ended && missing_count == 0}});
  }
  std::lock_guard<std::mutex> lock(summary_mutex_);
  summary_ = list;
}

void LoggerService::Flush() {
  if (inline_writer_) return WriteQueued();
  std::unique_lock<std::mutex> lock(mutex_);
  drained_.wait(lock, [this] { return queue_.empty() && in_flight_ == 0; });
}

nlohmann::json LoggerService::Details() {
  nlohmann::json d;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    d["queue"] = queue_.size();
  }
  d["queue_capacity"] = config_.queue_capacity;
  d["peak_queue"] = peak_queue_.load();
  d["db_path"] = config_.db_path;
  d["stored_blocks"] = stored_blocks_.load();
  d["stored_commands"] = stored_commands_.load();
  d["duplicates"] = duplicates_.load();
  d["replays"] = replays_.load();
  d["wrong_rig"] = wrong_rig_.load();  // messages naming another rig than their channel's
  d["recovery_requests"] = recovery_requests_.load();
  std::lock_guard<std::mutex> lock(summary_mutex_);
  d["experiments"] = summary_;
  return d;
}

void LoggerService::Poll(int timeout_ms) {
  transport_.Handle(timeout_ms);
  if (inline_writer_) {  // what the writer thread does: store, then recover when due
    WriteQueued();
    MaybeRecover(*inline_writer_);
  }
  if (reporter_.Due()) reporter_.Maybe("running", Details().dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), true);
}

}  // namespace idrig
