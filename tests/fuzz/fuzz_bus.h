#pragma once
// Shared by the handler targets (fuzz_handlers, fuzz_worker_logger): the deployment's keys, an
// LCM encoding made from a fuzzed payload (the target puts the type's fingerprint in front and
// signs it as the holder of the role's key would), the input's framing
// [selector][length, 2 bytes big-endian][payload]..., and the seed files in that framing.
#include <idrig/actuator_command_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_claim_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
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

// LLVMFuzzerInitialize of a handler target: a handler's exception is logged at error level;
// IDRIG_FUZZ_WRITE_SEEDS=DIR writes the target's seed corpus (valid message chains) and exits.
inline void InitHandlerTarget(void (*write_seeds)(const std::string& dir)) {
  spdlog::set_level(spdlog::level::err);
  if (const char* dir = std::getenv("IDRIG_FUZZ_WRITE_SEEDS")) {
    write_seeds(dir);
    std::exit(0);
  }
}

// An exception out of a handler (counted in handler_errors: DESIGN.md says handlers never
// throw) is a finding.
inline void AbortOnHandlerErrors(Transport& transport, int64_t errors_before) {
  const int64_t errors = transport.counters().handler_errors;
  if (errors <= errors_before) return;
  std::fprintf(stderr, "an exception escaped a handler (handler_errors %lld)\n",
               static_cast<long long>(errors));
  std::abort();
}

// Seed messages.
inline identify_request_t SeedIdentify(const std::string& rig, int64_t request, int64_t experiment,
                                       const std::string& method, const std::string& options) {
  identify_request_t r{};
  r.request_id = request;
  r.rig_id = rig;
  r.experiment_id = experiment;
  r.method = method;
  r.options_json = options;
  r.requested_by = "fuzz";
  return r;
}

// A rig's experiment status for the seeds: `blocks` blocks, `samples` samples done of as many;
// an interrupted one names `missing`.
inline experiment_status_t SeedRigStatus(const std::string& rig, int64_t experiment, int32_t state,
                                         int64_t blocks, int64_t samples, const std::string& missing) {
  experiment_status_t s{};
  s.source = "rig";
  s.rig_id = rig;
  s.experiment_id = experiment;
  s.state = state;
  s.sample_rate_hz = 100;
  s.samples_done = s.samples_total = samples;
  s.blocks_total = blocks;
  s.message = state == experiment_status_t::STATE_INTERRUPTED ? missing : "";
  return s;
}

inline identify_claim_t SeedClaim(const std::string& rig, int64_t request, int32_t kind,
                                  const std::string& worker, double lease_s = 0) {
  identify_claim_t c{};
  c.request_id = request;
  c.rig_id = rig;
  c.kind = kind;
  c.worker_id = worker;
  c.attempt = 1;
  c.lease_s = lease_s;
  return c;
}

// n samples at 100 Hz from `first`, u[i] = u_of(i).
template <class U>
actuator_command_t SeedCommand(const std::string& rig, int64_t seq, int64_t experiment,
                               int64_t first, int32_t flags, int n, U u_of) {
  actuator_command_t c{};
  c.seq = seq;
  c.key_id = 1;
  c.rig_id = rig;
  c.experiment_id = experiment;
  c.first_sample = first;
  c.sample_rate_hz = 100;
  c.flags = flags;
  c.n_samples = n;
  for (int i = 0; i < n; ++i) c.u.push_back(u_of(i));
  return c;
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
