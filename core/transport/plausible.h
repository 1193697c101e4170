#pragma once
// lcm-gen's decoders resize a vector to the count read from the message before checking that
// the bytes are there: a 60-byte message claiming n_samples = 2·10⁹ makes a receiver allocate
// 16 GB (found by tests/fuzz/fuzz_messages). PlausibleArrays<T>() walks the encoding of the
// types with variable-length arrays (LCM: big-endian, a string is an int32 length including the
// NUL, then the bytes) and refuses a count whose elements could not fit in the message, and a
// string length below 1 or beyond the message (every idrig type is listed).
#include <cstddef>
#include <cstdint>
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
#include <vector>

namespace idrig {

// spec, after the 8-byte fingerprint: 'q' 8 bytes, 'i' 4, 'b' 1, 's' a string, 'n' an int32
// count (kept), then '1' or '8': an array of 1- or 8-byte elements of the product of the counts
// since the last array.
// end (optional): where the walk stopped.
inline bool PlausibleEncoding(const uint8_t* data, size_t size, const char* spec,
                              size_t* end = nullptr) {
  if (size < 8) return false;
  size_t pos = 8;
  std::vector<int64_t> counts;
  auto int32_at = [&](size_t at) {
    return static_cast<int32_t>((uint32_t(data[at]) << 24) | (uint32_t(data[at + 1]) << 16) |
                                (uint32_t(data[at + 2]) << 8) | uint32_t(data[at + 3]));
  };
  for (const char* c = spec; *c; ++c) {
    size_t need = 0;
    switch (*c) {
      case 'q': need = 8; break;
      case 'i': need = 4; break;
      case 'b': need = 1; break;
      case 's':
      case 'n': {
        if (pos + 4 > size) return false;
        const int32_t n = int32_at(pos);
        pos += 4;
        // A string's length counts its NUL (>= 1); lcm-gen computes length - 1 in int and
        // reads that many bytes (INT_MIN - 1 overflows to a 2 GB read: fuzz_messages, UBSan).
        if (n < (*c == 's' ? 1 : 0) || static_cast<size_t>(n) > size - pos) return false;
        if (*c == 'n') {
          counts.push_back(n);
          continue;
        }
        need = static_cast<size_t>(n);
        break;
      }
      case '1':
      case '8': {
        int64_t elements = 1;
        for (int64_t n : counts) {
          elements *= n;
          if (elements > static_cast<int64_t>(size)) return false;
        }
        counts.clear();
        need = static_cast<size_t>(elements) * (*c == '8' ? 8 : 1);
        break;
      }
      default:
        return false;
    }
    if (need > size - pos) return false;
    pos += need;
  }
  if (end) *end = pos;
  return true;
}

template <class T>
bool PlausibleArrays(const uint8_t*, size_t) {
  return true;  // a type not listed here (tests' own types)
}
#define IDRIG_PLAUSIBLE(type, spec)                                       \
  template <>                                                             \
  inline bool PlausibleArrays<type>(const uint8_t* d, size_t n) {         \
    return PlausibleEncoding(d, n, spec);                                 \
  }
// The string-only types: every string length must fit (fields in .lcm order).
IDRIG_PLAUSIBLE(experiment_request_t, "qqsqisqqqqqs")
IDRIG_PLAUSIBLE(experiment_status_t, "qqssqqisqqqqqqs")
IDRIG_PLAUSIBLE(identify_claim_t, "qqqsisiq")
IDRIG_PLAUSIBLE(identify_request_t, "qqsqsss")
IDRIG_PLAUSIBLE(model_result_t, "qqsqsibsssqqsqqss")
IDRIG_PLAUSIBLE(result_ack_t, "qqsqbs")
IDRIG_PLAUSIBLE(request_reply_t, "qqsqsiqs")
IDRIG_PLAUSIBLE(service_status_t, "qqsssisqqqqqqqqqqqqs")
#undef IDRIG_PLAUSIBLE
template <>
inline bool PlausibleArrays<actuator_command_t>(const uint8_t* d, size_t n) {
  return PlausibleEncoding(d, n, "qqisqqqin8");
}
template <>
inline bool PlausibleArrays<measurement_block_t>(const uint8_t* d, size_t n) {
  // n_samples, n_inputs, n_outputs, then u[n_samples][n_inputs] and y[n_samples][n_outputs].
  size_t pos = 0;
  if (!PlausibleEncoding(d, n, "qsqqqq", &pos) || pos + 12 > n) return false;
  int64_t count[3];
  for (int k = 0; k < 3; ++k) {
    const uint8_t* p = d + pos + 4 * k;
    count[k] = static_cast<int32_t>((uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) |
                                    (uint32_t(p[2]) << 8) | uint32_t(p[3]));
    if (count[k] < 0 || count[k] > static_cast<int64_t>(n)) return false;
  }
  return count[0] * (count[1] + count[2]) * 8 <= static_cast<int64_t>(n - pos - 12);
}
template <>
inline bool PlausibleArrays<signed_message_t>(const uint8_t* d, size_t n) {
  return PlausibleEncoding(d, n, "qqsssn1");
}
template <>
inline bool PlausibleArrays<replay_request_t>(const uint8_t* d, size_t n) {
  return PlausibleEncoding(d, n, "qqssqn8");
}
template <>
inline bool PlausibleArrays<replay_done_t>(const uint8_t* d, size_t n) {
  return PlausibleEncoding(d, n, "qqssqbbqqin8");
}

}  // namespace idrig
