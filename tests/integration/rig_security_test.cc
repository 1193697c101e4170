// The simulated rig refuses forged, replayed, unsigned and over-limit commands, and goes to
// its safe input when commands stop (watchdog). Over memq:// with the real RigSim class.
#include <gtest/gtest.h>

#include <chrono>
#include <idrig/actuator_command_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/measurement_block_t.hpp>
#include <thread>

#include "core/transport/channels.h"
#include "services/rig_sim/rig_sim.h"

namespace idrig {
namespace {

const HmacKey kKey(32, 3);

class RigSecurity : public ::testing::Test {
 protected:
  void SetUp() override {
    transport_ = MakeLcmTransport("memq://");
    RigSimConfig config;
    config.rig_id = "rig-s";
    TransferFunction first_order;  // 1/(s + 1)
    first_order.num = Eigen::VectorXd::Ones(1);
    first_order.den = Eigen::Vector2d(1.0, 1.0);
    config.plant = first_order;
    config.max_abs = 2.0;
    config.max_rate = 100.0;  // units/s
    config.watchdog_s = 0.3;
    config.safe_input = 0.0;
    config.block_samples = 5;
    config.keys[1] = kKey;
    rig_ = std::make_unique<RigSim>(*transport_, config);
    transport_->Subscribe("IDRIG/rig-s/MEAS",
                          [this](const std::string&, const uint8_t* d, size_t n) {
                            measurement_block_t b;
                            if (Decode(d, n, &b, nullptr)) blocks_.push_back(b);
                          });
    transport_->Subscribe("IDRIG/rig-s/EXP_STATUS",
                          [this](const std::string&, const uint8_t* d, size_t n) {
                            experiment_status_t s;
                            if (Decode(d, n, &s, nullptr)) last_status_ = s;
                          });
  }
  actuator_command_t Command(int64_t seq, int64_t first, std::vector<double> u, int32_t flags = 0) {
    actuator_command_t c{};
    c.utime = NowMicros();
    c.seq = seq;
    c.key_id = 1;
    c.rig_id = "rig-s";
    c.experiment_id = 77;
    c.first_sample = first;
    c.sample_rate_hz = 100.0;
    c.flags = flags;
    c.n_samples = static_cast<int32_t>(u.size());
    c.u = std::move(u);
    std::fill(std::begin(c.hmac), std::end(c.hmac), 0);
    return c;
  }
  void Send(const actuator_command_t& c) {
    transport_->PublishMessage("IDRIG/rig-s/CMD", c);
    for (int i = 0; i < 3; ++i) rig_->Poll(5);
  }
  int64_t Samples() const {
    int64_t n = 0;
    for (const auto& b : blocks_) n += b.n_samples;
    return n;
  }
  std::unique_ptr<Transport> transport_;
  std::unique_ptr<RigSim> rig_;
  std::vector<measurement_block_t> blocks_;
  experiment_status_t last_status_{};
};

TEST_F(RigSecurity, AppliesSignedCommandsAndRefusesForgedReplayedUnsigned) {
  actuator_command_t good = Command(10, 0, {0.1, 0.2, 0.3, 0.4, 0.5});
  SignCommand(&good, kKey);
  Send(good);
  EXPECT_EQ(Samples(), 5);
  EXPECT_DOUBLE_EQ(rig_->applied_input(), 0.5);

  Send(good);  // the same signed message again
  EXPECT_EQ(transport_->counters().replayed, 1);

  actuator_command_t forged = Command(11, 5, {0.6, 0.7, 0.8, 0.9, 1.0});
  SignCommand(&forged, kKey);
  forged.u[2] = 1.9;  // changed after signing
  Send(forged);
  EXPECT_EQ(transport_->counters().forged, 1);

  actuator_command_t other_key = Command(12, 5, {0.6, 0.7, 0.8, 0.9, 1.0});
  SignCommand(&other_key, HmacKey(32, 4));
  Send(other_key);
  EXPECT_EQ(transport_->counters().forged, 2);

  Send(Command(13, 5, {0.6, 0.7, 0.8, 0.9, 1.0}));  // not signed
  EXPECT_EQ(transport_->counters().unsigned_count, 1);

  // None of the refused commands moved the actuator or produced data.
  EXPECT_EQ(Samples(), 5);
  EXPECT_DOUBLE_EQ(rig_->applied_input(), 0.5);
  EXPECT_EQ(transport_->counters().handler_errors, 0);
}

TEST_F(RigSecurity, RefusesOverLimitCommandsAndGoesSafe) {
  actuator_command_t good = Command(20, 0, {0.5, 0.5, 0.5, 0.5, 0.5});
  SignCommand(&good, kKey);
  Send(good);
  ASSERT_TRUE(rig_->running());
  // |u| = 2.5 above max_abs = 2, validly signed: refused, experiment aborted, safe input.
  actuator_command_t too_big = Command(21, 5, {0.5, 0.5, 2.5, 0.5, 0.5});
  SignCommand(&too_big, kKey);
  Send(too_big);
  EXPECT_EQ(transport_->counters().over_limit, 1);
  EXPECT_FALSE(rig_->running());
  EXPECT_DOUBLE_EQ(rig_->applied_input(), 0.0);
  EXPECT_EQ(last_status_.state, experiment_status_t::STATE_FAILED);
  EXPECT_NE(last_status_.message.find("above the rig's limit"), std::string::npos)
      << last_status_.message;
  EXPECT_EQ(Samples(), 5);
  // A jump of 1.5 in one sample at 100 Hz is 150 units/s, above max_rate = 100.
  actuator_command_t too_fast = Command(22, 0, {1.5});
  too_fast.experiment_id = 78;
  SignCommand(&too_fast, kKey);
  Send(too_fast);
  EXPECT_EQ(transport_->counters().over_limit, 2);
  EXPECT_FALSE(rig_->running());
}

// Found by tests/fuzz/fuzz_handlers (timeout-194c7745): a validly signed command of the running
// experiment starting at sample 4·10^18 made the rig hold its input over the "lost" samples in
// a loop that never ended. Now refused before any sample is applied: the experiment fails at
// once, naming the limit, and no block is published for it.
TEST_F(RigSecurity, ACommandFarBeyondTheSampleLimitEndsTheExperimentAtOnce) {
  actuator_command_t good = Command(30, 0, {0.5, 0.5, 0.5, 0.5, 0.5});
  SignCommand(&good, kKey);
  Send(good);
  ASSERT_TRUE(rig_->running());
  actuator_command_t far = Command(31, 4000000000000000000, {0.5});
  SignCommand(&far, kKey);
  Send(far);
  EXPECT_FALSE(rig_->running());
  EXPECT_EQ(last_status_.state, experiment_status_t::STATE_FAILED);
  EXPECT_NE(last_status_.message.find("beyond the rig's maximum of 10000000 samples"),
            std::string::npos)
      << last_status_.message;
  EXPECT_EQ(Samples(), 5);
  EXPECT_EQ(transport_->counters().handler_errors, 0);
}

// fuzz_handlers timeout-46135f21: a signed command far ahead (but within max_samples) made the
// rig hold its input over millions of "lost" samples. A gap is held only as long as the
// watchdog would have let the rig wait: here 0.3 s × 100 Hz + one block (5) = 35 samples.
TEST_F(RigSecurity, AGapLongerThanTheWatchdogAllowsEndsTheExperiment) {
  actuator_command_t good = Command(40, 0, {0.5, 0.5, 0.5, 0.5, 0.5});
  SignCommand(&good, kKey);
  Send(good);
  actuator_command_t near = Command(41, 5 + 35, {0.5});  // a gap of 35: held
  SignCommand(&near, kKey);
  Send(near);
  ASSERT_TRUE(rig_->running());
  actuator_command_t far = Command(42, 41 + 36, {0.5});  // a gap of 36: refused
  SignCommand(&far, kKey);
  Send(far);
  EXPECT_FALSE(rig_->running());
  EXPECT_EQ(last_status_.state, experiment_status_t::STATE_FAILED);
  EXPECT_NE(last_status_.message.find("a gap longer than the watchdog"), std::string::npos)
      << last_status_.message;
  EXPECT_EQ(Samples(), 41);  // the five, the 35 held and the one of the near command
  EXPECT_EQ(transport_->counters().handler_errors, 0);
}

TEST_F(RigSecurity, WatchdogAppliesTheSafeInputWhenCommandsStop) {
  actuator_command_t good = Command(30, 0, {0.4, 0.8, 1.2});
  SignCommand(&good, kKey);
  Send(good);
  EXPECT_TRUE(rig_->running());
  EXPECT_DOUBLE_EQ(rig_->applied_input(), 1.2);
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(600);
  while (std::chrono::steady_clock::now() < end) rig_->Poll(10);
  EXPECT_FALSE(rig_->running());
  EXPECT_DOUBLE_EQ(rig_->applied_input(), 0.0);
  EXPECT_EQ(last_status_.state, experiment_status_t::STATE_FAILED);
  EXPECT_NE(last_status_.message.find("watchdog"), std::string::npos);
  EXPECT_EQ(Samples(), 3);  // the partial block was flushed
}

TEST_F(RigSecurity, UndecodableAndForeignMessagesAreCountedNotThrown) {
  const uint8_t garbage[3] = {9, 9, 9};
  transport_->Publish("IDRIG/rig-s/CMD", garbage, sizeof(garbage));
  measurement_block_t wrong_type{};
  transport_->PublishMessage("IDRIG/rig-s/CMD", wrong_type);
  for (int i = 0; i < 3; ++i) rig_->Poll(5);
  EXPECT_EQ(transport_->counters().undecodable, 1);
  EXPECT_EQ(transport_->counters().foreign, 1);
  EXPECT_EQ(transport_->counters().handler_errors, 0);
}

}  // namespace
}  // namespace idrig
