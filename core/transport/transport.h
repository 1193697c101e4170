#pragma once
// Thin messaging layer over LCM (services take a Transport&, so tests can use memq:// or a lossy
// wrapper). Handlers never throw out of here: a handler's exception is caught and counted.
// Messages are raw bytes at this level; Decode<T>() turns them into lcm-gen types and counts
// what fails (foreign fingerprint, undecodable, oversized) instead of throwing.
#include <atomic>
#include <cstdint>
#include <cstring>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "core/transport/plausible.h"

namespace idrig {

// Wall clock [µs since the epoch], the utime of every message.
int64_t NowMicros();

// Counters shown in every service_status_t. Atomic: handlers and writer threads update them.
struct TransportCounters {
  std::atomic<int64_t> received{0}, published{0}, dropped{0}, undecodable{0}, foreign{0},
      oversized{0}, unsigned_count{0}, forged{0}, replayed{0}, over_limit{0}, handler_errors{0},
      publish_errors{0};
};

using RawHandler =
    std::function<void(const std::string& channel, const uint8_t* data, size_t size)>;

class Transport {
 public:
  virtual ~Transport() = default;
  // 0 on success, -1 on failure (counted in publish_errors).
  virtual int Publish(const std::string& channel, const void* data, size_t size) = 0;
  // channel_regex is an LCM (POSIX extended, anchored) regex. queue_capacity > 0 raises LCM's
  // per-subscription queue (default 30 messages) for receivers that must not lose data.
  virtual void Subscribe(const std::string& channel_regex, RawHandler handler,
                         int queue_capacity = 0) = 0;
  // Dispatches the messages that arrive within timeout_ms (at least one wait); returns the
  // number dispatched, or -1 on a transport error.
  virtual int Handle(int timeout_ms) = 0;
  TransportCounters& counters() { return counters_; }

  // Encodes and publishes an lcm-gen message.
  template <class T>
  int PublishMessage(const std::string& channel, const T& message) {
    std::vector<uint8_t> buffer(message.getEncodedSize());
    if (message.encode(buffer.data(), 0, static_cast<int>(buffer.size())) < 0) {
      ++counters_.publish_errors;
      return -1;
    }
    return Publish(channel, buffer.data(), buffer.size());
  }

 protected:
  TransportCounters counters_;
};

// Decodes bytes as T. Counts and returns false (never throws) for a foreign fingerprint, a
// failed (or throwing) decode or a message above max_size bytes (0: no limit).
template <class T>
bool Decode(const uint8_t* data, size_t size, T* out, TransportCounters* counters,
            size_t max_size = 0) {
  if (max_size > 0 && size > max_size) {
    if (counters) ++counters->oversized;
    return false;
  }
  if (size < 8) {
    if (counters) ++counters->undecodable;
    return false;
  }
  const uint64_t expected = static_cast<uint64_t>(T::getHash());
  uint64_t found = 0;
  for (int i = 0; i < 8; ++i) found = (found << 8) | data[i];
  if (found != expected) {
    if (counters) ++counters->foreign;
    return false;
  }
  if (!PlausibleArrays<T>(data, size)) {  // a count the message cannot hold (plausible.h)
    if (counters) ++counters->undecodable;
    return false;
  }
  // lcm-gen's decoders throw (std::length_error) on a string whose length field is 0 or
  // negative (found by tests/fuzz/fuzz_messages): undecodable, like any other bad message.
  try {
    if (out->decode(data, 0, static_cast<int>(size)) < 0) {
      if (counters) ++counters->undecodable;
      return false;
    }
  } catch (const std::exception&) {
    if (counters) ++counters->undecodable;
    return false;
  }
  return true;
}

// The real transport: lcm::LCM on a URL (udpm://…, memq://, file://…). Throws
// std::runtime_error naming the URL when LCM cannot start (e.g. no multicast route).
std::unique_ptr<Transport> MakeLcmTransport(const std::string& url);

// Wraps a transport and drops each received message with probability `loss` (seeded): a lossy
// network for tests, without tc netem.
std::unique_ptr<Transport> MakeLossyTransport(std::unique_ptr<Transport> inner, double loss,
                                              uint64_t seed);

// The default private URL of idrig's tests and demo: udpm, ttl=0 (stays on the host), a large
// receive buffer.
std::string PrivateUdpmUrl(int port, int ttl = 0);

}  // namespace idrig
