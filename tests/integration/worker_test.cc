// The worker's record assembly from measurement blocks and the lineage data hash.
#include <gtest/gtest.h>

#include "core/transport/signing.h"
#include "services/worker/worker_service.h"

namespace idrig {
namespace {

measurement_block_t Block(int64_t seq, int64_t first, int n) {
  measurement_block_t b{};
  b.rig_id = "r";
  b.seq = seq;
  b.first_sample = first;
  b.sample_time_s = 0.5;
  b.n_samples = n;
  b.n_inputs = 1;
  b.n_outputs = 1;
  for (int i = 0; i < n; ++i) {
    b.u.push_back({static_cast<double>(first + i)});
    b.y.push_back({-static_cast<double>(first + i)});
  }
  return b;
}

TEST(Worker, AssemblesTheRecordInSampleOrder) {
  std::map<int64_t, measurement_block_t> blocks = {{1, Block(1, 3, 2)}, {0, Block(0, 0, 3)}};
  const IoRecord r = AssembleRecord(blocks, 2);
  ASSERT_EQ(r.NumSamples(), 5);
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(r.u(k, 0), k);
    EXPECT_EQ(r.y(k, 0), -k);
    EXPECT_DOUBLE_EQ(r.t(k), 0.5 * k);
  }
  // The hash is SHA-256 of (Ts, u, y) as doubles: recompute it independently.
  std::vector<double> data = {0.5, 0, 1, 2, 3, 4, -0.0, -1, -2, -3, -4};  // y_0 = -0.0 (bitwise)
  EXPECT_EQ(RecordHash(r), Sha256Hex(data.data(), data.size() * sizeof(double)));
}

TEST(Worker, MissingOrInconsistentBlocksAreNamed) {
  std::map<int64_t, measurement_block_t> blocks = {{0, Block(0, 0, 3)}, {2, Block(2, 6, 3)}};
  try {
    AssembleRecord(blocks, 3);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("block 1 is missing"), std::string::npos) << e.what();
  }
  blocks[1] = Block(1, 4, 3);  // should start at 3
  try {
    AssembleRecord(blocks, 3);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("block 1 starts at sample 4, expected 3"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(AssembleRecord(blocks, 0), std::invalid_argument);
}

}  // namespace
}  // namespace idrig
