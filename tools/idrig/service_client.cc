#include "tools/idrig/service_client.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <idrig/experiment_request_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <stdexcept>
#include <thread>

#include "core/transport/channels.h"

namespace idrig {

std::string DefaultLcmUrl() {
  const char* env = std::getenv("LCM_DEFAULT_URL");
  if (env && *env) return env;
  return "udpm://239.255.76.67:7667?ttl=0";
}

std::string OperatorKeyPath(const std::string& flag_value) {
  if (!flag_value.empty()) return flag_value;
  const char* env = std::getenv("IDRIG_KEY_FILE");
  return env && *env ? env : "";
}

ServiceClient::ServiceClient(const std::string& url, const std::string& key_file)
    : transport_(MakeLcmTransport(url)) {
  if (key_file.empty()) {
    key_error_ = "this command changes state and needs the operator key: --key-file FILE or "
                 "IDRIG_KEY_FILE=FILE (the demo's is idrig-demo/operator.key; make one with "
                 "`openssl rand -hex 32 > FILE && chmod 600 FILE` and give it to idrig-excite "
                 "and idrig-catalog as operator_key_file)";
  } else {
    KeyRing ring;
    ring.keys[kOperatorRole] = ReadKeyFile(key_file);  // std::invalid_argument: exit 2
    signer_.emplace(kOperatorRole, ring.keys[kOperatorRole], CliSenderId());
    verifier_.emplace(ring, "", 300.0, "idrig");
    transport_->Subscribe(
        AnyRigChannel(ChannelKind::kRequestReply),
        [this](const std::string& channel, const uint8_t* d, size_t n) {
          request_reply_t r;
          if (!verifier_->Open(channel, d, n, {kOperatorRole}, &r, nullptr, &transport_->counters()))
            return;
          auto& slot = replies_[{r.request_id, r.source}];
          if (r.utime >= slot.utime) slot = r;
        },
        1000);
  }
  transport_->Subscribe(
      AnyRigChannel(ChannelKind::kExperimentStatus),
      [this](const std::string&, const uint8_t* d, size_t n) {
        experiment_status_t s;
        if (!Decode(d, n, &s, &transport_->counters())) return;
        auto& slot = experiments_[{s.rig_id, s.experiment_id, s.source}];
        if (s.utime >= slot.utime) slot = s;
      },
      1000);
  transport_->Subscribe(
      kAnyStatusChannel,
      [this](const std::string&, const uint8_t* d, size_t n) {
        service_status_t s;
        if (!Decode(d, n, &s, &transport_->counters())) return;
        services_[s.instance_id] = s;
      },
      1000);
}

EnvelopeSigner& ServiceClient::Signer() {
  if (!signer_) throw CommandFailure(key_error_, 2);
  return *signer_;
}

const request_reply_t* ServiceClient::Reply(int64_t request_id, const std::string& source) const {
  auto it = replies_.find({request_id, source});
  return it == replies_.end() ? nullptr : &it->second;
}

const request_reply_t& ServiceClient::AwaitReply(int64_t request_id, const std::string& source,
                                                 const std::string& who,
                                                 const std::function<void()>& send,
                                                 double timeout_s, std::vector<int32_t> states,
                                                 double resend_s) {
  Signer();
  states.push_back(request_reply_t::STATE_REFUSED);
  const auto start = std::chrono::steady_clock::now();
  auto last_send = start;
  bool said = false;
  send();
  for (;;) {
    Spin(100);
    const request_reply_t* reply = Reply(request_id, source);
    if (reply && std::find(states.begin(), states.end(), reply->state) != states.end()) {
      if (reply->state == request_reply_t::STATE_REFUSED)
        throw CommandFailure("request " + std::to_string(request_id) + " refused by " + who + ": " +
                             reply->message);
      return *reply;
    }
    const auto now = std::chrono::steady_clock::now();
    const double waited = std::chrono::duration<double>(now - start).count();
    if (waited > timeout_s)
      throw CommandFailure(
          "no answer from " + who + " to request " + std::to_string(request_id) + " within " +
          std::to_string(static_cast<int>(timeout_s)) + " s" +
          (reply ? " (last: " + reply->message + ")"
                 : " (is it running, on this URL, with the same operator key?); nothing was "
                   "queued"));
    if (!said && waited > 1.0 && !reply) {
      std::cerr << "waiting for " << who << " to acknowledge request " << request_id
                << " (re-sending every " << resend_s << " s, up to " << timeout_s << " s)…\n";
      said = true;
    }
    if (std::chrono::duration<double>(now - last_send).count() >= resend_s) {
      send();  // idempotent by request id; a fresh signature each time
      last_send = now;
    }
  }
}

void ServiceClient::Spin(int ms) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
  while (std::chrono::steady_clock::now() < end) {
    const int left = static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                          end - std::chrono::steady_clock::now())
                                          .count());
    transport_->Handle(std::max(1, std::min(left, 50)));
  }
}

int64_t NewId() {
  static int64_t last = 0;
  int64_t id = (NowMicros() / 1000) * 1000 + (getpid() % 1000);
  if (id <= last) id = last + 1;
  last = id;
  return id;
}

const char* ExperimentStateName(int32_t state) {
  switch (state) {
    case experiment_status_t::STATE_PENDING:
      return "pending";
    case experiment_status_t::STATE_RUNNING:
      return "running";
    case experiment_status_t::STATE_DONE:
      return "done";
    case experiment_status_t::STATE_STOPPED:
      return "stopped";
    case experiment_status_t::STATE_FAILED:
      return "failed";
    case experiment_status_t::STATE_INTERRUPTED:
      return "interrupted";
  }
  return "unknown";
}

int64_t ServiceClient::StartExperiment(const std::string& rig, int64_t experiment_id,
                                       const std::string& spec, double fs, double duration_s,
                                       double speed, double max_abs, int64_t request_id) {
  experiment_request_t r{};
  r.utime = NowMicros();
  r.request_id = request_id > 0 ? request_id : NewId();
  r.rig_id = rig;
  r.experiment_id = experiment_id;
  r.action = experiment_request_t::ACTION_START;
  r.signal_spec = spec;
  r.sample_rate_hz = fs;
  r.duration_s = duration_s;
  r.speed = speed;
  r.max_abs = max_abs;
  r.requested_by = Signer().sender();
  Signer().Publish(*transport_, Channel(rig, ChannelKind::kExperimentRequest), r);
  return r.request_id;
}

void ServiceClient::StopExperiment(const std::string& rig, int64_t experiment_id,
                                   int64_t request_id) {
  experiment_request_t r{};
  r.utime = NowMicros();
  r.request_id = request_id;
  r.rig_id = rig;
  r.experiment_id = experiment_id;
  r.action = experiment_request_t::ACTION_STOP;
  r.requested_by = Signer().sender();
  Signer().Publish(*transport_, Channel(rig, ChannelKind::kExperimentRequest), r);
}

void ServiceClient::RequestIdentify(const std::string& rig, int64_t request_id,
                                    int64_t experiment_id, const std::string& method,
                                    const std::string& options_json) {
  identify_request_t r{};
  r.utime = NowMicros();
  r.request_id = request_id;
  r.rig_id = rig;
  r.experiment_id = experiment_id;
  r.method = method;
  r.options_json = options_json.empty() ? "{}" : options_json;
  r.requested_by = Signer().sender();
  Signer().Publish(*transport_, Channel(rig, ChannelKind::kIdentifyRequest), r);
}

const experiment_status_t* ServiceClient::ExperimentStatus(const std::string& rig,
                                                           int64_t experiment_id,
                                                           const std::string& source) const {
  auto it = experiments_.find({rig, experiment_id, source});
  return it == experiments_.end() ? nullptr : &it->second;
}

ChildProcess Spawn(const std::string& name, const std::string& program,
                   const std::vector<std::string>& args, const std::string& log_path) {
  std::vector<std::string> argv_storage = {program};
  argv_storage.insert(argv_storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_storage) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("cannot fork for " + name);
  if (pid == 0) {
    const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      close(fd);
    }
    execv(program.c_str(), argv.data());
    _exit(127);
  }
  return {name, static_cast<int>(pid), log_path};
}

bool ChildAlive(const ChildProcess& child) {
  if (child.pid <= 0) return false;
  int status = 0;
  return waitpid(child.pid, &status, WNOHANG) == 0;
}

void StopChild(ChildProcess& child, double grace_s) {
  if (child.pid <= 0) return;
  kill(child.pid, SIGTERM);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(grace_s);
  int status = 0;
  while (std::chrono::steady_clock::now() < end) {
    if (waitpid(child.pid, &status, WNOHANG) != 0) {
      child.pid = -1;
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(child.pid, SIGKILL);
  waitpid(child.pid, &status, 0);
  child.pid = -1;
}

std::string ExecutableDir() {
  char path[4096] = {0};
  const ssize_t n = readlink("/proc/self/exe", path, sizeof(path) - 1);
  if (n <= 0) return ".";
  std::string s(path, static_cast<size_t>(n));
  return s.substr(0, s.find_last_of('/'));
}

std::string CommandPathFromHere() {
  const std::string exe = ExecutableDir() + "/idrig";
  char cwd[4096] = {0};
  if (!getcwd(cwd, sizeof(cwd) - 1)) return exe;
  const std::string here = std::string(cwd) + "/";
  if (exe.compare(0, here.size(), here) == 0) return exe.substr(here.size());
  return exe;
}

}  // namespace idrig
