#pragma once
// What the command line needs to talk to the services: publish requests, collect the latest
// experiment and service status, spawn and stop service processes (idrig demo).
#include <idrig/experiment_status_t.hpp>
#include <idrig/result_ack_t.hpp>
#include <idrig/service_status_t.hpp>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "core/transport/transport.h"

namespace idrig {

// The default URL of the command line: LCM_DEFAULT_URL, else LCM's own default with ttl=0.
std::string DefaultLcmUrl();

class ServiceClient {
 public:
  explicit ServiceClient(const std::string& url);
  Transport& transport() { return *transport_; }
  // Dispatches messages for `ms` milliseconds.
  void Spin(int ms);

  int64_t StartExperiment(const std::string& rig, int64_t experiment_id, const std::string& spec,
                          double fs, double duration_s, double speed, double max_abs,
                          int64_t request_id = 0);
  void StopExperiment(const std::string& rig, int64_t experiment_id);
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
  const std::map<int64_t, result_ack_t>& acks() const { return acks_; }

 private:
  std::unique_ptr<Transport> transport_;
  std::map<std::tuple<std::string, int64_t, std::string>, experiment_status_t> experiments_;
  std::map<std::string, service_status_t> services_;  // by instance id
  std::map<int64_t, result_ack_t> acks_;              // by request id
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
