#include "core/transport/signing.h"

#include "core/transport/auth.h"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace idrig {

std::string ToHex(const uint8_t* data, size_t size) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  out.reserve(2 * size);
  for (size_t i = 0; i < size; ++i) {
    out += digits[data[i] >> 4];
    out += digits[data[i] & 15];
  }
  return out;
}

void CheckKeyStrength(const HmacKey& key, const std::string& what) {
  const std::string fix = ": make a new one with `openssl rand -hex 32 > FILE && chmod 600 FILE`";
  if (key.size() < 32)
    throw std::invalid_argument(what + " is too short (" + std::to_string(key.size()) +
                                " bytes; at least 32 random bytes)" + fix);
  // A repeated pattern (all zero, "abab…", a short key typed twice) has a small period.
  for (size_t period = 1; period <= key.size() / 2; ++period) {
    bool periodic = true;
    for (size_t i = period; i < key.size() && periodic; ++i) periodic = key[i] == key[i - period];
    if (periodic)
      throw std::invalid_argument(what + " repeats a " + std::to_string(period) +
                                  "-byte pattern (too little entropy)" + fix);
  }
  // 32 random bytes have about 30 distinct values; fewer than a quarter of the length is not
  // random (e.g. a key made of ASCII digits or a few letters).
  bool seen[256] = {false};
  size_t distinct = 0;
  for (uint8_t b : key) distinct += !seen[b], seen[b] = true;
  if (distinct < key.size() / 4 + 2)
    throw std::invalid_argument(what + " has only " + std::to_string(distinct) +
                                " distinct byte values (too little entropy)" + fix);
}

HmacKey ReadKeyFile(const std::string& path) {
  struct stat info {};
  if (stat(path.c_str(), &info) != 0)
    throw std::invalid_argument("cannot read HMAC key file '" + path + "'");
  if (info.st_mode & 077) {
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%04o", static_cast<unsigned>(info.st_mode & 07777));
    throw std::invalid_argument("HMAC key file '" + path + "' is readable by group or others (mode " +
                                mode + "): `chmod 600 " + path + "`");
  }
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot read HMAC key file '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return ParseKeyText(ss.str(), path);
}

HmacKey ParseKeyText(const std::string& text, const std::string& path) {
  std::string hex;
  for (char c : text)
    if (!std::isspace(static_cast<unsigned char>(c))) hex += c;
  auto nibble = [&](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    throw std::invalid_argument("HMAC key file '" + path +
                                "' must hold hex digits only (`openssl rand -hex 32 > " + path + "`)");
  };
  if (hex.size() % 2 != 0)
    throw std::invalid_argument("HMAC key file '" + path + "' must hold an even number of hex digits");
  HmacKey key(hex.size() / 2);
  for (size_t i = 0; i < key.size(); ++i)
    key[i] = static_cast<uint8_t>(nibble(hex[2 * i]) * 16 + nibble(hex[2 * i + 1]));
  CheckKeyStrength(key, "HMAC key file '" + path + "'");
  return key;
}

HmacKey WriteNewKeyFile(const std::string& path) {
  HmacKey key(32);
  if (RAND_bytes(key.data(), static_cast<int>(key.size())) != 1)
    throw std::runtime_error("no random bytes for a new HMAC key");
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  if (fd < 0) throw std::invalid_argument("cannot write HMAC key file '" + path + "'");
  fchmod(fd, 0600);  // also when the file existed with a wider mode
  const std::string text = ToHex(key.data(), key.size()) + "\n";
  const bool ok = write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  close(fd);
  if (!ok) throw std::invalid_argument("cannot write HMAC key file '" + path + "'");
  return key;
}

std::string Sha256Hex(const void* data, size_t size) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(data, size, digest, &length, EVP_sha256(), nullptr);
  return ToHex(digest, length);
}

std::string HmacSha256Hex(const HmacKey& key, const void* data, size_t size) {
  unsigned char mac[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()),
       static_cast<const unsigned char*>(data), size, mac, &length);
  return ToHex(mac, length);
}

namespace {
// HMAC over the encoding with a zeroed hmac field.
void ComputeHmac(const actuator_command_t& command, const HmacKey& key, uint8_t out[32]) {
  actuator_command_t copy = command;
  std::fill(std::begin(copy.hmac), std::end(copy.hmac), 0);
  std::vector<uint8_t> buffer(copy.getEncodedSize());
  copy.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
  unsigned int length = 32;
  HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()), buffer.data(), buffer.size(), out,
       &length);
}
}  // namespace

void SignCommand(actuator_command_t* command, const HmacKey& key) {
  uint8_t mac[32];
  ComputeHmac(*command, key, mac);
  std::copy(mac, mac + 32, command->hmac);
}

const char* ToString(CommandCheck check) {
  switch (check) {
    case CommandCheck::kOk:
      return "ok";
    case CommandCheck::kUnsigned:
      return "unsigned";
    case CommandCheck::kUnknownKey:
      return "unknown key id";
    case CommandCheck::kForged:
      return "forged (HMAC mismatch)";
    case CommandCheck::kReplayed:
      return "replayed (seq not above the last accepted)";
  }
  return "?";
}

CommandCheck CommandVerifier::Verify(const actuator_command_t& command) {
  bool all_zero = true;
  for (uint8_t b : command.hmac) all_zero &= (b == 0);
  if (all_zero) return CommandCheck::kUnsigned;
  const auto key = keys_.find(command.key_id);
  if (key == keys_.end()) return CommandCheck::kUnknownKey;
  uint8_t mac[32];
  ComputeHmac(command, key->second, mac);
  if (CRYPTO_memcmp(mac, command.hmac, 32) != 0) return CommandCheck::kForged;
  auto last = last_seq_.find(command.key_id);
  if (last != last_seq_.end() && command.seq <= last->second) return CommandCheck::kReplayed;
  if (store_ && store_->Accept("key" + std::to_string(command.key_id), command.seq,
                               command.utime) != ReplayStore::Verdict::kFresh)
    return CommandCheck::kReplayed;
  last_seq_[command.key_id] = command.seq;
  return CommandCheck::kOk;
}

}  // namespace idrig
