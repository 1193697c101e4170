// idrig-logger's class over memq://: the header peek agrees with the full decode, gaps are
// found by sequence number, a replay re-publishes exactly the missing blocks, and a full
// queue drops (and counts) instead of blocking.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <idrig/experiment_status_t.hpp>
#include <idrig/measurement_block_t.hpp>
#include <idrig/replay_done_t.hpp>
#include <idrig/replay_request_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "core/transport/channels.h"
#include "services/logger/logger_service.h"

namespace idrig {
namespace {

measurement_block_t Block(int64_t seq) {
  measurement_block_t b{};
  b.utime = 1000 + seq;
  b.rig_id = "rig-l";
  b.experiment_id = 9;
  b.seq = seq;
  b.first_sample = 4 * seq;
  b.sample_time_s = 0.01;
  b.n_samples = 4;
  b.n_inputs = 1;
  b.n_outputs = 1;
  b.u.assign(4, {static_cast<double>(seq)});
  b.y.assign(4, {-static_cast<double>(seq)});
  return b;
}

std::string TempPath(const std::string& name) {
  const std::string path = ::testing::TempDir() + "/" + name + "_" + std::to_string(getpid());
  for (const char* suffix : {"", "-wal", "-shm"}) std::remove((path + suffix).c_str());
  return path;
}

TEST(Logger, HeaderPeekAgreesWithDecode) {
  const measurement_block_t b = Block(12345);
  std::vector<uint8_t> bytes(b.getEncodedSize());
  b.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  MeasurementHeader h;
  ASSERT_TRUE(PeekMeasurementHeader(bytes.data(), bytes.size(), &h));
  EXPECT_EQ(h.rig_id, "rig-l");
  EXPECT_EQ(h.experiment_id, 9);
  EXPECT_EQ(h.seq, 12345);
  EXPECT_EQ(h.first_sample, 4 * 12345);
  EXPECT_EQ(h.n_samples, 4);
  EXPECT_EQ(h.utime, 1000 + 12345);
  EXPECT_FALSE(PeekMeasurementHeader(bytes.data(), 20, &h));  // truncated
  bytes[0] ^= 1;
  EXPECT_FALSE(PeekMeasurementHeader(bytes.data(), bytes.size(), &h));  // another type
}

TEST(Logger, FindsGapsAndReplaysWhatIsMissing) {
  auto t = MakeLcmTransport("memq://");
  LoggerConfig config;
  config.db_path = TempPath("logger_gaps.db");
  config.recover_period_s = 100;  // no recovery requests in this test
  LoggerService logger(*t, config);
  std::vector<int64_t> replayed;
  replay_done_t done{};
  t->Subscribe("IDRIG/rig-l/REPLAY", [&](const std::string&, const uint8_t* d, size_t n) {
    measurement_block_t b;
    if (Decode(d, n, &b, nullptr)) replayed.push_back(b.seq);
  });
  t->Subscribe("IDRIG/rig-l/REPLAY_DONE", [&](const std::string&, const uint8_t* d, size_t n) {
    Decode(d, n, &done, nullptr);
  });
  for (int64_t seq : {0, 1, 2, 4, 5, 7}) t->PublishMessage("IDRIG/rig-l/MEAS", Block(seq));
  experiment_status_t status{};
  status.source = "rig";
  status.rig_id = "rig-l";
  status.experiment_id = 9;
  status.state = experiment_status_t::STATE_DONE;
  status.blocks_total = 9;
  status.samples_total = 36;
  t->PublishMessage("IDRIG/rig-l/EXP_STATUS", status);
  for (int i = 0; i < 5; ++i) logger.Poll(5);
  logger.Flush();
  replay_request_t request{};
  request.replay_id = 31;
  request.requester = "test";
  request.rig_id = "rig-l";
  request.experiment_id = 9;
  request.have_seqs = {0, 1, 2};
  request.n_have = 3;
  t->PublishMessage("IDRIG/rig-l/REPLAY_REQ", request);
  for (int i = 0; i < 5; ++i) logger.Poll(5);
  logger.Flush();
  for (int i = 0; i < 5; ++i) logger.Poll(5);
  EXPECT_EQ(replayed, (std::vector<int64_t>{4, 5, 7}));
  EXPECT_EQ(done.replay_id, 31);
  EXPECT_TRUE(done.ended);
  EXPECT_FALSE(done.complete);
  EXPECT_EQ(done.blocks_total, 9);
  EXPECT_EQ(done.missing_seqs, (std::vector<int64_t>{3, 6, 8}));
  EXPECT_EQ(logger.stored_blocks(), 6);
}

TEST(Logger, AlsoWritesAnLcmlogThatLcmReadsAndARestartAppendsToIt) {
  auto t = MakeLcmTransport("memq://");
  LoggerConfig config;
  config.db_path = TempPath("logger_lcmlog.db");
  config.lcmlog_path = TempPath("logger.lcmlog");
  // Two runs of the logger (a restart): the second appends, the first run's events stay.
  for (const auto& run : {std::vector<int64_t>{0, 1}, std::vector<int64_t>{2}}) {
    t = MakeLcmTransport("memq://");  // a new process: its own transport
    LoggerService logger(*t, config);
    for (int64_t seq : run) t->PublishMessage("IDRIG/rig-l/MEAS", Block(seq));
    for (int i = 0; i < 5; ++i) logger.Poll(5);
    logger.Flush();
  }
  lcm::LogFile log(config.lcmlog_path, "r");
  ASSERT_TRUE(log.good());
  std::vector<int64_t> seqs;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    EXPECT_EQ(e->channel, "IDRIG/rig-l/MEAS");
    measurement_block_t b;
    ASSERT_GT(b.decode(e->data, 0, e->datalen), 0);
    seqs.push_back(b.seq);
  }
  EXPECT_EQ(seqs, (std::vector<int64_t>{0, 1, 2}));
}

TEST(Logger, AFullQueueDropsAndCounts) {
  auto t = MakeLcmTransport("memq://");
  LoggerConfig config;
  config.db_path = TempPath("logger_full.db");
  config.queue_capacity = 0;  // every message overflows
  LoggerService logger(*t, config);
  t->PublishMessage("IDRIG/rig-l/MEAS", Block(0));
  t->PublishMessage("IDRIG/rig-l/MEAS", Block(1));
  for (int i = 0; i < 3; ++i) logger.Poll(5);
  EXPECT_EQ(t->counters().dropped, 2);
  EXPECT_EQ(logger.stored_blocks(), 0);
}

}  // namespace
}  // namespace idrig
