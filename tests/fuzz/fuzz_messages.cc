// Every LCM message decoder (Decode<T> of each idrig type) and the envelope verifier on
// arbitrary bytes: they must return false (counted), never crash or throw.
#include <idrig/actuator_command_t.hpp>
#include <idrig/experiment_request_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_claim_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <idrig/measurement_block_t.hpp>
#include <idrig/model_result_t.hpp>
#include <idrig/replay_done_t.hpp>
#include <idrig/replay_request_t.hpp>
#include <idrig/request_reply_t.hpp>
#include <idrig/result_ack_t.hpp>
#include <idrig/service_status_t.hpp>
#include <idrig/signed_message_t.hpp>

#include <spdlog/spdlog.h>

#include "core/transport/auth.h"

namespace {
template <class T>
void Try(const uint8_t* data, size_t size, idrig::TransportCounters* counters) {
  T message;
  idrig::Decode(data, size, &message, counters, 65536);
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace idrig;
  static EnvelopeVerifier* verifier = [] {
    spdlog::set_level(spdlog::level::off);
    KeyRing ring;
    ring.keys[kOperatorRole] = HmacKey(32, 1);
    ring.keys[kServiceRole] = HmacKey(32, 2);
    return new EnvelopeVerifier(ring, "", 300, "fuzz");
  }();
  TransportCounters counters;
  Try<actuator_command_t>(data, size, &counters);
  Try<experiment_request_t>(data, size, &counters);
  Try<experiment_status_t>(data, size, &counters);
  Try<identify_claim_t>(data, size, &counters);
  Try<identify_request_t>(data, size, &counters);
  Try<measurement_block_t>(data, size, &counters);
  Try<model_result_t>(data, size, &counters);
  Try<replay_done_t>(data, size, &counters);
  Try<replay_request_t>(data, size, &counters);
  Try<request_reply_t>(data, size, &counters);
  Try<result_ack_t>(data, size, &counters);
  Try<service_status_t>(data, size, &counters);
  Try<signed_message_t>(data, size, &counters);
  experiment_request_t inner;
  verifier->Open("IDRIG/f/EXP_REQ", data, size, {kOperatorRole, kServiceRole}, &inner, nullptr,
                 &counters);
  // The fingerprint is the first 8 bytes: also try every type with its own fingerprint in front,
  // so the fuzzer reaches past the type check.
  if (size >= 8) {
    std::vector<uint8_t> patched(data, data + size);
    auto with_hash = [&](int64_t hash) {
      for (int i = 0; i < 8; ++i) patched[i] = static_cast<uint8_t>(uint64_t(hash) >> (56 - 8 * i));
    };
    with_hash(signed_message_t::getHash());
    verifier->Open("IDRIG/f/EXP_REQ", patched.data(), patched.size(), {kOperatorRole}, &inner,
                   nullptr, &counters);
    with_hash(measurement_block_t::getHash());
    Try<measurement_block_t>(patched.data(), patched.size(), &counters);
    with_hash(model_result_t::getHash());
    Try<model_result_t>(patched.data(), patched.size(), &counters);
    with_hash(actuator_command_t::getHash());
    Try<actuator_command_t>(patched.data(), patched.size(), &counters);
  }
  return 0;
}
