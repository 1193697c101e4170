// Service benchmarks (run by hand inside a private network namespace; see docs/services.md):
//   services_bench logger-rate BIN_DIR [seconds]   idrig-logger vs lcm-logger, 200-byte blocks
//   services_bench latency BIN_DIR [samples]       end of experiment -> model stored
//   services_bench jobs BIN_DIR WORKERS [jobs] [heavy]   identification jobs per second
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <idrig/experiment_request_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <idrig/measurement_block_t.hpp>
#include <idrig/result_ack_t.hpp>
#include <idrig/service_status_t.hpp>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/catalog/catalog.h"
#include "core/catalog/experiment_store.h"
#include "core/transport/channels.h"
#include "core/transport/auth.h"
#include "core/transport/signing.h"
#include "core/transport/transport.h"

using namespace idrig;
using Clock = std::chrono::steady_clock;

namespace {
const std::string kUrl = PrivateUdpmUrl(7733, 0);

pid_t Start(const std::vector<std::string>& command, const std::string& log) {
  std::vector<std::string> args = command;
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    execvp(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}
void Stop(pid_t pid) {
  kill(pid, SIGTERM);
  int status;
  waitpid(pid, &status, 0);
}
long PeakKb(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}
template <class P>
bool Until(Transport& t, P done, double seconds) {
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < end) {
    t.Handle(5);
    if (done()) return true;
  }
  return false;
}
std::string Dir(const std::string& name) {
  const std::string dir = "/tmp/idrig_bench_" + name + "_" + std::to_string(getpid());
  std::system(("rm -rf " + dir + " && mkdir -p " + dir).c_str());
  return dir;
}

int LoggerRate(const std::string& bin, double seconds) {
  const std::string dir = Dir("logger");
  const pid_t logger = Start(
      {bin + "/idrig-logger", "--db", dir + "/experiments.db", "--url", kUrl}, dir + "/logger.log");
  const pid_t lcm_logger =
      Start({"lcm-logger", "--lcm-url=" + kUrl, "-c", "IDRIG/bench/MEAS", "-q", dir + "/lcm.log"},
            dir + "/lcm-logger.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  auto t = MakeLcmTransport(kUrl);
  measurement_block_t block{};
  block.rig_id = "bench";
  block.sample_time_s = 0.001;
  block.n_samples = 9;
  block.n_inputs = 1;
  block.n_outputs = 1;
  block.u.assign(9, {0.5});
  block.y.assign(9, {0.25});
  std::printf("block size %d bytes; %s s per rate\n", block.getEncodedSize(),
              std::to_string(seconds).c_str());
  std::printf("%10s %10s %14s %14s\n", "rate/s", "sent", "idrig-logger", "lcm-logger");
  int64_t experiment = 1;
  int64_t lcm_total = 0;
  for (int rate : {5000, 10000, 20000, 30000, 40000, 50000, 60000, 80000}) {
    const int64_t n = static_cast<int64_t>(rate * seconds);
    block.experiment_id = experiment;
    const auto start = Clock::now();
    for (int64_t k = 0; k < n; ++k) {
      block.seq = k;
      block.first_sample = 9 * k;
      block.utime = NowMicros();
      t->PublishMessage("IDRIG/bench/MEAS", block);
      // Paced in bursts of 20 messages (a sleeping sender leaves the cores to the receivers).
      if (k % 20 == 19)
        std::this_thread::sleep_until(
            start + std::chrono::nanoseconds(static_cast<int64_t>(1e9 * (k + 1) / rate)));
    }
    const double achieved = n / std::chrono::duration<double>(Clock::now() - start).count();
    std::this_thread::sleep_for(std::chrono::seconds(2));  // writers drain
    int64_t stored = 0;
    {
      ExperimentStore store(dir + "/experiments.db");
      stored = static_cast<int64_t>(store.BlockSeqs("bench", experiment).size());
    }
    int64_t lcm_count = 0;
    {
      lcm::LogFile log(dir + "/lcm.log", "r");
      while (const lcm::LogEvent* e = log.readNextEvent()) {
        measurement_block_t b;
        if (e->channel == "IDRIG/bench/MEAS" && b.decode(e->data, 0, e->datalen) > 0 &&
            b.experiment_id == experiment)
          ++lcm_count;
      }
    }
    lcm_total += lcm_count;
    std::printf("%10d %10lld %13.2f%% %13.2f%%   (achieved %.0f/s)\n", rate,
                static_cast<long long>(n), 100.0 * stored / n, 100.0 * lcm_count / n, achieved);
    std::fflush(stdout);
    ++experiment;
  }
  std::printf("idrig-logger peak memory (VmHWM): %ld kB; lcm-logger: %ld kB\n", PeakKb(logger),
              PeakKb(lcm_logger));
  Stop(logger);
  Stop(lcm_logger);
  return 0;
}

struct Cluster {
  std::string dir;
  std::vector<pid_t> pids;
  Cluster(const std::string& bin, const std::string& name, int workers, int rig_block,
          int excite_block) {
    dir = Dir(name);
    WriteNewKeyFile(dir + "/hmac.key");
    WriteNewKeyFile(dir + "/operator.key");
    WriteNewKeyFile(dir + "/service.key");
    const std::string keys = "\"operator_key_file\":\"" + dir + "/operator.key\",\"service_key_file\":\"" +
                             dir + "/service.key\"";
    std::ofstream(dir + "/catalog.json") << "{\"db_path\":\"" << dir << "/catalog.db\"," << keys << "}";
    std::ofstream(dir + "/worker.json") << "{" << keys << "}";
    std::ofstream(dir + "/plant.json")
        << R"({"format":"idrig.model/1","kind":"tf","domain":"continuous","Ts":0,"num":[0.5,1],"den":[1,2.5,4,1.5]})";
    std::ofstream(dir + "/rig.json")
        << "{\"rig_id\":\"bench\",\"model_file\":\"" << dir
        << "/plant.json\",\"noise_std\":0.001,\"key_file\":\"" << dir
        << "/hmac.key\",\"block_samples\":" << rig_block << ",\"max_abs\":5}";
    std::ofstream(dir + "/excite.json") << "{\"rig_id\":\"bench\",\"key_file\":\"" << dir
                                        << "/hmac.key\",\"block_samples\":" << excite_block
                                        << ",\"max_abs\":5,\"max_speed\":100000," << keys << "}";
    pids.push_back(Start({bin + "/idrig-catalog", "--config", dir + "/catalog.json", "--url", kUrl},
                         dir + "/catalog.log"));
    pids.push_back(Start({bin + "/idrig-logger", "--db", dir + "/experiments.db", "--url", kUrl},
                         dir + "/logger.log"));
    pids.push_back(Start({bin + "/idrig-rig-sim", "--config", dir + "/rig.json", "--url", kUrl},
                         dir + "/rig.log"));
    pids.push_back(Start({bin + "/idrig-excite", "--config", dir + "/excite.json", "--url", kUrl},
                         dir + "/excite.log"));
    for (int w = 0; w < workers; ++w)
      pids.push_back(Start({bin + "/idrig-worker", "--config", dir + "/worker.json", "--id",
                            "bw" + std::to_string(w), "--url", kUrl},
                           dir + "/w.log"));
  }
  ~Cluster() {
    for (pid_t p : pids) Stop(p);
  }
};

struct Client {
  std::unique_ptr<Transport> t = MakeLcmTransport(kUrl);
  KeyRing keys;
  std::unique_ptr<EnvelopeSigner> signer;
  std::unique_ptr<EnvelopeVerifier> verifier;
  std::set<std::string> services;
  experiment_status_t rig{};
  std::map<int64_t, int64_t> acks;  // request id -> receive time [µs]
  std::map<int64_t, result_ack_t> ack_messages;
  explicit Client(const std::string& dir) {
    keys.keys[kOperatorRole] = ReadKeyFile(dir + "/operator.key");
    keys.keys[kServiceRole] = ReadKeyFile(dir + "/service.key");
    signer = std::make_unique<EnvelopeSigner>(kOperatorRole, keys.keys[kOperatorRole], "bench");
    verifier = std::make_unique<EnvelopeVerifier>(keys, "", 300, "bench");
    t->Subscribe("IDRIG/STATUS/.*", [&](const std::string&, const uint8_t* d, size_t n) {
      service_status_t s;
      if (Decode(d, n, &s, nullptr)) services.insert(s.instance_id);
    });
    t->Subscribe("IDRIG/bench/EXP_STATUS", [&](const std::string&, const uint8_t* d, size_t n) {
      experiment_status_t s;
      if (Decode(d, n, &s, nullptr) && s.source == "rig") rig = s;
    });
    t->Subscribe(
        "IDRIG/bench/ACK",
        [&](const std::string& channel, const uint8_t* d, size_t n) {
          result_ack_t a;
          if (verifier->Open(channel, d, n, {kServiceRole}, &a, nullptr, nullptr) &&
              !acks.count(a.request_id)) {
            acks[a.request_id] = NowMicros();
            ack_messages[a.request_id] = a;
          }
        },
        10000);
  }
  void Experiment(int64_t id, const std::string& spec, double fs, double duration, double speed) {
    experiment_request_t r{};
    r.utime = NowMicros();
    r.request_id = id;
    r.rig_id = "bench";
    r.experiment_id = id;
    r.action = experiment_request_t::ACTION_START;
    r.signal_spec = spec;
    r.sample_rate_hz = fs;
    r.duration_s = duration;
    r.speed = speed;
    signer->Publish(*t, "IDRIG/bench/EXP_REQ", r);
  }
  void Identify(int64_t request_id, int64_t experiment, const std::string& method,
                const std::string& options) {
    identify_request_t r{};
    r.utime = NowMicros();
    r.request_id = request_id;
    r.rig_id = "bench";
    r.experiment_id = experiment;
    r.method = method;
    r.options_json = options;
    signer->Publish(*t, "IDRIG/bench/IDENT_REQ", r);
  }
};

int Latency(const std::string& bin, int64_t samples) {
  Cluster cluster(bin, "latency", 1, 1000, 500);
  Client c(cluster.dir);
  if (!Until(
          *c.t, [&] { return c.services.size() >= 5; }, 10))
    return 1;
  const double fs = 1000.0;
  std::printf("%lld samples at %.0f Hz in blocks of 1000 (16 KB)\n",
              static_cast<long long>(samples), fs);
  int64_t request = 100;
  for (const char* method : {"arx", "arx-oe"}) {
    for (int run = 0; run < 3; ++run) {
      const int64_t experiment = 1000 + request;
      c.rig = experiment_status_t{};
      c.Experiment(experiment, "prbs:bits=12,amp=1", fs, samples / fs, 200.0);
      if (!Until(
              *c.t,
              [&] {
                return c.rig.experiment_id == experiment &&
                       c.rig.state == experiment_status_t::STATE_DONE;
              },
              30)) {
        std::printf("experiment did not finish\n");
        return 1;
      }
      const int64_t end = c.rig.end_utime;
      c.Identify(++request, experiment, method, "{\"order\":3}");
      if (!Until(
              *c.t, [&] { return c.acks.count(request) > 0; }, 30)) {
        std::printf("no ack\n");
        return 1;
      }
      Catalog catalog(cluster.dir + "/catalog.db", true);
      const auto m = catalog.ModelForRequest(request);
      std::printf(
          "%-7s run %d: end of experiment -> model committed %.3f s, -> ack heard %.3f s (compute "
          "%.3f s, %lld samples)\n",
          method, run + 1, 1e-6 * (m->created_utime - end), 1e-6 * (c.acks[request] - end),
          m->compute_s, static_cast<long long>(m->n_samples));
      std::fflush(stdout);
    }
  }
  return 0;
}

int Jobs(const std::string& bin, int workers, int jobs, bool heavy) {
  // light: arx on 511 samples (a few ms); heavy: arx-oe on 5110 samples (tens of ms).
  const double fs = heavy ? 100.0 : 10.0;
  const std::string method = heavy ? "arx-oe" : "arx";
  Cluster cluster(bin, "jobs" + std::to_string(workers), workers, 100, 50);
  Client c(cluster.dir);
  if (!Until(
          *c.t, [&] { return static_cast<int>(c.services.size()) >= 4 + workers; }, 10))
    return 1;
  c.Experiment(77, "prbs:bits=9,amp=1", fs, 51.1, heavy ? 1000.0 : 200.0);
  if (!Until(
          *c.t,
          [&] {
            return c.rig.experiment_id == 77 && c.rig.state == experiment_status_t::STATE_DONE;
          },
          20))
    return 1;
  Until(
      *c.t, [] { return false; }, 0.5);
  const auto start = Clock::now();
  for (int j = 0; j < jobs; ++j) c.Identify(5000 + j, 77, method, "{\"order\":3}");
  auto last = Clock::now();
  const bool ok = Until(
      *c.t,
      [&] {
        if (Clock::now() - last > std::chrono::seconds(2)) {  // re-send lost requests
          for (int j = 0; j < jobs; ++j)
            if (!c.acks.count(5000 + j)) c.Identify(5000 + j, 77, method, "{\"order\":3}");
          last = Clock::now();
        }
        return static_cast<int>(c.acks.size()) >= jobs;
      },
      120);
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  std::map<std::string, int> per_worker;
  for (const auto& [id, a] : c.ack_messages) ++per_worker[a.worker_id];
  std::printf("%d worker(s): %d jobs (%s, %d samples) in %.2f s = %.1f jobs/s%s;", workers, jobs,
              method.c_str(), static_cast<int>(fs * 51.1 + 0.5), elapsed, jobs / elapsed,
              ok ? "" : " (INCOMPLETE)");
  for (const auto& [w, n] : per_worker) std::printf(" %s %d", w.c_str(), n);
  Catalog catalog(cluster.dir + "/catalog.db", true);
  std::printf("; models stored %lld\n", static_cast<long long>(catalog.CountModels()));
  return ok ? 0 : 1;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: services_bench logger-rate|latency|jobs BIN_DIR [args]\n");
    return 2;
  }
  const std::string mode = argv[1], bin = argv[2];
  if (mode == "logger-rate") return LoggerRate(bin, argc > 3 ? std::stod(argv[3]) : 2.0);
  if (mode == "latency") return Latency(bin, argc > 3 ? std::stoll(argv[3]) : 100000);
  if (mode == "jobs")
    return Jobs(bin, argc > 3 ? std::stoi(argv[3]) : 1, argc > 4 ? std::stoi(argv[4]) : 40,
                argc > 5 && std::string(argv[5]) == "heavy");
  std::fprintf(stderr, "unknown mode %s\n", mode.c_str());
  return 2;
}
