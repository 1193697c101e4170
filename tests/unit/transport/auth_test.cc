// Signed envelopes: the HMAC against an independent computation (HmacSha256Hex over the bytes
// the docs name), refusal of unsigned, forged, wrong-role, re-routed, stale and replayed
// messages, the replay store surviving a "restart" (a new object on the same file), and key
// hygiene (weak keys, key files readable by others).
#include "core/transport/auth.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdio>
#include <fstream>
#include <idrig/experiment_request_t.hpp>

namespace idrig {
namespace {

HmacKey TestKey(uint8_t salt) {
  HmacKey key(32);
  for (size_t i = 0; i < key.size(); ++i) key[i] = static_cast<uint8_t>(i * 37 + salt * 11 + 5);
  return key;
}

experiment_request_t Request() {
  experiment_request_t r{};
  r.utime = NowMicros();
  r.request_id = 42;
  r.rig_id = "rig-a";
  r.experiment_id = 7;
  r.action = experiment_request_t::ACTION_START;
  r.signal_spec = "step:amp=1";
  r.sample_rate_hz = 10;
  r.duration_s = 1;
  return r;
}

const std::string kChannel = "IDRIG/rig-a/EXP_REQ";

KeyRing Ring() {
  KeyRing ring;
  ring.keys[kOperatorRole] = TestKey(1);
  ring.keys[kServiceRole] = TestKey(2);
  return ring;
}

TEST(Auth, HmacCoversTheChannelAndTheEnvelopeWithAZeroedHmacField) {
  EnvelopeSigner signer(kOperatorRole, TestKey(1), "cli:test@host");
  const std::vector<uint8_t> bytes = signer.Seal(kChannel, Request());
  signed_message_t envelope;
  ASSERT_EQ(envelope.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  const std::string received = ToHex(envelope.hmac, 32);
  std::fill(std::begin(envelope.hmac), std::end(envelope.hmac), 0);
  std::vector<uint8_t> zeroed(envelope.getEncodedSize());
  envelope.encode(zeroed.data(), 0, static_cast<int>(zeroed.size()));
  std::vector<uint8_t> input(kChannel.begin(), kChannel.end());
  input.push_back(0);
  input.insert(input.end(), zeroed.begin(), zeroed.end());
  EXPECT_EQ(received, HmacSha256Hex(TestKey(1), input.data(), input.size()));
  EXPECT_EQ(envelope.payload_type, "experiment_request_t");
  EXPECT_EQ(envelope.key_role, "operator");
}

TEST(Auth, RefusesUnsignedForgedWrongRoleRedirectedAndReplayed) {
  EnvelopeVerifier verifier(Ring(), "", 60, "test");
  TransportCounters counters;
  EnvelopeSigner op(kOperatorRole, TestKey(1), "cli:a@h");
  const std::vector<std::string> operator_only = {kOperatorRole};
  experiment_request_t out;
  Sender who;
  auto sealed = op.Seal(kChannel, Request());
  ASSERT_TRUE(verifier.Open(kChannel, sealed.data(), sealed.size(), operator_only, &out, &who, &counters));
  EXPECT_EQ(out.request_id, 42);
  EXPECT_EQ(who.id, "cli:a@h");
  // The same bytes again: replayed.
  EXPECT_EQ(verifier.Verify(kChannel, sealed.data(), sealed.size(), operator_only, nullptr, nullptr,
                            &counters),
            AuthCheck::kReplayed);
  // A bare message: unsigned.
  const experiment_request_t bare = Request();
  std::vector<uint8_t> raw(bare.getEncodedSize());
  bare.encode(raw.data(), 0, static_cast<int>(raw.size()));
  EXPECT_EQ(verifier.Verify(kChannel, raw.data(), raw.size(), operator_only, nullptr, nullptr, &counters),
            AuthCheck::kUnsigned);
  // A key nobody gave us, under the operator role: forged.
  EnvelopeSigner attacker(kOperatorRole, TestKey(9), "cli:a@h");
  auto forged = attacker.Seal(kChannel, Request());
  EXPECT_EQ(verifier.Verify(kChannel, forged.data(), forged.size(), operator_only, nullptr, nullptr,
                            &counters),
            AuthCheck::kForged);
  // A flipped payload byte: forged.
  auto tampered = op.Seal(kChannel, Request());
  tampered[tampered.size() - 40] ^= 1;
  EXPECT_EQ(verifier.Verify(kChannel, tampered.data(), tampered.size(), operator_only, nullptr, nullptr,
                            &counters),
            AuthCheck::kForged);
  // A service-signed experiment request: the wrong role for EXP_REQ.
  EnvelopeSigner service(kServiceRole, TestKey(2), "worker-1");
  auto wrong_role = service.Seal(kChannel, Request());
  EXPECT_EQ(verifier.Verify(kChannel, wrong_role.data(), wrong_role.size(), operator_only, nullptr,
                            nullptr, &counters),
            AuthCheck::kWrongRole);
  // Signed for rig-a, published on rig-b's channel: forged.
  auto moved = op.Seal(kChannel, Request());
  EXPECT_EQ(verifier.Verify("IDRIG/rig-b/EXP_REQ", moved.data(), moved.size(), operator_only, nullptr,
                            nullptr, &counters),
            AuthCheck::kForged);
  EXPECT_EQ(counters.forged, 3);
  EXPECT_EQ(counters.replayed, 1);
  EXPECT_EQ(counters.unsigned_count, 2);
  EXPECT_EQ(verifier.Details()["refused"].size(), 4u);
}

TEST(Auth, ReplayMarksSurviveARestartOfTheReceiver) {
  const std::string path = ::testing::TempDir() + "/idrig_replay_store";
  std::remove(path.c_str());
  EnvelopeSigner op(kOperatorRole, TestKey(1), "cli:a@h");
  std::vector<std::vector<uint8_t>> recorded;
  for (int i = 0; i < 3; ++i) recorded.push_back(op.Seal(kChannel, Request()));
  {
    EnvelopeVerifier first(Ring(), path, 60, "test");
    for (const auto& m : recorded)
      EXPECT_EQ(first.Verify(kChannel, m.data(), m.size(), {kOperatorRole}, nullptr, nullptr, nullptr),
                AuthCheck::kOk);
  }
  EnvelopeVerifier restarted(Ring(), path, 60, "test");
  for (const auto& m : recorded)
    EXPECT_EQ(restarted.Verify(kChannel, m.data(), m.size(), {kOperatorRole}, nullptr, nullptr, nullptr),
              AuthCheck::kReplayed);
  auto fresh = op.Seal(kChannel, Request());
  EXPECT_EQ(restarted.Verify(kChannel, fresh.data(), fresh.size(), {kOperatorRole}, nullptr, nullptr,
                             nullptr),
            AuthCheck::kOk);
  // Without the file (memory only) the restart would have accepted them: the file is what helps.
  EnvelopeVerifier amnesiac(Ring(), "", 60, "test");
  EXPECT_EQ(amnesiac.Verify(kChannel, recorded[0].data(), recorded[0].size(), {kOperatorRole}, nullptr,
                            nullptr, nullptr),
            AuthCheck::kOk);
}

TEST(Auth, StaleMessagesAreRefusedEvenByAReceiverWithNoMarks) {
  ReplayStore store("", 60);
  EXPECT_EQ(store.Accept("s", 10, NowMicros() - 120000000), ReplayStore::Verdict::kStale);
  EXPECT_EQ(store.Accept("s", 10, NowMicros()), ReplayStore::Verdict::kFresh);
  EXPECT_EQ(store.Accept("s", 10, NowMicros()), ReplayStore::Verdict::kReplayed);
}

TEST(Auth, CommandMarksPersistAcrossVerifiers) {
  const std::string path = ::testing::TempDir() + "/idrig_command_store";
  std::remove(path.c_str());
  actuator_command_t c{};
  c.utime = NowMicros();
  c.seq = 1000;
  c.key_id = 1;
  c.rig_id = "rig-a";
  SignCommand(&c, TestKey(3));
  {
    ReplayStore store(path);
    CommandVerifier v;
    v.AddKey(1, TestKey(3));
    v.UseStore(&store);
    EXPECT_EQ(v.Verify(c), CommandCheck::kOk);
  }
  ReplayStore store(path);
  CommandVerifier v;
  v.AddKey(1, TestKey(3));
  v.UseStore(&store);
  EXPECT_EQ(v.Verify(c), CommandCheck::kReplayed);
}

void WriteKey(const std::string& path, const std::string& hex, mode_t mode) {
  std::ofstream(path, std::ios::trunc) << hex << "\n";
  chmod(path.c_str(), mode);
}

std::string Message(const std::string& path) {
  try {
    ReadKeyFile(path);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(KeyHygiene, WeakKeysAndOpenKeyFilesAreRefusedWithTheFix) {
  const std::string path = ::testing::TempDir() + "/idrig_weak_key";
  WriteKey(path, std::string(64, '0'), 0600);
  EXPECT_NE(Message(path).find("repeats a 1-byte pattern"), std::string::npos) << Message(path);
  EXPECT_NE(Message(path).find("openssl rand -hex 32"), std::string::npos);
  WriteKey(path, "0123456789abcdef0123456789abcdef", 0600);  // 16 bytes
  EXPECT_NE(Message(path).find("too short"), std::string::npos) << Message(path);
  WriteKey(path, "deadbeef0badf00d" "deadbeef0badf00d" "deadbeef0badf00d" "deadbeef0badf00d", 0600);
  EXPECT_NE(Message(path).find("8-byte pattern"), std::string::npos) << Message(path);
  // 32 bytes from only 4 values, no period.
  WriteKey(path, "0001020300010203000102030001020302010003020100030201000302010003", 0600);
  EXPECT_NE(Message(path).find("distinct byte values"), std::string::npos) << Message(path);
  const HmacKey good = WriteNewKeyFile(path);
  EXPECT_EQ(ReadKeyFile(path), good);
  chmod(path.c_str(), 0644);
  EXPECT_NE(Message(path).find("chmod 600 " + path), std::string::npos) << Message(path);
  EXPECT_NE(Message(path).find("0644"), std::string::npos);
  WriteNewKeyFile(path);  // rewriting makes it 0600 again
  EXPECT_EQ(Message(path), "");
}

}  // namespace
}  // namespace idrig
