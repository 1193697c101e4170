#pragma once
// Authentication of every message that changes state (docs/services.md, "Authentication").
// A sender wraps the LCM encoding of the message in a signed_message_t envelope:
//   hmac = HMAC-SHA256(key[role], channel || 0x00 || E), E = the envelope's encoding with hmac
//   set to 32 zero bytes; E holds utime, seq, sender, key_role, the inner type name and bytes.
// Binding the channel stops a message signed for one rig or kind being replayed onto another.
// The receiver checks, in this order: an envelope at all (else "unsigned"), a role it accepts
// on this channel and holds a key for, the HMAC (constant-time), the time window around its own
// clock, and a seq above the high-water mark of (role, sender) — kept in a file in the
// service's state directory, so replaying recorded traffic to a restarted receiver fails too.
// Keys by role: "operator" (people: start/stop experiments, request identifications) and
// "service" (the services among themselves: claims, grants, results, acknowledgements).
#include <cstdint>
#include <idrig/signed_message_t.hpp>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/transport/signing.h"
#include "core/transport/transport.h"

namespace idrig {

inline constexpr const char* kOperatorRole = "operator";
inline constexpr const char* kServiceRole = "service";

// The deployment keys a process holds, by role.
struct KeyRing {
  std::map<std::string, HmacKey> keys;
  const HmacKey* Find(const std::string& role) const;
  bool Has(const std::string& role) const { return Find(role) != nullptr; }
  // Config keys "operator_key_file" and "service_key_file" (each optional; ReadKeyFile's checks).
  static KeyRing FromConfig(const nlohmann::json& config);
};

// High-water marks (last accepted seq) per sender, persisted by appending one line per accepted
// message to `path` (a single write(2): survives kill -9; the file is compacted to one line per
// live sender when it grows). path "" keeps them in memory only. Senders not heard for longer
// than the window are forgotten: their old messages are outside the window anyway.
class ReplayStore {
 public:
  enum class Verdict { kFresh, kReplayed, kStale };
  // window_s <= 0: no time window (commands: seq alone, per key id).
  explicit ReplayStore(std::string path = "", double window_s = 0);
  ~ReplayStore();
  ReplayStore(const ReplayStore&) = delete;
  ReplayStore& operator=(const ReplayStore&) = delete;
  // kFresh (and recorded) when utime is within the window of now and seq is above the mark.
  Verdict Accept(const std::string& sender, int64_t seq, int64_t utime);
  int64_t Mark(const std::string& sender) const;
  size_t size() const { return marks_.size(); }
  const std::string& path() const { return path_; }

 private:
  void Load();
  void Compact();
  std::string path_;
  double window_s_;
  int fd_ = -1;
  size_t lines_ = 0;
  std::map<std::string, std::pair<int64_t, int64_t>> marks_;  // sender -> (seq, utime)
};

enum class AuthCheck { kOk, kUnsigned, kNoKey, kWrongRole, kForged, kStale, kReplayed, kUndecodable };
const char* ToString(AuthCheck check);

struct Sender {
  std::string id, role;
  int64_t seq = 0, utime = 0;
};

class EnvelopeSigner {
 public:
  EnvelopeSigner(std::string role, HmacKey key, std::string sender);
  // The encoded envelope of `message` for `channel` (a fresh seq each call: never re-send bytes).
  template <class T>
  std::vector<uint8_t> Seal(const std::string& channel, const T& message) {
    std::vector<uint8_t> inner(message.getEncodedSize());
    message.encode(inner.data(), 0, static_cast<int>(inner.size()));
    return SealBytes(channel, T::getTypeName(), inner);
  }
  template <class T>
  int Publish(Transport& transport, const std::string& channel, const T& message) {
    const std::vector<uint8_t> bytes = Seal(channel, message);
    return transport.Publish(channel, bytes.data(), bytes.size());
  }
  std::vector<uint8_t> SealBytes(const std::string& channel, const std::string& type,
                                 const std::vector<uint8_t>& inner);
  const std::string& sender() const { return sender_; }
  const std::string& role() const { return role_; }

 private:
  std::string role_;
  HmacKey key_;
  std::string sender_;
  std::mutex mutex_;
  int64_t last_seq_ = 0;
};

// The receiving side of one service: its keys, the replay store, and what it refused.
class EnvelopeVerifier {
 public:
  // state_path: the replay store's file ("" = memory only); window_s: accepted |utime - now|.
  EnvelopeVerifier(KeyRing keys, std::string state_path, double window_s, std::string service);
  // Checks an envelope received on `channel`, signed by one of `roles`; on kOk fills payload and
  // sender. Refusals are counted (unsigned_count, forged, replayed in counters) and logged.
  AuthCheck Verify(const std::string& channel, const uint8_t* data, size_t size,
                   const std::vector<std::string>& roles, std::vector<uint8_t>* payload,
                   Sender* sender, TransportCounters* counters);
  // Verify, then Decode<T> the payload (a wrong inner type is counted as foreign).
  template <class T>
  bool Open(const std::string& channel, const uint8_t* data, size_t size,
            const std::vector<std::string>& roles, T* out, Sender* sender,
            TransportCounters* counters) {
    std::vector<uint8_t> payload;
    Sender who;
    if (Verify(channel, data, size, roles, &payload, &who, counters) != AuthCheck::kOk) return false;
    if (sender) *sender = who;
    return Decode(payload.data(), payload.size(), out, counters);
  }
  const KeyRing& keys() const { return keys_; }
  // {"refused": {reason: count}, "last_refusal": "...", "senders": N}
  nlohmann::json Details() const;

 private:
  void Refuse(AuthCheck check, const std::string& channel, const std::string& detail,
              TransportCounters* counters);
  KeyRing keys_;
  ReplayStore store_;
  std::string service_;
  std::map<std::string, int64_t> refused_;
  std::string last_refusal_;
};

// The sender id of this process for the command line: "cli:<user>@<host>".
std::string CliSenderId();

}  // namespace idrig
