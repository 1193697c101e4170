#pragma once
// Channel names. Every rig's traffic carries its rig id, so rigs sharing a network do not mix:
//   IDRIG/<rig>/EXP_REQ     experiment_request_t   CLI -> excite
//   IDRIG/<rig>/CMD         actuator_command_t     excite -> rig (signed)
//   IDRIG/<rig>/MEAS        measurement_block_t    rig -> logger, workers
//   IDRIG/<rig>/EXP_STATUS  experiment_status_t    excite, rig -> everyone
//   IDRIG/<rig>/IDENT_REQ   identify_request_t     CLI, catalog (re-offer) -> workers, catalog
//   IDRIG/<rig>/CLAIM       identify_claim_t       workers <-> catalog
//   IDRIG/<rig>/RESULT      model_result_t         worker -> catalog
//   IDRIG/<rig>/ACK         result_ack_t           catalog -> worker
//   IDRIG/<rig>/REPLAY_REQ  replay_request_t       worker -> logger
//   IDRIG/<rig>/REPLAY      measurement_block_t    logger -> worker
//   IDRIG/<rig>/REPLAY_DONE replay_done_t          logger -> worker
//   IDRIG/<rig>/RIG_REPLAY_REQ replay_request_t    logger -> rig (blocks it lost; the rig
//                                                  re-publishes them on MEAS)
//   IDRIG/<rig>/REQ_REPLY   request_reply_t        excite, catalog -> CLI (accepted, refused, done)
//   EXP_REQ, IDENT_REQ, CLAIM, RESULT, ACK and REQ_REPLY carry signed_message_t envelopes
//   (core/transport/auth.h) around the types named above.
//   IDRIG/STATUS/<service>  service_status_t       every service, ~1 Hz
// LCM limits channel names to 63 characters: rig ids are 1..24 of [A-Za-z0-9_-].
#include <string>

namespace idrig {

enum class ChannelKind {
  kExperimentRequest,
  kCommand,
  kMeasurement,
  kExperimentStatus,
  kIdentifyRequest,
  kClaim,
  kResult,
  kAck,
  kReplayRequest,
  kReplay,
  kReplayDone,
  kRigReplayRequest,
  kRequestReply
};

// Throws std::invalid_argument naming the rule when the rig id is not usable in a channel.
void ValidateRigId(const std::string& rig_id);
// The same rule without throwing.
bool IsValidRigId(const std::string& rig_id);
// A message's rig id is the rig of the channel it came on, and usable in channel names (a
// handler that answers on Channel(rig_id, …) must check this first: Channel() throws).
bool IsRigOfChannel(const std::string& rig_id, const std::string& channel);
// "IDRIG/<rig>/<KIND>".
std::string Channel(const std::string& rig_id, ChannelKind kind);
// Regex matching the kind on every rig (for services that serve all rigs).
std::string AnyRigChannel(ChannelKind kind);
// The rig id of a channel "IDRIG/<rig>/…" ("" when it is not one).
std::string RigOfChannel(const std::string& channel);
std::string StatusChannel(const std::string& service);
inline constexpr const char* kAnyStatusChannel = "IDRIG/STATUS/.*";

}  // namespace idrig
