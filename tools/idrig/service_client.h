#pragma once
// What the command line needs to talk to the services: publish requests, collect the latest
// experiment and service status, spawn and stop service processes (idrig demo).
#include <idrig/experiment_status_t.hpp>
#include <idrig/request_reply_t.hpp>
#include <idrig/service_status_t.hpp>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "core/transport/auth.h"
#include "core/transport/transport.h"

namespace idrig {

// A command that did not do what was asked (refused, failed job, no answer): main() prints the
// reason and exits with code() (1; 2 for bad input such as a missing key).
class CommandFailure : public std::runtime_error {
 public:
  explicit CommandFailure(const std::string& what, int code = 1)
      : std::runtime_error(what), code_(code) {}
  int code() const { return code_; }

 private:
  int code_;
};

// The operator key file: the flag's value, else $IDRIG_KEY_FILE, else "".
std::string OperatorKeyPath(const std::string& flag_value);

// The default URL of the command line: LCM_DEFAULT_URL, else LCM's own default with ttl=0.
std::string DefaultLcmUrl();

class ServiceClient {
 public:
  // key_file: the operator key (OperatorKeyPath); needed by the commands that change state
  // (they throw CommandFailure saying how to give it), not by readers.
  explicit ServiceClient(const std::string& url, const std::string& key_file = "");
  Transport& transport() { return *transport_; }
  // Dispatches messages for `ms` milliseconds.
  void Spin(int ms);
  bool has_key() const { return signer_.has_value(); }

  // The latest verified answer of `source` ("excite" or "catalog") to a request; nullptr if none.
  const request_reply_t* Reply(int64_t request_id, const std::string& source) const;
  // Calls send() now and every resend_s until `source` answers request_id with a state in
  // `states` (or a refusal); says on stderr that it waits after 1 s. Throws CommandFailure
  // naming `who` when nothing answers within timeout_s, or with the reason when refused.
  const request_reply_t& AwaitReply(int64_t request_id, const std::string& source,
                                    const std::string& who, const std::function<void()>& send,
                                    double timeout_s, std::vector<int32_t> states,
                                    double resend_s = 1.0);

  int64_t StartExperiment(const std::string& rig, int64_t experiment_id, const std::string& spec,
                          double fs, double duration_s, double speed, double max_abs,
                          int64_t request_id = 0);
  void StopExperiment(const std::string& rig, int64_t experiment_id, int64_t request_id);
  void RequestIdentify(const std::string& rig, int64_t request_id, int64_t experiment_id,
                       const std::string& method, const std::string& options_json);

  // Latest status of an experiment from a source ("excite" or "rig"); nullptr if none heard.
  const experiment_status_t* ExperimentStatus(const std::string& rig, int64_t experiment_id,
                                              const std::string& source) const;
  const std::map<std::tuple<std::string, int64_t, std::string>, experiment_status_t>& experiments()
      const {
    return experiments_;
  }
  const std::map<std::string, service_status_t>& services() const { return services_; }

 private:
  EnvelopeSigner& Signer();
  std::unique_ptr<Transport> transport_;
  std::optional<EnvelopeSigner> signer_;
  std::optional<EnvelopeVerifier> verifier_;
  std::string key_error_;
  std::map<std::pair<int64_t, std::string>, request_reply_t> replies_;
  std::map<std::tuple<std::string, int64_t, std::string>, experiment_status_t> experiments_;
  std::map<std::string, service_status_t> services_;  // by instance id
};

// A unique id from the clock and the process id (experiment and request ids).
int64_t NewId();
const char* ExperimentStateName(int32_t state);

// Child processes of `idrig demo`.
struct ChildProcess {
  std::string name;
  int pid = -1;
  std::string log_path;
};
// Starts `program args…` with stdout and stderr appended to log_path. Throws on failure.
ChildProcess Spawn(const std::string& name, const std::string& program,
                   const std::vector<std::string>& args, const std::string& log_path);
// SIGTERM, then SIGKILL after grace_s.
void StopChild(ChildProcess& child, double grace_s = 2.0);
bool ChildAlive(const ChildProcess& child);
// Directory of the running executable (to find idrig-* next to idrig).
std::string ExecutableDir();
// The running idrig (/proc/self/exe) as a command that works from the current directory:
// relative ("build/bin/idrig") when it lies below it, else absolute.
std::string CommandPathFromHere();

}  // namespace idrig
