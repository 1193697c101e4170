// `idrig demo`: every service on a private LCM URL (re-run inside `unshare -n` when this
// machine has no multicast route), a step and a multisine experiment on the simulated rig,
// identification with two methods each, and the stored models with their history.
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>

#include "core/catalog/catalog.h"
#include "core/io/gap_json.h"
#include "core/io/model_json.h"
#include "core/transport/channels.h"
#include "core/transport/signing.h"
#include "tools/idrig/commands.h"
#include "tools/idrig/model_print.h"
#include "tools/idrig/service_client.h"

namespace idrig {
namespace {

std::vector<std::string> g_args;  // the command line, for re-executing inside a namespace

bool MulticastWorks(const std::string& url) {
  try {
    auto t = MakeLcmTransport(url);
    bool received = false;
    t->Subscribe("IDRIG_PROBE",
                 [&](const std::string&, const uint8_t*, size_t) { received = true; });
    const uint8_t byte = 1;
    if (t->Publish("IDRIG_PROBE", &byte, 1) != 0) return false;
    for (int i = 0; i < 10 && !received; ++i) t->Handle(50);
    return received;
  } catch (const std::exception&) {
    return false;
  }
}

// Re-runs this command inside a private network namespace whose loopback carries multicast.
[[noreturn]] void ReexecInNetns() {
  setenv("IDRIG_IN_NETNS", "1", 1);
  std::vector<std::string> args = {
      "unshare",
      geteuid() == 0 ? "-n" : "-rn",
      "sh",
      "-c",
      "ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo && exec \"$0\" \"$@\"",
      ExecutableDir() + "/idrig"};
  args.insert(args.end(), g_args.begin() + 1, g_args.end());
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  execvp("unshare", argv.data());
  throw std::runtime_error(
      "no multicast route here, and `unshare` could not be run (install util-linux)");
}

void WriteJson(const std::string& path, const nlohmann::json& j) {
  std::ofstream out(path);
  out << j.dump(2) << "\n";
}

struct DemoJob {
  int64_t request_id;
  int64_t experiment_id;
  std::string label, method, options;
};


// The demo's "simulation model": the rig's plant with its last denominator coefficient 20 % low
// (1.2 instead of 1.5), as a designer's model with a mis-estimated stiffness would be.
TransferFunction DemoSimModel(const TransferFunction& plant) {
  TransferFunction sim = plant;
  sim.den(sim.den.size() - 1) *= 0.8;
  return sim;
}

void RunDemo(const std::string& dir, int port, double speed, int workers, bool allow_netns) {
  const std::string url = PrivateUdpmUrl(port, 0);
  if (!MulticastWorks(url)) {
    if (allow_netns && !std::getenv("IDRIG_IN_NETNS")) {
      std::cout << "no multicast route on this machine: re-running inside a private network "
                   "namespace (unshare -n; lo gets multicast and 224.0.0.0/4)\n"
                << std::flush;
      ReexecInNetns();
    }
    throw std::runtime_error("LCM multicast does not work on " + url +
                             " (add a route: ip route add 224.0.0.0/4 dev lo)");
  }
  mkdir(dir.c_str(), 0755);
  mkdir((dir + "/logs").c_str(), 0755);
  const std::string rig = "sim1";
  // Three deployment keys (docs/services.md, "Authentication"): commands (excite -> rig), the
  // operator's (requests from the command line), the services' (claims, results, acks).
  const std::string key_file = dir + "/hmac.key", operator_key = dir + "/operator.key",
                    service_key = dir + "/service.key";
  for (const std::string& k : {key_file, operator_key, service_key}) {
    try {
      ReadKeyFile(k);
    } catch (const std::invalid_argument&) {
      WriteNewKeyFile(k);  // missing (or weak, or readable by others): a new one
    }
  }
  const std::string state = dir + "/state";
  mkdir(state.c_str(), 0700);
  // The simulated rig: seed 001's plant W(p) = (0.5p + 1)/(p^3 + 2.5p^2 + 4p + 1.5) + noise.
  TransferFunction plant;
  plant.num = Eigen::Vector2d(0.5, 1.0);
  plant.den = Eigen::Vector4d(1.0, 2.5, 4.0, 1.5);
  WriteModelFile(plant, dir + "/plant.json");
  WriteJson(dir + "/catalog.json", {{"db_path", dir + "/catalog.db"},
                                    {"lease_s", 3.0},
                                    {"offer_period_s", 0.5},
                                    {"operator_key_file", operator_key},
                                    {"service_key_file", service_key},
                                    {"state_dir", state}});
  WriteJson(dir + "/logger.json", {{"db_path", dir + "/experiments.db"}});
  WriteJson(dir + "/rig_sim.json", {{"rig_id", rig},
                                    {"model_file", dir + "/plant.json"},
                                    {"noise_std", 0.005},
                                    {"seed", 1},
                                    {"max_abs", 5.0},
                                    {"max_rate", 2000.0},
                                    {"watchdog_s", 2.0},
                                    {"block_samples", 100},
                                    {"key_file", key_file},
                                    {"key_id", 1},
                                    {"state_dir", state + "/rig"}});
  WriteJson(dir + "/excite.json", {{"rig_id", rig},
                                   {"key_file", key_file},
                                   {"key_id", 1},
                                   {"operator_key_file", operator_key},
                                   {"state_dir", state},
                                   {"block_samples", 20},
                                   {"max_abs", 5.0},
                                   {"max_rate", 2000.0}});
  WriteJson(dir + "/worker.json", {{"renew_s", 0.5},
                                   {"replay_retry_s", 0.3},
                                   {"operator_key_file", operator_key},
                                   {"service_key_file", service_key},
                                   {"state_dir", state}});

  const std::string bin = ExecutableDir();
  std::vector<ChildProcess> children;
  auto spawn = [&](const std::string& name, const std::string& program,
                   std::vector<std::string> args) {
    args.push_back("--url");
    args.push_back(url);
    children.push_back(Spawn(name, bin + "/" + program, args, dir + "/logs/" + name + ".log"));
  };
  std::cout << "idrig demo: services on " << url << ", files in " << dir << "/\n";
  spawn("catalog", "idrig-catalog", {"--config", dir + "/catalog.json"});
  spawn("logger", "idrig-logger", {"--config", dir + "/logger.json"});
  spawn("rig-sim", "idrig-rig-sim", {"--config", dir + "/rig_sim.json"});
  spawn("excite", "idrig-excite", {"--config", dir + "/excite.json"});
  for (int w = 1; w <= workers; ++w)
    spawn("worker-" + std::to_string(w), "idrig-worker",
          {"--config", dir + "/worker.json", "--id", "worker-" + std::to_string(w)});
  struct Cleanup {
    std::vector<ChildProcess>& children;
    ~Cleanup() {
      for (auto& c : children) StopChild(c);
    }
  } cleanup{children};

  ServiceClient client(url, operator_key);
  const size_t expected = 4 + static_cast<size_t>(workers);
  for (int i = 0; i < 100 && client.services().size() < expected; ++i) {
    client.Spin(100);
    for (const auto& c : children)
      if (!ChildAlive(c)) throw std::runtime_error(c.name + " exited; see " + c.log_path);
  }
  if (client.services().size() < expected)
    throw std::runtime_error("only " + std::to_string(client.services().size()) + " of " +
                             std::to_string(expected) + " services reported status; see " + dir +
                             "/logs");
  std::cout << "[1/4] services up:";
  for (const auto& [id, s] : client.services()) std::cout << " " << id << "(pid " << s.pid << ")";
  std::cout << "\n";

  struct Experiment {
    std::string label, spec;
    double fs, duration;
    int64_t id = 0;
  };
  std::vector<Experiment> experiments = {
      {"step", "step:amp=1,at=1", 10.0, 30.0},
      {"multisine", "multisine:f0=0.05,lines=1;3;9,amp=1", 20.0, 200.0},
      {"diagnose", "diagnose:T=100,f1=0.5,amp=1,seed=1", 10.0, 200.0},
  };
  std::cout << "[2/4] experiments on rig " << rig << " (simulated time x" << speed << "):\n";
  for (auto& e : experiments) {
    e.id = NewId();
    const int64_t request_id = NewId();
    client.AwaitReply(
        request_id, "excite", "idrig-excite of rig " + rig,
        [&] { client.StartExperiment(rig, e.id, e.spec, e.fs, e.duration, speed, 0.0, request_id); },
        10.0, {request_reply_t::STATE_ACCEPTED});
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(e.duration / speed + 20.0);
    int last_percent = -1;
    for (;;) {
      client.Spin(100);
      const auto* ex = client.ExperimentStatus(rig, e.id, "excite");
      const auto* rs = client.ExperimentStatus(rig, e.id, "rig");
      if (ex && ex->state == experiment_status_t::STATE_FAILED)
        throw std::runtime_error("experiment refused: " + ex->message);
      const int64_t total = ex ? ex->samples_total : 0;
      const int64_t done = rs ? rs->samples_done : 0;
      const int percent = total > 0 ? static_cast<int>(100 * done / total) : 0;
      if (percent / 10 != last_percent / 10 ||
          (rs && rs->state != experiment_status_t::STATE_RUNNING)) {
        last_percent = percent;
        std::cout << "  " << std::setw(9) << std::left << e.label << " experiment " << e.id << "  "
                  << std::string(percent / 5, '#') << std::string(20 - percent / 5, '.') << " "
                  << done << "/" << total << " samples\n"
                  << std::flush;
      }
      if (rs && rs->state != experiment_status_t::STATE_RUNNING &&
          rs->state != experiment_status_t::STATE_PENDING) {
        if (rs->state != experiment_status_t::STATE_DONE)
          throw std::runtime_error("experiment ended " +
                                   std::string(ExperimentStateName(rs->state)) + ": " +
                                   rs->message);
        std::cout << "  " << e.label << ": done, " << rs->samples_total << " samples in "
                  << rs->blocks_total << " blocks\n";
        break;
      }
      if (std::chrono::steady_clock::now() > deadline)
        throw std::runtime_error("experiment " + e.label + " did not finish; see " + dir + "/logs");
    }
  }

  const double wb = 2.0 * M_PI * 0.05;
  std::vector<DemoJob> jobs = {
      {NewId(), experiments[0].id, "step", "arx-oe", "{\"order\":3}"},
      {NewId(), experiments[0].id, "step", "arx", "{\"order\":3}"},
      {NewId(), experiments[1].id, "multisine", "arx-oe", "{\"order\":3}"},
      {NewId(), experiments[1].id, "multisine", "finite-frequency",
       nlohmann::json({{"order", 3},
                       {"numerator_degree", 1},
                       {"base_omega", wb},
                       {"multiples", {1, 3, 9}},
                       {"skip_base_periods", 1}})
           .dump()},
      // The user's simulation model of the rig, with a slow pole 20 % off: the gap diagnosis
      // against it, on the diagnose sequence (docs/gap.md).
      {NewId(), experiments[2].id, "diagnose", "gap-diagnose",
       nlohmann::json({{"sim", ModelToJson(DemoSimModel(plant))}}).dump()},
  };
  std::cout << "[3/4] identification jobs (claimed by the workers, stored by the catalogue):\n";
  const auto start = std::chrono::steady_clock::now();
  auto last_send = start - std::chrono::seconds(10);
  std::set<int64_t> reported;
  auto finished = [&](int64_t request_id) {
    const request_reply_t* r = client.Reply(request_id, "catalog");
    return r && (r->state == request_reply_t::STATE_DONE || r->state == request_reply_t::STATE_FAILED ||
                 r->state == request_reply_t::STATE_REFUSED);
  };
  while (reported.size() < jobs.size()) {
    if (std::chrono::steady_clock::now() - last_send > std::chrono::seconds(1)) {
      // Idempotent by request id: re-sent until the catalogue says the job has ended (its
      // answer to a repeated request is the job's state).
      for (const auto& j : jobs)
        if (!finished(j.request_id))
          client.RequestIdentify(rig, j.request_id, j.experiment_id, j.method, j.options);
      last_send = std::chrono::steady_clock::now();
    }
    client.Spin(100);
    for (const auto& j : jobs) {
      if (!finished(j.request_id) || reported.count(j.request_id)) continue;
      const request_reply_t& r = *client.Reply(j.request_id, "catalog");
      reported.insert(j.request_id);
      const double t =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::cout << "  " << std::setw(9) << std::left << j.label << " " << std::setw(17) << j.method
                << (r.state == request_reply_t::STATE_DONE
                        ? "stored as model " + std::to_string(r.model_id) + " (" + r.message + ")"
                        : std::string("FAILED: ") + r.message)
                << " after " << Number(t, 3) << " s\n";
    }
    if (std::chrono::steady_clock::now() - start > std::chrono::seconds(90))
      throw std::runtime_error("identification did not finish; see " + dir + "/logs");
  }
  for (auto& c : children) StopChild(c);

  std::cout << "[4/4] the catalogue " << dir << "/catalog.db:\n\n";
  Catalog catalog(dir + "/catalog.db", true);
  for (const auto& j : jobs) {
    auto m = catalog.ModelForRequest(j.request_id);
    if (!m) {
      auto job = catalog.Job(j.request_id);
      std::cout << j.label << " / " << j.method << ": failed: " << (job ? job->message : "?")
                << "\n\n";
      continue;
    }
    std::cout << j.label << " / " << j.method << ": ";
    PrintModel(catalog, *m, false);
    std::cout << "\n";
  }
  const std::string self = CommandPathFromHere();  // the running binary, as typed from here
  std::cout
      << "true plant: W = (0.5 s + 1) / (s^3 + 2.5 s^2 + 4 s + 1.5), poles -0.5, -1+-1.414j\n\n";
  for (const auto& d : catalog.Diagnoses(rig, 1)) {
    std::cout << "gap diagnosis " << d.report_id << " of the sim model W = (0.5 s + 1) / (s^3 + "
              << "2.5 s^2 + 4 s + 1.2) against experiment " << d.experiment_id << ":\n";
    std::istringstream text(GapReportText(nlohmann::json::parse(d.report_json)));
    std::string line;
    for (int i = 0; i < 4 && std::getline(text, line); ++i) std::cout << "  " << line << "\n";
    std::cout << "  (whole report and plots: " << self << " gap report " << d.report_id << " --db "
              << dir << "/catalog.db --plots " << dir << "/gap)\n\n";
  }
  std::cout << "all models of rig " << rig << " (every demo run adds to the history):\n";
  PrintModelTable(catalog, catalog.Models(rig));
  std::cout << "\n";
  PrintHistory(catalog, rig, "wn_1", "");
  std::cout << "\nnext: " << self << " models list --db " << dir << "/catalog.db\n"
            << "      " << self << " models history --db " << dir << "/catalog.db --rig " << rig
            << " --param wn_2 --svg " << dir << "/wn_2.svg\n"
            << "      " << self << " experiment list --db " << dir << "/catalog.db --experiments "
            << dir << "/experiments.db\n"
            << "      sqlite3 " << dir
            << "/catalog.db 'SELECT model_id, method, data_hash FROM models'\n"
            << "\nthe dashboard (models, Bode, history, gap plots; read-only, on this machine only):\n"
            << "      " << self << " serve --db " << dir << "/catalog.db --experiments " << dir
            << "/experiments.db   # then open http://127.0.0.1:8765/\n";
}

}  // namespace

void SetCommandLine(int argc, char** argv) { g_args.assign(argv, argv + argc); }

void RegisterDemoCommand(CLI::App& app) {
  // ---- demo
  {
    struct Args {
      std::string dir = "idrig-demo";
      int port = 7694, workers = 2;
      double speed = 50.0;
      bool no_netns = false;
    };
    auto args = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "demo",
        "start every service on a private LCM URL, run a step and a multisine experiment "
        "on the simulated rig, identify with two methods each, and print the stored models "
        "with their history");
    cmd->add_option("--dir", args->dir,
                    "directory for the catalogue, experiment store, configs, logs");
    cmd->add_option("--port", args->port, "UDP port of the private udpm URL (ttl=0)")
        ->check(CLI::Range(1024, 65535));
    cmd->add_option("--speed", args->speed, "simulated time / wall time")
        ->check(CLI::Range(1.0, 1000.0));
    cmd->add_option("--workers", args->workers, "number of idrig-worker processes")
        ->check(CLI::Range(1, 8));
    cmd->add_flag("--no-netns", args->no_netns,
                  "do not re-run inside `unshare -n` when multicast is missing");
    cmd->callback(
        [args] { RunDemo(args->dir, args->port, args->speed, args->workers, !args->no_netns); });
  }
}

}  // namespace idrig
