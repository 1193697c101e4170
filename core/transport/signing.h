#pragma once
// Authentication of actuator commands: HMAC-SHA256 with a shared key, plus a strictly
// increasing sequence number per key id so that a recorded command cannot be replayed.
//   hmac = HMAC-SHA256(key, E), E = LCM encoding of the command with hmac = 32 zero bytes.
// Keys are 32 random bytes, stored as 64 hex characters in a file readable by its owner only.
#include <cstdint>
#include <idrig/actuator_command_t.hpp>
#include <map>
#include <string>
#include <vector>

namespace idrig {

using HmacKey = std::vector<uint8_t>;
class ReplayStore;  // core/transport/auth.h

// Reads a hex key file (whitespace ignored). Throws std::invalid_argument naming the file and
// saying how to fix it when it is missing, not hex, readable by group or others, or too weak
// (CheckKeyStrength).
HmacKey ReadKeyFile(const std::string& path);
// The text of a key file named `path` (for the messages): hex digits, whitespace ignored, then
// CheckKeyStrength. ReadKeyFile after its mode checks; tests/fuzz/fuzz_config feeds it bytes.
HmacKey ParseKeyText(const std::string& text, const std::string& path);
// Throws std::invalid_argument (what + the reason + how to make a good key) for a key shorter
// than 32 bytes, one that repeats a pattern (all-zero, "abab…"), or one with few distinct bytes.
void CheckKeyStrength(const HmacKey& key, const std::string& what);
// Writes 32 bytes from the OS's random source as hex, mode 0600.
HmacKey WriteNewKeyFile(const std::string& path);
std::string ToHex(const uint8_t* data, size_t size);

// SHA-256 of bytes, as hex.
std::string Sha256Hex(const void* data, size_t size);

// HMAC-SHA256(key, data), as hex.
std::string HmacSha256Hex(const HmacKey& key, const void* data, size_t size);

// Fills command.hmac.
void SignCommand(actuator_command_t* command, const HmacKey& key);

enum class CommandCheck { kOk, kUnsigned, kUnknownKey, kForged, kReplayed };
const char* ToString(CommandCheck check);

// The receiving side: keys by id, and the last accepted seq per key id.
class CommandVerifier {
 public:
  void AddKey(int32_t key_id, HmacKey key) { keys_[key_id] = std::move(key); }
  // Keeps the last accepted seq per key id in `store` too (on disk): a restarted rig refuses
  // recorded commands as well. The store must outlive the verifier.
  void UseStore(ReplayStore* store) { store_ = store; }
  // Checks signature, then freshness; on kOk records seq as the last accepted one.
  CommandCheck Verify(const actuator_command_t& command);

 private:
  std::map<int32_t, HmacKey> keys_;
  std::map<int32_t, int64_t> last_seq_;
  ReplayStore* store_ = nullptr;
};

}  // namespace idrig
