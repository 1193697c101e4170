#include "core/transport/channels.h"

#include <stdexcept>

namespace idrig {
namespace {
const char* Suffix(ChannelKind kind) {
  switch (kind) {
    case ChannelKind::kExperimentRequest:
      return "EXP_REQ";
    case ChannelKind::kCommand:
      return "CMD";
    case ChannelKind::kMeasurement:
      return "MEAS";
    case ChannelKind::kExperimentStatus:
      return "EXP_STATUS";
    case ChannelKind::kIdentifyRequest:
      return "IDENT_REQ";
    case ChannelKind::kClaim:
      return "CLAIM";
    case ChannelKind::kResult:
      return "RESULT";
    case ChannelKind::kAck:
      return "ACK";
    case ChannelKind::kReplayRequest:
      return "REPLAY_REQ";
    case ChannelKind::kReplay:
      return "REPLAY";
    case ChannelKind::kReplayDone:
      return "REPLAY_DONE";
    case ChannelKind::kRigReplayRequest:
      return "RIG_REPLAY_REQ";
    case ChannelKind::kRequestReply:
      return "REQ_REPLY";
  }
  return "?";
}
}  // namespace

void ValidateRigId(const std::string& rig_id) {
  if (rig_id.empty() || rig_id.size() > 24)
    throw std::invalid_argument("rig id '" + rig_id + "' must have 1 to 24 characters");
  for (char c : rig_id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-';
    if (!ok)
      throw std::invalid_argument("rig id '" + rig_id +
                                  "' may only use letters, digits, '_' and '-'");
  }
}

bool IsValidRigId(const std::string& rig_id) {
  try {
    ValidateRigId(rig_id);
    return true;
  } catch (const std::invalid_argument&) {
    return false;
  }
}

bool IsRigOfChannel(const std::string& rig_id, const std::string& channel) {
  return rig_id == RigOfChannel(channel) && IsValidRigId(rig_id);
}

std::string Channel(const std::string& rig_id, ChannelKind kind) {
  ValidateRigId(rig_id);
  return "IDRIG/" + rig_id + "/" + Suffix(kind);
}

std::string AnyRigChannel(ChannelKind kind) {
  return std::string("IDRIG/[A-Za-z0-9_-]+/") + Suffix(kind);
}

std::string RigOfChannel(const std::string& channel) {
  if (channel.rfind("IDRIG/", 0) != 0) return "";
  const auto end = channel.find('/', 6);
  if (end == std::string::npos) return "";
  return channel.substr(6, end - 6);
}

std::string StatusChannel(const std::string& service) { return "IDRIG/STATUS/" + service; }

}  // namespace idrig
