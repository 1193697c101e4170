#pragma once
// Shared by the handler targets (fuzz_handlers, fuzz_worker_logger): the deployment's keys, an
// LCM encoding made from a fuzzed payload (the target puts the type's fingerprint in front and
// signs it as the holder of the role's key would), the input's framing
// [selector][length, 2 bytes big-endian][payload]..., and the seed files in that framing.
#include <idrig/actuator_command_t.hpp>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "core/transport/auth.h"
#include "core/transport/signing.h"
#include "core/transport/transport.h"

namespace idrig::fuzz {

inline HmacKey MakeKey(uint8_t salt) {
  HmacKey key(32);
  for (size_t i = 0; i < key.size(); ++i) key[i] = static_cast<uint8_t>(i * 37 + salt * 101 + 11);
  return key;
}
inline const HmacKey& CommandKey() { static const HmacKey k = MakeKey(1); return k; }
inline const HmacKey& OperatorKey() { static const HmacKey k = MakeKey(2); return k; }
inline const HmacKey& ServiceKey() { static const HmacKey k = MakeKey(3); return k; }

template <class T>
std::vector<uint8_t> WithFingerprint(const uint8_t* payload, size_t size) {
  std::vector<uint8_t> bytes(8 + size);
  const uint64_t hash = static_cast<uint64_t>(T::getHash());
  for (int i = 0; i < 8; ++i) bytes[i] = static_cast<uint8_t>(hash >> (56 - 8 * i));
  std::copy(payload, payload + size, bytes.begin() + 8);
  return bytes;
}

// The payload as a T, unsigned (status, blocks, replays: not signed by design).
template <class T>
void PublishPlain(Transport& transport, const std::string& channel, const uint8_t* payload,
                  size_t size) {
  const std::vector<uint8_t> bytes = WithFingerprint<T>(payload, size);
  transport.Publish(channel, bytes.data(), bytes.size());
}

// The payload as a T in an envelope signed by `signer`.
template <class T>
void PublishSigned(Transport& transport, EnvelopeSigner& signer, const std::string& channel,
                   const uint8_t* payload, size_t size) {
  const std::vector<uint8_t> sealed =
      signer.SealBytes(channel, T::getTypeName(), WithFingerprint<T>(payload, size));
  transport.Publish(channel, sealed.data(), sealed.size());
}

// An actuator command, signed with the command key (id 1) as excite signs it when it decodes.
inline void PublishCommand(Transport& transport, const std::string& channel,
                           const uint8_t* payload, size_t size) {
  std::vector<uint8_t> bytes = WithFingerprint<actuator_command_t>(payload, size);
  actuator_command_t command;
  if (Decode(bytes.data(), bytes.size(), &command, nullptr)) {
    command.key_id = 1;
    SignCommand(&command, CommandKey());
    bytes.resize(command.getEncodedSize());
    command.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  }
  transport.Publish(channel, bytes.data(), bytes.size());
}

// Calls on_message(selector, payload, size) for each message of the input, in order.
template <class F>
void ForEachMessage(const uint8_t* data, size_t size, F on_message) {
  size_t pos = 0;
  while (pos < size) {
    const uint8_t selector = data[pos++];
    size_t length = 0;
    if (pos + 2 <= size) length = (size_t(data[pos]) << 8) | data[pos + 1];
    pos = std::min(pos + 2, size);
    length = std::min(length, size - pos);
    on_message(selector, data + pos, length);
    pos += length;
  }
}

// A seed: messages in the input's framing (each the LCM encoding without its fingerprint).
class SeedWriter {
 public:
  template <class T>
  SeedWriter& Add(uint8_t selector, const T& message) {
    std::vector<uint8_t> bytes(message.getEncodedSize());
    message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    const size_t length = bytes.size() - 8;
    out_.push_back(selector);
    out_.push_back(static_cast<uint8_t>(length >> 8));
    out_.push_back(static_cast<uint8_t>(length));
    out_.insert(out_.end(), bytes.begin() + 8, bytes.end());
    return *this;
  }
  void Save(const std::string& path) const {
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(out_.data()), static_cast<std::streamsize>(out_.size()));
  }

 private:
  std::vector<uint8_t> out_;
};

}  // namespace idrig::fuzz
