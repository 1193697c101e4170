#include "core/transport/auth.h"

#include <fcntl.h>
#include <openssl/crypto.h>
#include <openssl/hmac.h>
#include <pwd.h>
#include <sys/stat.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>

#include "core/transport/service_util.h"
#include "core/transport/status.h"

namespace idrig {

const HmacKey* KeyRing::Find(const std::string& role) const {
  auto it = keys.find(role);
  return it == keys.end() ? nullptr : &it->second;
}

KeyRing KeyRing::FromConfig(const nlohmann::json& config) {
  KeyRing ring;
  for (const char* role : {kOperatorRole, kServiceRole}) {
    const std::string file = ConfigValue<std::string>(config, (std::string(role) + "_key_file").c_str(), "");
    if (!file.empty()) ring.keys[role] = ReadKeyFile(file);
  }
  return ring;
}

// ---- replay store

ReplayStore::ReplayStore(std::string path, double window_s)
    : path_(std::move(path)), window_s_(window_s) {
  if (path_.empty()) return;
  const size_t slash = path_.find_last_of('/');
  if (slash != std::string::npos && slash > 0) MakeDirectories(path_.substr(0, slash));
  Load();
  Compact();
}

ReplayStore::~ReplayStore() {
  if (fd_ >= 0) close(fd_);
}

void ReplayStore::Load() {
  std::ifstream in(path_);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string sender;
    int64_t seq = 0, utime = 0;
    if (!(fields >> sender >> seq >> utime)) continue;  // a torn last line after a crash
    auto& mark = marks_[sender];
    if (seq > mark.first) mark = {seq, utime};
  }
}

void ReplayStore::Compact() {
  const int64_t now = NowMicros();
  for (auto it = marks_.begin(); it != marks_.end();) {
    const bool expired = window_s_ > 0 && now - it->second.second > static_cast<int64_t>(2e6 * window_s_);
    it = expired ? marks_.erase(it) : std::next(it);
  }
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
  const std::string tmp = path_ + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw std::invalid_argument("cannot write the replay store '" + tmp + "'");
    for (const auto& [sender, mark] : marks_)
      out << sender << ' ' << mark.first << ' ' << mark.second << '\n';
  }
  if (std::rename(tmp.c_str(), path_.c_str()) != 0)
    throw std::invalid_argument("cannot replace the replay store '" + path_ + "'");
  lines_ = marks_.size();
  fd_ = open(path_.c_str(), O_WRONLY | O_APPEND);
  if (fd_ < 0) throw std::invalid_argument("cannot open the replay store '" + path_ + "'");
}

ReplayStore::Verdict ReplayStore::Accept(const std::string& sender, int64_t seq, int64_t utime) {
  if (window_s_ > 0 && std::llabs(NowMicros() - utime) > static_cast<int64_t>(window_s_ * 1e6))
    return Verdict::kStale;
  auto it = marks_.find(sender);
  if (it != marks_.end() && seq <= it->second.first) return Verdict::kReplayed;
  marks_[sender] = {seq, utime};
  if (fd_ >= 0) {
    const std::string line = sender + ' ' + std::to_string(seq) + ' ' + std::to_string(utime) + '\n';
    if (write(fd_, line.data(), line.size()) != static_cast<ssize_t>(line.size()))
      spdlog::error("replay store '{}': write failed; marks kept in memory", path_);
    if (++lines_ > 4096 + 4 * marks_.size()) Compact();
  }
  return Verdict::kFresh;
}

int64_t ReplayStore::Mark(const std::string& sender) const {
  auto it = marks_.find(sender);
  return it == marks_.end() ? 0 : it->second.first;
}

// ---- envelopes

const char* ToString(AuthCheck check) {
  switch (check) {
    case AuthCheck::kOk:
      return "ok";
    case AuthCheck::kUnsigned:
      return "unsigned (not a signed_message_t)";
    case AuthCheck::kNoKey:
      return "signed with a key role this service does not hold";
    case AuthCheck::kWrongRole:
      return "signed with a key role not allowed on this channel";
    case AuthCheck::kForged:
      return "forged (HMAC mismatch)";
    case AuthCheck::kStale:
      return "outside the time window (replayed or clock skew)";
    case AuthCheck::kReplayed:
      return "replayed (seq not above the sender's last accepted)";
    case AuthCheck::kUndecodable:
      return "undecodable envelope";
  }
  return "?";
}

namespace {
void EnvelopeMac(const HmacKey& key, const std::string& channel, signed_message_t envelope,
                 uint8_t out[32]) {
  std::fill(std::begin(envelope.hmac), std::end(envelope.hmac), 0);
  std::vector<uint8_t> buffer(channel.size() + 1 + envelope.getEncodedSize());
  std::copy(channel.begin(), channel.end(), buffer.begin());
  buffer[channel.size()] = 0;
  envelope.encode(buffer.data() + channel.size() + 1, 0,
                  static_cast<int>(buffer.size() - channel.size() - 1));
  unsigned int length = 32;
  HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()), buffer.data(), buffer.size(), out,
       &length);
}
}  // namespace

EnvelopeSigner::EnvelopeSigner(std::string role, HmacKey key, std::string sender)
    : role_(std::move(role)), key_(std::move(key)), sender_(std::move(sender)) {
  if (key_.size() < 16) throw std::invalid_argument("no " + role_ + " key to sign with");
}

std::vector<uint8_t> EnvelopeSigner::SealBytes(const std::string& channel, const std::string& type,
                                               const std::vector<uint8_t>& inner) {
  signed_message_t envelope{};
  {
    std::lock_guard<std::mutex> lock(mutex_);
    envelope.utime = NowMicros();
    last_seq_ = std::max(envelope.utime, last_seq_ + 1);
    envelope.seq = last_seq_;
  }
  envelope.sender = sender_;
  envelope.key_role = role_;
  envelope.payload_type = type;
  envelope.payload_size = static_cast<int32_t>(inner.size());
  envelope.payload = inner;
  EnvelopeMac(key_, channel, envelope, envelope.hmac);
  std::vector<uint8_t> bytes(envelope.getEncodedSize());
  envelope.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

EnvelopeVerifier::EnvelopeVerifier(KeyRing keys, std::string state_path, double window_s,
                                   std::string service)
    : keys_(std::move(keys)), store_(std::move(state_path), window_s), service_(std::move(service)) {}

void EnvelopeVerifier::Refuse(AuthCheck check, const std::string& channel,
                              const std::string& detail, TransportCounters* counters) {
  if (counters) {
    if (check == AuthCheck::kForged)
      ++counters->forged;
    else if (check == AuthCheck::kReplayed || check == AuthCheck::kStale)
      ++counters->replayed;
    else
      ++counters->unsigned_count;
  }
  const std::string reason = ToString(check);
  const int64_t n = ++refused_[reason];
  last_refusal_ = channel + ": " + reason + (detail.empty() ? "" : " (" + detail + ")");
  // Every refusal leaves a line, but a flood does not fill the disk: the first 20 of each
  // reason, then every 1000th with the count.
  if (n <= 20 || n % 1000 == 0)
    spdlog::warn("{}: refused a message on {}: {}{} [{} so far]", service_, channel, reason,
                 detail.empty() ? "" : " (" + detail + ")", n);
}

AuthCheck EnvelopeVerifier::Verify(const std::string& channel, const uint8_t* data, size_t size,
                                   const std::vector<std::string>& roles,
                                   std::vector<uint8_t>* payload, Sender* sender,
                                   TransportCounters* counters) {
  signed_message_t envelope;
  TransportCounters scratch;
  if (!Decode(data, size, &envelope, &scratch, 65536)) {
    const AuthCheck check = scratch.foreign ? AuthCheck::kUnsigned : AuthCheck::kUndecodable;
    if (check == AuthCheck::kUndecodable && counters) ++counters->undecodable;
    Refuse(check, channel, "", check == AuthCheck::kUnsigned ? counters : nullptr);
    return check;
  }
  const std::string who = envelope.key_role + ":" + envelope.sender;
  const std::string detail = envelope.payload_type + " from " + who;
  if (std::find(roles.begin(), roles.end(), envelope.key_role) == roles.end()) {
    Refuse(AuthCheck::kWrongRole, channel, detail, counters);
    return AuthCheck::kWrongRole;
  }
  const HmacKey* key = keys_.Find(envelope.key_role);
  if (!key) {
    Refuse(AuthCheck::kNoKey, channel, detail, counters);
    return AuthCheck::kNoKey;
  }
  uint8_t mac[32];
  EnvelopeMac(*key, channel, envelope, mac);
  if (CRYPTO_memcmp(mac, envelope.hmac, 32) != 0) {
    Refuse(AuthCheck::kForged, channel, detail, counters);
    return AuthCheck::kForged;
  }
  const ReplayStore::Verdict verdict = store_.Accept(who, envelope.seq, envelope.utime);
  if (verdict != ReplayStore::Verdict::kFresh) {
    const AuthCheck check =
        verdict == ReplayStore::Verdict::kStale ? AuthCheck::kStale : AuthCheck::kReplayed;
    Refuse(check, channel, detail + ", seq " + std::to_string(envelope.seq), counters);
    return check;
  }
  if (payload) *payload = std::move(envelope.payload);
  if (sender) *sender = {envelope.sender, envelope.key_role, envelope.seq, envelope.utime};
  return AuthCheck::kOk;
}

nlohmann::json EnvelopeVerifier::Details() const {
  nlohmann::json refused = nlohmann::json::object();
  for (const auto& [reason, n] : refused_) refused[reason] = n;
  nlohmann::json roles = nlohmann::json::array();
  for (const auto& [role, key] : keys_.keys) roles.push_back(role);
  return {{"refused", refused}, {"last_refusal", last_refusal_}, {"senders", store_.size()},
          {"key_roles", roles}, {"replay_store", store_.path()}};
}

std::string CliSenderId() {
  const passwd* pw = getpwuid(getuid());
  return std::string("cli:") + (pw ? pw->pw_name : std::to_string(getuid())) + "@" + HostName();
}

}  // namespace idrig
