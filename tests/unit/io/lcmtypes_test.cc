// The lcm-gen'd C++ type encodes and decodes (and a wrong fingerprint is refused).
#include <gtest/gtest.h>

#include <idrig/measurement_block_t.hpp>
#include <vector>

TEST(LcmTypes, MeasurementBlockRoundTrip) {
  idrig::measurement_block_t block;
  block.utime = 1700000000000000;
  block.rig_id = "rig-a";
  block.experiment_id = 7;
  block.seq = 3;
  block.first_sample = 300;
  block.sample_time_s = 0.01;
  block.n_samples = 100;
  block.n_inputs = 1;
  block.n_outputs = 2;
  block.u.assign(100, std::vector<double>(1, 0.5));
  block.y.assign(100, std::vector<double>(2, -1.25));
  std::vector<uint8_t> buffer(block.getEncodedSize());
  ASSERT_EQ(block.encode(buffer.data(), 0, buffer.size()), static_cast<int>(buffer.size()));
  EXPECT_LT(buffer.size(), 60000u);
  idrig::measurement_block_t back;
  ASSERT_EQ(back.decode(buffer.data(), 0, buffer.size()), static_cast<int>(buffer.size()));
  EXPECT_EQ(back.rig_id, "rig-a");
  EXPECT_EQ(back.y[99][1], -1.25);
  buffer[0] ^= 0xff;  // corrupt the fingerprint
  EXPECT_LT(back.decode(buffer.data(), 0, buffer.size()), 0);
}
