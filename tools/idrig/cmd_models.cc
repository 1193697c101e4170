// The distributed service from the command line: `idrig demo`, `idrig experiment
// start|status|stop`, `idrig models request|list|show|history`, `idrig status`, `idrig spy`.
// Channels, messages and the catalogue schema: docs/services.md.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>

#include "core/catalog/catalog.h"
#include "core/io/gap_json.h"
#include "core/io/model_json.h"
#include "core/transport/channels.h"
#include "core/transport/signing.h"
#include "tools/idrig/commands.h"
#include "tools/idrig/service_client.h"

#ifndef IDRIG_TYPES_JAR
#define IDRIG_TYPES_JAR ""
#endif

namespace idrig {
namespace {

std::vector<std::string> g_args;  // the command line, for re-executing inside a namespace

std::string TimeText(int64_t utime) {
  const std::time_t t = static_cast<std::time_t>(utime / 1000000);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%d %H:%M:%S", std::gmtime(&t));
  return buffer;
}

std::string Polynomial(const nlohmann::json& coefficients, const char* var) {
  std::ostringstream s;
  s << std::setprecision(4);
  const int degree = static_cast<int>(coefficients.size()) - 1;
  bool first = true;
  for (int i = 0; i <= degree; ++i) {
    const double c = coefficients[i].get<double>();
    const int power = degree - i;
    if (std::abs(c) < 1e-12 && degree > 0) continue;
    s << (first ? (c < 0 ? "-" : "") : (c < 0 ? " - " : " + ")) << std::abs(c);
    if (power >= 1) s << " " << var;
    if (power >= 2) s << "^" << power;
    first = false;
  }
  return first ? "0" : s.str();
}

std::string ModelText(const std::string& model_json) {
  try {
    const nlohmann::json m = nlohmann::json::parse(model_json);
    const bool discrete = m.value("domain", "") == "discrete";
    const char* var = discrete ? "z" : "s";
    if (m.value("kind", "") == "tf")
      return "(" + Polynomial(m["num"], var) + ") / (" + Polynomial(m["den"], var) + ")" +
             (discrete ? ", Ts = " + std::to_string(m.value("Ts", 0.0)) + " s" : "");
    return "state space, order " + std::to_string(m["A"].size());
  } catch (...) {
    return "(unreadable model)";
  }
}

std::string Number(double value, int precision = 4) {
  if (!std::isfinite(value)) return "-";
  std::ostringstream s;
  s << std::setprecision(precision) << value;
  return s.str();
}

std::map<std::string, double> MetricMap(Catalog& catalog, int64_t model_id) {
  std::map<std::string, double> out;
  for (const auto& m : catalog.Metrics(model_id)) out[m.name] = m.value;
  return out;
}

std::string PolesText(const std::map<std::string, double>& metrics) {
  std::ostringstream s;
  s << std::setprecision(4);
  for (int k = 1; metrics.count("pole_" + std::to_string(k) + "_re"); ++k) {
    const double re = metrics.at("pole_" + std::to_string(k) + "_re");
    const double im = metrics.at("pole_" + std::to_string(k) + "_im");
    s << (k > 1 ? ", " : "") << re;
    if (std::abs(im) > 1e-9) s << (im < 0 ? "-" : "+") << std::abs(im) << "j";
  }
  return s.str();
}

void PrintModelTable(Catalog& catalog, const std::vector<ModelRecord>& models) {
  std::cout << std::left << std::setw(6) << "id" << std::setw(10) << "rig" << std::setw(18)
            << "experiment" << std::setw(18) << "method" << std::setw(9) << "fit %" << std::setw(21)
            << "stored (UTC)"
            << "poles [rad/s]\n";
  for (const auto& m : models) {
    const auto metrics = MetricMap(catalog, m.model_id);
    const double fit =
        metrics.count("record_fit_percent") ? metrics.at("record_fit_percent") : m.fit_percent;
    std::cout << std::left << std::setw(6) << m.model_id << std::setw(10) << m.rig_id
              << std::setw(18) << m.experiment_id << std::setw(18) << m.method << std::setw(9)
              << Number(fit, 4) << std::setw(21) << TimeText(m.created_utime) << PolesText(metrics)
              << "\n";
  }
}

void PrintModel(Catalog& catalog, const ModelRecord& m, bool json) {
  if (json) {
    nlohmann::json j = {{"model_id", m.model_id},
                        {"request_id", m.request_id},
                        {"rig_id", m.rig_id},
                        {"experiment_id", m.experiment_id},
                        {"signal_spec", m.signal_spec},
                        {"method", m.method},
                        {"options", nlohmann::json::parse(m.options_json, nullptr, false)},
                        {"data_hash", m.data_hash},
                        {"n_samples", m.n_samples},
                        {"sample_time_s", m.sample_time_s},
                        {"software_version", m.software_version},
                        {"worker_id", m.worker_id},
                        {"created_utime", m.created_utime},
                        {"compute_s", m.compute_s},
                        {"model", nlohmann::json::parse(m.model_json)}};
    nlohmann::json metrics = nlohmann::json::object();
    for (const auto& x : catalog.Metrics(m.model_id)) metrics[x.name] = x.value;
    j["metrics"] = metrics;
    std::cout << j.dump(2) << "\n";
    return;
  }
  const auto metrics = MetricMap(catalog, m.model_id);
  std::cout << "model " << m.model_id << " (request " << m.request_id << ")\n"
            << "  W = " << ModelText(m.model_json) << "\n"
            << "  poles: " << PolesText(metrics) << " rad/s\n"
            << "  fit on the whole record "
            << (metrics.count("record_fit_percent") ? Number(metrics.at("record_fit_percent"))
                                                    : "-")
            << " % (the method's own: " << Number(m.fit_percent) << " %), DC gain "
            << (metrics.count("dc_gain") ? Number(metrics.at("dc_gain")) : "-") << ", status "
            << m.status << "\n"
            << "  lineage: rig " << m.rig_id << ", experiment " << m.experiment_id << " ("
            << (m.signal_spec.empty() ? "signal unknown" : m.signal_spec) << "), " << m.n_samples
            << " samples at Ts " << m.sample_time_s << " s, data sha256 "
            << m.data_hash.substr(0, 16) << "…\n"
            << "           method " << m.method << " " << m.options_json << ", idrig "
            << m.software_version << ", worker " << m.worker_id << ", " << Number(m.compute_s, 3)
            << " s, stored " << TimeText(m.created_utime) << " UTC\n";
}

// A parameter over time, one line per model, with a bar: the history plot of a terminal.
void PrintHistory(Catalog& catalog, const std::string& rig, const std::string& metric,
                  const std::string& method) {
  const auto history = catalog.History(rig, metric, method);
  if (history.empty()) {
    std::cout << "no model of rig '" << rig << "' has metric '" << metric
              << "' (metrics: fit_percent, dc_gain, order, pole_k_re, pole_k_im, wn_k, zeta_k)\n";
    return;
  }
  double lo = history[0].second, hi = lo;
  for (const auto& h : history) {
    lo = std::min(lo, h.second);
    hi = std::max(hi, h.second);
  }
  const double span = hi > lo ? hi - lo : std::max(1e-12, std::abs(hi));
  const double base = hi > lo ? lo - 0.1 * span : lo - span;
  std::cout << metric << " of rig " << rig << (method.empty() ? "" : " (" + method + ")")
            << " over time:\n";
  for (const auto& [m, value] : history) {
    const int width = static_cast<int>(std::lround(40.0 * (value - base) / (hi - base)));
    std::cout << "  " << TimeText(m.created_utime) << "  model " << std::setw(4) << std::left
              << m.model_id << std::setw(16) << m.method << std::right << std::setw(11)
              << Number(value, 5) << "  " << std::string(std::max(1, width), '#') << "\n";
  }
}

// The history as an SVG line plot (value against storage time), for a browser or a report.
void WriteHistorySvg(Catalog& catalog, const std::string& rig, const std::string& metric,
                     const std::string& method, const std::string& path) {
  const auto history = catalog.History(rig, metric, method);
  if (history.empty())
    throw std::invalid_argument("no model of rig '" + rig + "' has metric '" + metric + "'");
  double t0 = history.front().first.created_utime * 1e-6,
         t1 = history.back().first.created_utime * 1e-6;
  double lo = history[0].second, hi = lo;
  for (const auto& h : history) {
    lo = std::min(lo, h.second);
    hi = std::max(hi, h.second);
  }
  if (hi - lo < 1e-12) {
    lo -= 0.5;
    hi += 0.5;
  }
  if (t1 - t0 < 1e-6) t1 = t0 + 1.0;
  const double w = 640, h = 320, m = 50;
  auto x = [&](double t) { return m + (w - 2 * m) * (t - t0) / (t1 - t0); };
  auto y = [&](double v) { return h - m - (h - 2 * m) * (v - lo) / (hi - lo); };
  std::ofstream out(path);
  if (!out) throw std::invalid_argument("cannot write '" + path + "'");
  out << "<svg xmlns='http://www.w3.org/2000/svg' width='" << w << "' height='" << h << "'>\n"
      << "<rect width='100%' height='100%' fill='white'/>\n"
      << "<text x='" << m << "' y='20' font-family='sans-serif' font-size='14'>" << metric
      << " of rig " << rig << (method.empty() ? "" : " (" + method + ")") << ", "
      << TimeText(history.front().first.created_utime) << " .. "
      << TimeText(history.back().first.created_utime) << " UTC</text>\n"
      << "<text x='5' y='" << y(hi) + 4 << "' font-size='11'>" << Number(hi) << "</text>\n"
      << "<text x='5' y='" << y(lo) + 4 << "' font-size='11'>" << Number(lo) << "</text>\n"
      << "<polyline fill='none' stroke='steelblue' stroke-width='1.5' points='";
  for (const auto& [model, value] : history)
    out << x(model.created_utime * 1e-6) << "," << y(value) << " ";
  out << "'/>\n";
  for (const auto& [model, value] : history)
    out << "<circle cx='" << x(model.created_utime * 1e-6) << "' cy='" << y(value)
        << "' r='3' fill='steelblue'>"
        << "<title>model " << model.model_id << " " << model.method << ": " << Number(value, 6)
        << "</title></circle>\n";
  out << "</svg>\n";
}

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
  const std::string key_file = dir + "/hmac.key";
  if (access(key_file.c_str(), R_OK) != 0) WriteNewKeyFile(key_file);
  // The simulated rig: seed 001's plant W(p) = (0.5p + 1)/(p^3 + 2.5p^2 + 4p + 1.5) + noise.
  TransferFunction plant;
  plant.num = Eigen::Vector2d(0.5, 1.0);
  plant.den = Eigen::Vector4d(1.0, 2.5, 4.0, 1.5);
  WriteModelFile(plant, dir + "/plant.json");
  WriteJson(dir + "/catalog.json",
            {{"db_path", dir + "/catalog.db"}, {"lease_s", 3.0}, {"offer_period_s", 0.5}});
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
                                    {"key_id", 1}});
  WriteJson(dir + "/excite.json", {{"rig_id", rig},
                                   {"key_file", key_file},
                                   {"key_id", 1},
                                   {"block_samples", 20},
                                   {"max_abs", 5.0},
                                   {"max_rate", 2000.0}});
  WriteJson(dir + "/worker.json", {{"renew_s", 0.5}, {"replay_retry_s", 0.3}});

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

  ServiceClient client(url);
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
    const int64_t request_id =
        client.StartExperiment(rig, e.id, e.spec, e.fs, e.duration, speed, 0.0);
    auto last_request = std::chrono::steady_clock::now();
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(e.duration / speed + 20.0);
    int last_percent = -1;
    for (;;) {
      client.Spin(100);
      const auto* ex = client.ExperimentStatus(rig, e.id, "excite");
      const auto* rs = client.ExperimentStatus(rig, e.id, "rig");
      if (ex && ex->state == experiment_status_t::STATE_FAILED)
        throw std::runtime_error("experiment refused: " + ex->message);
      if (!ex && std::chrono::steady_clock::now() - last_request > std::chrono::seconds(1)) {
        // Not heard of yet (request lost?): the same request again (idempotent by request id).
        client.StartExperiment(rig, e.id, e.spec, e.fs, e.duration, speed, 0.0, request_id);
        last_request = std::chrono::steady_clock::now();
      }
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
  while (reported.size() < jobs.size()) {
    if (std::chrono::steady_clock::now() - last_send > std::chrono::seconds(2)) {
      for (const auto& j : jobs)  // idempotent by request id: re-sent until acknowledged
        if (!client.acks().count(j.request_id))
          client.RequestIdentify(rig, j.request_id, j.experiment_id, j.method, j.options);
      last_send = std::chrono::steady_clock::now();
    }
    client.Spin(100);
    for (const auto& j : jobs) {
      auto ack = client.acks().find(j.request_id);
      if (ack == client.acks().end() || reported.count(j.request_id)) continue;
      reported.insert(j.request_id);
      const double t =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::cout << "  " << std::setw(9) << std::left << j.label << " " << std::setw(17) << j.method
                << (ack->second.model_id > 0
                        ? "stored as model " + std::to_string(ack->second.model_id)
                        : std::string("FAILED (see idrig models list)"))
                << " by " << ack->second.worker_id << " after " << Number(t, 3) << " s\n";
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
  std::cout
      << "true plant: W = (0.5 s + 1) / (s^3 + 2.5 s^2 + 4 s + 1.5), poles -0.5, -1+-1.414j\n\n";
  for (const auto& d : catalog.Diagnoses(rig, 1)) {
    std::cout << "gap diagnosis " << d.report_id << " of the sim model W = (0.5 s + 1) / (s^3 + "
              << "2.5 s^2 + 4 s + 1.2) against experiment " << d.experiment_id << ":\n";
    std::istringstream text(GapReportText(nlohmann::json::parse(d.report_json)));
    std::string line;
    for (int i = 0; i < 4 && std::getline(text, line); ++i) std::cout << "  " << line << "\n";
    std::cout << "  (whole report and plots: build/bin/idrig gap report " << d.report_id << " --db "
              << dir << "/catalog.db --plots " << dir << "/gap)\n\n";
  }
  std::cout << "all models of rig " << rig << " (every demo run adds to the history):\n";
  PrintModelTable(catalog, catalog.Models(rig));
  std::cout << "\n";
  PrintHistory(catalog, rig, "wn_1", "");
  std::cout << "\nnext: build/bin/idrig models list --db " << dir << "/catalog.db\n"
            << "      build/bin/idrig models history --db " << dir << "/catalog.db --rig " << rig
            << " --param wn_2\n"
            << "      sqlite3 " << dir
            << "/catalog.db 'SELECT model_id, method, data_hash FROM models'\n";
}

}  // namespace

void SetCommandLine(int argc, char** argv) { g_args.assign(argv, argv + argc); }

void RegisterServiceCommands(CLI::App& app) {
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
  // ---- experiment start|status|stop
  {
    auto* group = app.add_subcommand("experiment", "start, watch or stop experiments on a rig");
    group->require_subcommand(1);
    struct Args {
      std::string url = DefaultLcmUrl(), rig = "sim1", signal;
      double fs = 10, duration = 10, speed = 1, max_abs = 0, seconds = 1.5;
      int64_t experiment = 0;
      bool wait = false;
    };
    auto args = std::make_shared<Args>();
    auto* start =
        group->add_subcommand("start", "publish an experiment request (prints the experiment id)");
    auto* status =
        group->add_subcommand("status", "listen for experiment status and print the latest");
    auto* stop =
        group->add_subcommand("stop", "stop a running experiment (the rig goes to its safe input)");
    for (auto* c : {start, status, stop}) {
      c->add_option("--url", args->url, "LCM URL (default $LCM_DEFAULT_URL or udpm ttl=0)");
      c->add_option("--rig", args->rig, "rig id");
    }
    start->add_option("--signal", args->signal, "excitation SPEC (docs/excitation.md)")->required();
    start->add_option("--fs", args->fs, "sample rate [Hz]")->check(CLI::PositiveNumber);
    start->add_option("--duration", args->duration, "experiment length [s]")
        ->check(CLI::PositiveNumber);
    start->add_option("--speed", args->speed, "experiment time / wall time (simulated rigs)")
        ->check(CLI::PositiveNumber);
    start->add_option("--max-abs", args->max_abs, "lower |u| limit for this experiment")
        ->check(CLI::NonNegativeNumber);
    start->add_option("--experiment", args->experiment, "experiment id (default: from the clock)");
    start->add_flag("--wait", args->wait, "wait until the rig reports the end");
    status->add_option("--experiment", args->experiment, "only this experiment");
    status->add_option("--seconds", args->seconds, "how long to listen");
    stop->add_option("--experiment", args->experiment, "experiment id")->required();
    start->callback([args] {
      ValidateRigId(args->rig);
      ServiceClient client(args->url);
      const int64_t id = args->experiment > 0 ? args->experiment : NewId();
      const int64_t request_id = client.StartExperiment(args->rig, id, args->signal, args->fs,
                                                        args->duration, args->speed, args->max_abs);
      std::cout << id << "\n" << std::flush;
      if (!args->wait) return;
      for (int i = 0; i < 100000; ++i) {
        client.Spin(200);
        const auto* ex = client.ExperimentStatus(args->rig, id, "excite");
        if (!ex && i % 5 == 4)  // not heard of yet: the same request again (idempotent)
          client.StartExperiment(args->rig, id, args->signal, args->fs, args->duration, args->speed,
                                 args->max_abs, request_id);
        const auto* rs = client.ExperimentStatus(args->rig, id, "rig");
        if (ex && ex->state == experiment_status_t::STATE_FAILED)
          throw std::invalid_argument("experiment refused: " + ex->message);
        if (rs && rs->state >= experiment_status_t::STATE_DONE) {
          std::cerr << "experiment " << id << " " << ExperimentStateName(rs->state) << ": "
                    << rs->samples_total << " samples, " << rs->blocks_total << " blocks "
                    << rs->message << "\n";
          if (rs->state != experiment_status_t::STATE_DONE)
            throw std::runtime_error("experiment did not complete");
          return;
        }
        if (i == 0 && !ex) std::cerr << "waiting for idrig-excite on rig " << args->rig << "…\n";
      }
    });
    status->callback([args] {
      ServiceClient client(args->url);
      client.Spin(static_cast<int>(args->seconds * 1000));
      int shown = 0;
      for (const auto& [key, s] : client.experiments()) {
        if (s.rig_id != args->rig || (args->experiment && s.experiment_id != args->experiment))
          continue;
        std::cout << s.rig_id << " experiment " << s.experiment_id << " [" << s.source << "] "
                  << ExperimentStateName(s.state) << " " << s.samples_done << "/" << s.samples_total
                  << " samples"
                  << (s.source == "rig" ? ", " + std::to_string(s.blocks_total) + " blocks" : "")
                  << (s.signal_spec.empty() ? "" : ", " + s.signal_spec)
                  << (s.message.empty() ? "" : " — " + s.message) << "\n";
        ++shown;
      }
      if (!shown)
        std::cout << "no experiment status heard on rig " << args->rig << " within "
                  << args->seconds << " s\n";
    });
    stop->callback([args] {
      ServiceClient client(args->url);
      client.StopExperiment(args->rig, args->experiment);
      client.Spin(200);
    });
  }
  // ---- models request|list|show|history
  {
    auto* group = app.add_subcommand("models", "request identification; query the model catalogue");
    group->require_subcommand(1);
    struct Args {
      std::string db = "idrig-demo/catalog.db", rig, method, param = "wn_1", url = DefaultLcmUrl(),
                  options = "{}";
      int64_t id = 0, experiment = 0;
      bool json = false, wait = false;
    };
    auto args = std::make_shared<Args>();
    auto* request =
        group->add_subcommand("request", "ask the workers to identify a model from an experiment");
    auto* list = group->add_subcommand("list", "models in the catalogue, oldest first");
    auto* show = group->add_subcommand("show", "one model with its lineage and metrics");
    auto* history = group->add_subcommand(
        "history", "a parameter (pole, natural frequency, ...) over time for a rig");
    auto* export_cmd = group->add_subcommand(
        "export",
        "write a model as idrig.model/1 JSON (with its lineage under \"identification\")");
    auto* compare =
        group->add_subcommand("compare", "two models side by side: lineage and metrics");
    auto other = std::make_shared<int64_t>(0);
    auto out = std::make_shared<std::string>();
    export_cmd->add_option("id", args->id, "model id")->required();
    export_cmd->add_option("--out", *out, "file to write (default stdout)");
    compare->add_option("id", args->id, "first model id")->required();
    compare->add_option("other", *other, "second model id")->required();
    for (auto* c : {list, show, history, export_cmd, compare})
      c->add_option("--db", args->db, "catalogue file (idrig-catalog's db_path)");
    request->add_option("--url", args->url, "LCM URL");
    request->add_option("--rig", args->rig, "rig id")->required();
    request->add_option("--experiment", args->experiment, "experiment id")->required();
    request->add_option("--method", args->method, "method name (idrig identify --help)")
        ->required();
    request->add_option("--options", args->options, "method options as a JSON object");
    request->add_flag("--wait", args->wait, "wait for the catalogue's acknowledgement");
    list->add_option("--rig", args->rig, "only this rig");
    list->add_option("--method", args->method, "only this method");
    show->add_option("id", args->id, "model id")->required();
    show->add_flag("--json", args->json, "print as JSON");
    history->add_option("--rig", args->rig, "rig id")->required();
    history->add_option("--param", args->param,
                        "metric: wn_k, zeta_k, pole_k_re, pole_k_im, dc_gain, fit_percent, order");
    history->add_option("--method", args->method, "only this method");
    auto svg = std::make_shared<std::string>();
    history->add_option("--svg", *svg, "also write the plot as an SVG file");
    request->callback([args] {
      ValidateRigId(args->rig);
      if (nlohmann::json::parse(args->options, nullptr, false).is_discarded())
        throw std::invalid_argument("--options must be a JSON object, got '" + args->options + "'");
      ServiceClient client(args->url);
      const int64_t id = NewId();
      client.RequestIdentify(args->rig, id, args->experiment, args->method, args->options);
      std::cout << id << "\n" << std::flush;
      for (int i = 0; args->wait && i < 600; ++i) {
        client.Spin(100);
        auto ack = client.acks().find(id);
        if (ack != client.acks().end()) {
          std::cerr << (ack->second.model_id
                            ? "stored as model " + std::to_string(ack->second.model_id)
                            : std::string("failed (see the catalogue's jobs table)"))
                    << "\n";
          return;
        }
        if (i % 20 == 19)
          client.RequestIdentify(args->rig, id, args->experiment, args->method, args->options);
      }
      if (args->wait) throw std::runtime_error("no acknowledgement within 60 s");
    });
    list->callback([args] {
      Catalog catalog(args->db, true);
      PrintModelTable(catalog, catalog.Models(args->rig, args->method));
    });
    show->callback([args] {
      Catalog catalog(args->db, true);
      auto m = catalog.Model(args->id);
      if (!m)
        throw std::invalid_argument("no model " + std::to_string(args->id) + " in " + args->db);
      PrintModel(catalog, *m, args->json);
    });
    export_cmd->callback([args, out] {
      Catalog catalog(args->db, true);
      auto m = catalog.Model(args->id);
      if (!m)
        throw std::invalid_argument("no model " + std::to_string(args->id) + " in " + args->db);
      nlohmann::json j = nlohmann::json::parse(m->model_json);
      j["identification"] = {{"model_id", m->model_id},
                             {"rig_id", m->rig_id},
                             {"experiment_id", m->experiment_id},
                             {"signal_spec", m->signal_spec},
                             {"method", m->method},
                             {"options", nlohmann::json::parse(m->options_json, nullptr, false)},
                             {"data_hash", m->data_hash},
                             {"software_version", m->software_version},
                             {"created_utime", m->created_utime},
                             {"fit_percent", m->fit_percent}};
      if (out->empty()) {
        std::cout << j.dump(2) << "\n";
      } else {
        std::ofstream file(*out);
        if (!file) throw std::invalid_argument("cannot write '" + *out + "'");
        file << j.dump(2) << "\n";
      }
    });
    compare->callback([args, other] {
      Catalog catalog(args->db, true);
      auto a = catalog.Model(args->id), b = catalog.Model(*other);
      if (!a || !b)
        throw std::invalid_argument("no model " + std::to_string(!a ? args->id : *other) + " in " +
                                    args->db);
      const auto ma = MetricMap(catalog, a->model_id), mb = MetricMap(catalog, b->model_id);
      std::cout << std::left << std::setw(16) << "" << std::setw(28)
                << ("model " + std::to_string(a->model_id))
                << ("model " + std::to_string(b->model_id)) << "\n";
      auto row = [](const std::string& name, const std::string& x, const std::string& y) {
        std::cout << std::left << std::setw(16) << name << std::setw(28) << x << y << "\n";
      };
      row("method", a->method, b->method);
      row("experiment", std::to_string(a->experiment_id), std::to_string(b->experiment_id));
      row("signal", a->signal_spec.substr(0, 26), b->signal_spec.substr(0, 26));
      row("samples", std::to_string(a->n_samples), std::to_string(b->n_samples));
      row("data sha256", a->data_hash.substr(0, 16), b->data_hash.substr(0, 16));
      row("stored (UTC)", TimeText(a->created_utime), TimeText(b->created_utime));
      std::set<std::string> names;
      for (const auto& [k, v] : ma) names.insert(k);
      for (const auto& [k, v] : mb) names.insert(k);
      for (const auto& n : names)
        row(n, ma.count(n) ? Number(ma.at(n), 6) : "-", mb.count(n) ? Number(mb.at(n), 6) : "-");
    });
    history->callback([args, svg] {
      Catalog catalog(args->db, true);
      PrintHistory(catalog, args->rig, args->param, args->method);
      if (!svg->empty()) WriteHistorySvg(catalog, args->rig, args->param, args->method, *svg);
    });
  }
  // ---- status
  {
    struct Args {
      std::string url = DefaultLcmUrl();
      double seconds = 1.5;
    };
    auto args = std::make_shared<Args>();
    auto* cmd = app.add_subcommand("status", "list the running services (their periodic status)");
    cmd->add_option("--url", args->url, "LCM URL");
    cmd->add_option("--seconds", args->seconds, "how long to listen");
    cmd->callback([args] {
      ServiceClient client(args->url);
      client.Spin(static_cast<int>(args->seconds * 1000));
      for (const auto& [id, s] : client.services())
        std::cout << std::left << std::setw(28) << id << std::setw(8) << s.state << " host "
                  << s.host << " pid " << s.pid << " up " << Number(s.uptime_s, 3) << " s  recv "
                  << s.received << " sent " << s.published << " dropped " << s.dropped << " bad "
                  << (s.undecodable + s.foreign + s.oversized) << " refused "
                  << (s.unsigned_count + s.forged + s.replayed + s.over_limit) << "\n    "
                  << s.details_json << "\n";
      if (client.services().empty())
        std::cout << "no service status heard within " << args->seconds << " s\n";
    });
  }
  // ---- spy
  {
    auto url = std::make_shared<std::string>(DefaultLcmUrl());
    auto* cmd = app.add_subcommand(
        "spy",
        "lcm-spy with idrig's message types (java directly: Debian's wrapper fails on Java 17)");
    cmd->add_option("--url", *url, "LCM URL");
    cmd->callback([url] {
      std::string jar = IDRIG_TYPES_JAR;
      if (jar.empty() || access(jar.c_str(), R_OK) != 0)
        jar = ExecutableDir() + "/../share/java/idrig_lcmtypes.jar";
      if (access(jar.c_str(), R_OK) != 0)
        throw std::runtime_error("idrig's types jar is not built (needs a JDK): " + jar);
      const std::string cp = "/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar:" + jar;
      const std::string url_arg = "--lcm-url=" + *url;
      std::vector<std::string> a = {"java", "-cp", cp, "lcm.spy.Spy", url_arg};
      std::vector<char*> argv;
      for (auto& s : a) argv.push_back(s.data());
      argv.push_back(nullptr);
      execvp("java", argv.data());
      throw std::runtime_error("cannot run java (install default-jre-headless)");
    });
  }
}

}  // namespace idrig
