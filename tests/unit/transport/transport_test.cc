// Transport over memq://, channel names, and command signing: forged, replayed, unsigned and
// unknown-key commands are refused; undecodable and foreign messages are counted, not thrown.
#include "core/transport/transport.h"

#include <gtest/gtest.h>

#include <idrig/actuator_command_t.hpp>
#include <idrig/measurement_block_t.hpp>
#include <idrig/experiment_request_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_claim_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <idrig/model_result_t.hpp>
#include <idrig/replay_done_t.hpp>
#include <idrig/request_reply_t.hpp>
#include <idrig/result_ack_t.hpp>
#include <idrig/service_status_t.hpp>
#include <idrig/replay_request_t.hpp>
#include <idrig/signed_message_t.hpp>

#include "core/transport/channels.h"
#include "core/transport/signing.h"

namespace idrig {
namespace {

actuator_command_t Command(int64_t seq) {
  actuator_command_t c{};
  c.utime = 1;
  c.seq = seq;
  c.key_id = 1;
  c.rig_id = "rig-a";
  c.experiment_id = 5;
  c.first_sample = 10 * seq;
  c.sample_rate_hz = 100.0;
  c.flags = 0;
  c.n_samples = 3;
  c.u = {0.1, 0.2, 0.3};
  std::fill(std::begin(c.hmac), std::end(c.hmac), 0);
  return c;
}

const HmacKey kKey(32, 7);

TEST(Channels, CarryTheRigId) {
  EXPECT_EQ(Channel("rig-a", ChannelKind::kMeasurement), "IDRIG/rig-a/MEAS");
  EXPECT_EQ(RigOfChannel("IDRIG/rig-a/CMD"), "rig-a");
  EXPECT_EQ(RigOfChannel("LCM_SELF_TEST"), "");
  EXPECT_THROW(Channel("rig a", ChannelKind::kCommand), std::invalid_argument);
  EXPECT_THROW(Channel("", ChannelKind::kCommand), std::invalid_argument);
  EXPECT_THROW(Channel(std::string(25, 'x'), ChannelKind::kCommand), std::invalid_argument);
  // The longest channel stays within LCM's 63 characters.
  EXPECT_LE(Channel(std::string(24, 'x'), ChannelKind::kReplayDone).size(), 63u);
}

TEST(Signing, AcceptsSignedAndRefusesForgedReplayedUnsigned) {
  CommandVerifier verifier;
  verifier.AddKey(1, kKey);
  actuator_command_t good = Command(100);
  SignCommand(&good, kKey);
  EXPECT_EQ(verifier.Verify(good), CommandCheck::kOk);
  // The same message again: a replay.
  EXPECT_EQ(verifier.Verify(good), CommandCheck::kReplayed);
  // An older seq, validly signed: also a replay.
  actuator_command_t old = Command(99);
  SignCommand(&old, kKey);
  EXPECT_EQ(verifier.Verify(old), CommandCheck::kReplayed);
  // A changed sample after signing: forged.
  actuator_command_t tampered = Command(101);
  SignCommand(&tampered, kKey);
  tampered.u[1] = 5.0;
  EXPECT_EQ(verifier.Verify(tampered), CommandCheck::kForged);
  // Signed with another key: forged.
  actuator_command_t other = Command(102);
  SignCommand(&other, HmacKey(32, 8));
  EXPECT_EQ(verifier.Verify(other), CommandCheck::kForged);
  EXPECT_EQ(verifier.Verify(Command(103)), CommandCheck::kUnsigned);
  actuator_command_t unknown = Command(104);
  unknown.key_id = 9;
  SignCommand(&unknown, kKey);
  EXPECT_EQ(verifier.Verify(unknown), CommandCheck::kUnknownKey);
  // A forged attempt does not advance the accepted seq: the next good one passes.
  actuator_command_t next = Command(101);
  SignCommand(&next, kKey);
  EXPECT_EQ(verifier.Verify(next), CommandCheck::kOk);
}

TEST(Signing, HmacAndShaMatchPublishedTestVectors) {
  // RFC 4231 test case 2: key "Jefe", data "what do ya want for nothing?".
  const std::string jefe = "Jefe", data = "what do ya want for nothing?";
  EXPECT_EQ(HmacSha256Hex(HmacKey(jefe.begin(), jefe.end()), data.data(), data.size()),
            "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
  // FIPS 180-2 appendix B.1: SHA-256("abc").
  const std::string abc = "abc";
  EXPECT_EQ(Sha256Hex(abc.data(), abc.size()),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Signing, KeyFileErrorsNameTheFile) {
  EXPECT_THROW(ReadKeyFile("/nonexistent/key"), std::invalid_argument);
  const std::string path = ::testing::TempDir() + "/idrig_key_test";
  const HmacKey key = WriteNewKeyFile(path);
  EXPECT_EQ(ReadKeyFile(path), key);
  FILE* f = fopen(path.c_str(), "w");
  fputs("xyz", f);
  fclose(f);
  try {
    ReadKeyFile(path);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
}

// Regression (tests/fuzz/fuzz_messages, crash-b54a5555…): a message with the right
// fingerprint whose string length field is 0 made lcm-gen's decoder throw std::length_error
// out of Decode<T>; now it is counted as undecodable. The input: a measurement block's
// encoding with actuator_command_t's fingerprint, so utime/seq/key_id read the block's header
// and rig_id's length field reads zeros.
TEST(Transport, DecodeCountsAThrowingDecoderAsUndecodable) {
  measurement_block_t block{};
  block.rig_id = "sim1";
  block.experiment_id = 1;
  std::vector<uint8_t> bytes(block.getEncodedSize());
  block.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  const uint64_t hash = static_cast<uint64_t>(actuator_command_t::getHash());
  for (int i = 0; i < 8; ++i) bytes[i] = static_cast<uint8_t>(hash >> (56 - 8 * i));
  bytes.resize(64, 0);
  // rig_id's length sits after utime (8), seq (8), key_id (4): bytes 28..31 of the encoding.
  for (int i = 28; i < 32; ++i) bytes[i] = 0;
  actuator_command_t command;
  TransportCounters counters;
  EXPECT_NO_THROW(EXPECT_FALSE(Decode(bytes.data(), bytes.size(), &command, &counters)));
  EXPECT_EQ(counters.undecodable, 1);
}

template <class T>
std::vector<uint8_t> Encode(const T& m) {
  std::vector<uint8_t> bytes(m.getEncodedSize());
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// Regression (fuzz_messages, crash-bfd91f86…): a short message claiming a huge array count made
// the decoder allocate gigabytes before noticing the bytes were not there. Real encodings of
// every type with arrays pass the plausibility walk; a claimed count of 2·10⁹ does not.
TEST(Transport, ArrayCountsAMessageCannotHoldAreRefusedBeforeAllocating) {
  measurement_block_t block{};
  block.rig_id = "rig-a";
  block.n_samples = 3;
  block.n_inputs = 2;
  block.n_outputs = 1;
  block.u.assign(3, {1.0, 2.0});
  block.y.assign(3, {3.0});
  actuator_command_t command = Command(1);
  signed_message_t envelope{};
  envelope.sender = "s";
  envelope.key_role = "operator";
  envelope.payload_type = "x";
  envelope.payload_size = 5;
  envelope.payload.assign(5, 7);
  replay_request_t request{};
  request.requester = "w";
  request.rig_id = "rig-a";
  request.n_have = 2;
  request.have_seqs = {1, 2};
  replay_done_t done{};
  done.requester = "w";
  done.rig_id = "rig-a";
  done.n_missing = 1;
  done.missing_seqs = {4};
  TransportCounters counters;
  auto round_trip = [&](auto message) {
    const auto bytes = Encode(message);
    decltype(message) out;
    return Decode(bytes.data(), bytes.size(), &out, &counters);
  };
  EXPECT_TRUE(round_trip(block));
  EXPECT_TRUE(round_trip(command));
  EXPECT_TRUE(round_trip(envelope));
  EXPECT_TRUE(round_trip(request));
  EXPECT_TRUE(round_trip(done));
  EXPECT_EQ(counters.undecodable, 0);
  // The command with n_samples = 2·10⁹ and its 3 samples: 16 GB claimed in a 100-byte message.
  std::vector<uint8_t> bytes = Encode(command);
  const size_t n_samples_at = bytes.size() - 32 - 3 * 8 - 4;
  const uint32_t huge = 2000000000u;
  for (int i = 0; i < 4; ++i) bytes[n_samples_at + i] = static_cast<uint8_t>(huge >> (24 - 8 * i));
  actuator_command_t out;
  EXPECT_FALSE(Decode(bytes.data(), bytes.size(), &out, &counters));
  EXPECT_EQ(counters.undecodable, 1);
  std::vector<uint8_t> block_bytes = Encode(block);
  const size_t counts_at = block_bytes.size() - 9 * 8 - 12;
  for (int i = 0; i < 4; ++i) block_bytes[counts_at + i] = static_cast<uint8_t>(huge >> (24 - 8 * i));
  measurement_block_t block_out;
  EXPECT_FALSE(Decode(block_bytes.data(), block_bytes.size(), &block_out, &counters));
  EXPECT_EQ(counters.undecodable, 2);
  // Every string-only type: a real encoding passes; a string length of INT_MIN does not (lcm-gen
  // would compute INT_MIN - 1 and read 2 GB: fuzz_messages, crash-9112085f…).
  experiment_status_t status{};
  status.source = "rig";
  status.rig_id = "rig-a";
  service_status_t service{};
  service.service = "excite";
  model_result_t result{};
  result.rig_id = "rig-a";
  result.report_json = "{}";
  EXPECT_TRUE(round_trip(experiment_request_t{}));
  EXPECT_TRUE(round_trip(status));
  EXPECT_TRUE(round_trip(identify_claim_t{}));
  EXPECT_TRUE(round_trip(identify_request_t{}));
  EXPECT_TRUE(round_trip(result));
  EXPECT_TRUE(round_trip(result_ack_t{}));
  EXPECT_TRUE(round_trip(request_reply_t{}));
  EXPECT_TRUE(round_trip(service));
  EXPECT_EQ(counters.undecodable, 2);
  std::vector<uint8_t> result_bytes = Encode(result);
  for (int i = 0; i < 4; ++i) result_bytes[24 + i] = i == 0 ? 0x80 : 0;  // rig_id's length
  model_result_t result_out;
  EXPECT_FALSE(Decode(result_bytes.data(), result_bytes.size(), &result_out, &counters));
  EXPECT_EQ(counters.undecodable, 3);
}

TEST(Transport, MemqDeliversAndCountsBadMessages) {
  auto transport = MakeLcmTransport("memq://");
  int good = 0;
  transport->Subscribe("IDRIG/rig-a/MEAS", [&](const std::string&, const uint8_t* d, size_t n) {
    measurement_block_t block;
    if (Decode(d, n, &block, &transport->counters(), 60000)) ++good;
  });
  transport->Subscribe("IDRIG/rig-a/BOOM", [&](const std::string&, const uint8_t*, size_t) {
    throw std::runtime_error("handler bug");
  });
  measurement_block_t block{};
  block.rig_id = "rig-a";
  block.n_samples = 1;
  block.n_inputs = 1;
  block.n_outputs = 1;
  block.u = {{1.0}};
  block.y = {{2.0}};
  transport->PublishMessage("IDRIG/rig-a/MEAS", block);
  const uint8_t garbage[4] = {1, 2, 3, 4};
  transport->Publish("IDRIG/rig-a/MEAS", garbage, sizeof(garbage));
  actuator_command_t foreign = Command(1);
  transport->PublishMessage("IDRIG/rig-a/MEAS", foreign);
  std::vector<uint8_t> big(70000, 0);
  transport->Publish("IDRIG/rig-a/MEAS", big.data(), big.size());
  transport->Publish("IDRIG/rig-a/BOOM", garbage, sizeof(garbage));
  for (int i = 0; i < 10; ++i) transport->Handle(10);
  EXPECT_EQ(good, 1);
  EXPECT_EQ(transport->counters().undecodable, 1);
  EXPECT_EQ(transport->counters().foreign, 1);
  EXPECT_EQ(transport->counters().oversized, 1);
  EXPECT_EQ(transport->counters().handler_errors, 1);
}

TEST(Transport, LossyWrapperDropsAboutTheRequestedFraction) {
  auto lossy = MakeLossyTransport(MakeLcmTransport("memq://"), 0.25, 42);
  int received = 0;
  lossy->Subscribe("X", [&](const std::string&, const uint8_t*, size_t) { ++received; });
  const uint8_t byte = 0;
  for (int i = 0; i < 2000; ++i) {
    lossy->Publish("X", &byte, 1);
    if (i % 100 == 99) lossy->Handle(0);
  }
  while (lossy->Handle(10) > 0) {
  }
  // Binomial(2000, 0.75): mean 1500, sd 19.4; 5 sd either side.
  EXPECT_NEAR(received, 1500, 97);
  EXPECT_THROW(MakeLossyTransport(MakeLcmTransport("memq://"), 1.0, 1), std::invalid_argument);
}

}  // namespace
}  // namespace idrig
