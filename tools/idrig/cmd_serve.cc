// idrig serve: the rig engineer's desk, a local web app over the catalogue, the experiment store
// and (with --url) the live LCM bus. A JSON API under /api/ and the static front end (built by
// deploy/build-web.sh) at /. Read-only: only GET is served; every other method answers 405.
// Binds 127.0.0.1 unless --bind says otherwise. API and pages: docs/dashboard.md.
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include "core/catalog/catalog.h"
#include "core/io/gap_json.h"
#include "core/io/gap_svg.h"
#include "core/io/model_json.h"
#include "tools/idrig/catalog_views.h"
#include "tools/idrig/commands.h"
#include "tools/idrig/service_client.h"
// After Eigen: httplib includes <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace idrig {
namespace {

using json = nlohmann::json;

struct ServeOptions {
  std::string db = "idrig-demo/catalog.db", experiments = "idrig-demo/experiments.db", url,
              bind = "127.0.0.1", web_dir;
  int port = 8765;
};

bool IsFile(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// The live bus: a thread owns the ServiceClient and copies what it heard for the handlers.
class LiveBus {
 public:
  explicit LiveBus(const std::string& url) : url_(url) {
    thread_ = std::thread([this] { Run(); });
  }
  ~LiveBus() {
    stop_ = true;
    thread_.join();
  }
  json Snapshot() {
    std::lock_guard<std::mutex> lock(mutex_);
    return snapshot_;
  }

 private:
  void Run() {
    try {
      ServiceClient client(url_);
      while (!stop_) {
        client.Spin(250);
        json services = json::array(), experiments = json::array();
        for (const auto& [id, s] : client.services())
          services.push_back({{"instance_id", id}, {"service", s.service}, {"state", s.state},
                              {"host", s.host}, {"pid", s.pid}, {"uptime_s", s.uptime_s},
                              {"received", s.received}, {"published", s.published},
                              {"dropped", s.dropped}, {"age_s", (NowMicros() - s.utime) * 1e-6},
                              {"refused", s.unsigned_count + s.forged + s.replayed + s.over_limit},
                              {"details", json::parse(s.details_json, nullptr, false)}});
        for (const auto& [key, e] : client.experiments())
          experiments.push_back({{"rig_id", e.rig_id}, {"experiment_id", e.experiment_id},
                                 {"source", e.source}, {"state", ExperimentStateName(e.state)},
                                 {"samples_done", e.samples_done}, {"samples_total", e.samples_total},
                                 {"signal_spec", e.signal_spec}, {"message", e.message},
                                 {"age_s", (NowMicros() - e.utime) * 1e-6}});
        std::lock_guard<std::mutex> lock(mutex_);
        snapshot_ = {{"url", url_}, {"listening", true}, {"services", services},
                     {"experiments", experiments}};
      }
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      snapshot_ = {{"url", url_}, {"listening", false}, {"error", e.what()},
                   {"services", json::array()}, {"experiments", json::array()}};
    }
  }
  std::string url_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  json snapshot_ = {{"url", url_}, {"listening", true}, {"services", json::array()},
                    {"experiments", json::array()}};
  std::thread thread_;
};

httplib::Server* g_server = nullptr;
void StopServer(int) {
  if (g_server) g_server->stop();
}

class Desk {
 public:
  explicit Desk(const ServeOptions& o) : options_(o) {
    if (!o.url.empty()) bus_ = std::make_unique<LiveBus>(o.url);
  }

  std::unique_ptr<Catalog> OpenCatalog() const {
    if (!IsFile(options_.db))
      throw std::invalid_argument("catalogue '" + options_.db + "' does not exist (--db)");
    return std::make_unique<Catalog>(options_.db, true);
  }

  json Summary() const {
    json j = {{"db", options_.db}, {"experiments_store", options_.experiments},
              {"url", options_.url}, {"version", IDRIG_VERSION}, {"read_only", true}};
    j["db_present"] = IsFile(options_.db);
    j["store_present"] = IsFile(options_.experiments);
    if (j["db_present"]) {
      auto c = OpenCatalog();
      j["models"] = c->CountModels();
      j["experiments"] = c->Experiments().size();
      j["diagnoses"] = c->Diagnoses().size();
    }
    return j;
  }

  json Rigs() const {
    std::map<std::string, json> rigs;
    if (IsFile(options_.db)) {
      auto c = OpenCatalog();
      for (const auto& e : c->Experiments()) {
        json& r = rigs[e.rig_id];
        r["rig_id"] = e.rig_id;
        r["experiments"] = r.value("experiments", 0) + 1;
        r["last_experiment_utc"] = UtcTimeText(std::max(e.start_utime, e.end_utime));
      }
      for (const auto& m : c->Models()) {
        json& r = rigs[m.rig_id];
        r["rig_id"] = m.rig_id;
        r["models"] = r.value("models", 0) + 1;
        r["last_model_utc"] = UtcTimeText(m.created_utime);
      }
    }
    json live = bus_ ? bus_->Snapshot() : json{{"url", ""}, {"listening", false}, {"services", json::array()}, {"experiments", json::array()}};
    for (const auto& e : live["experiments"]) rigs[e["rig_id"].get<std::string>()]["rig_id"] = e["rig_id"];
    json list = json::array();
    for (auto& [id, r] : rigs) list.push_back(r);
    return {{"rigs", list}, {"live", live}};
  }

  const ServeOptions& options() const { return options_; }

  DiagnosisRecord RequireDiagnosis(const std::string& id_text) const;

 private:
  ServeOptions options_;
  std::unique_ptr<LiveBus> bus_;
};

int64_t IdFrom(const std::string& text, const char* what) {
  try {
    size_t used = 0;
    const long long v = std::stoll(text, &used);
    if (used == text.size() && v > 0) return v;
  } catch (const std::exception&) {
  }
  throw std::invalid_argument(std::string(what) + " must be a positive integer, got '" + text + "'");
}

std::string Param(const httplib::Request& req, const char* name, const std::string& fallback = "") {
  return req.has_param(name) ? req.get_param_value(name) : fallback;
}

// Runs a handler; errors become JSON {"error": message} (400 bad input, 404 missing, 500 else).
void Reply(httplib::Response& res, const std::function<json()>& f) {
  try {
    res.set_content(f().dump(), "application/json");
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    res.status = (m.rfind("no ", 0) == 0 || m.find("does not exist") != std::string::npos) ? 404 : 400;
    res.set_content(json({{"error", m}}).dump(), "application/json");
  } catch (const std::exception& e) {
    res.status = 500;
    res.set_content(json({{"error", e.what()}}).dump(), "application/json");
  }
}

DiagnosisRecord Desk::RequireDiagnosis(const std::string& id_text) const {
  const int64_t id = IdFrom(id_text, "report id");
  auto d = OpenCatalog()->Diagnosis(id);
  if (!d) throw std::invalid_argument("no diagnosis report " + std::to_string(id) + " in " + options_.db);
  return *d;
}

void Routes(httplib::Server& server, Desk& desk) {
  server.Get("/api/summary", [&](const httplib::Request&, httplib::Response& res) {
    Reply(res, [&] { return desk.Summary(); });
  });
  server.Get("/api/rigs", [&](const httplib::Request&, httplib::Response& res) {
    Reply(res, [&] { return desk.Rigs(); });
  });
  server.Get("/api/experiments", [&](const httplib::Request&, httplib::Response& res) {
    Reply(res, [&] {
      std::unique_ptr<Catalog> c = IsFile(desk.options().db) ? desk.OpenCatalog() : nullptr;
      return ExperimentsJson(c.get(), desk.options().experiments);
    });
  });
  server.Get(R"(/api/experiments/([A-Za-z0-9_-]+)/(\d+)/signals)",
             [&](const httplib::Request& req, httplib::Response& res) {
    Reply(res, [&] {
      std::string spec;
      const IoRecord r = LoadExperimentRecord(desk.options().experiments, req.matches[1],
                                              IdFrom(req.matches[2], "experiment id"), &spec);
      const int max_points = static_cast<int>(IdFrom(Param(req, "max", "3000"), "max"));
      const int stride = std::max(1, (r.NumSamples() + max_points - 1) / max_points);
      json t = json::array(), u = json::array(), y = json::array();
      for (int c = 0; c < r.NumInputs(); ++c) u.push_back(json::array());
      for (int c = 0; c < r.NumOutputs(); ++c) y.push_back(json::array());
      for (int k = 0; k < r.NumSamples(); k += stride) {
        t.push_back(r.t(k));
        for (int c = 0; c < r.NumInputs(); ++c) u[c].push_back(r.u(k, c));
        for (int c = 0; c < r.NumOutputs(); ++c) y[c].push_back(r.y(k, c));
      }
      return json{{"rig_id", std::string(req.matches[1])}, {"experiment_id", IdFrom(req.matches[2], "id")},
                  {"signal_spec", spec}, {"Ts", r.sample_time}, {"samples", r.NumSamples()},
                  {"stride", stride}, {"t", t}, {"u", u}, {"y", y}};
    });
  });
  server.Get(R"(/api/experiments/([A-Za-z0-9_-]+)/(\d+)/export\.(csv|mat))",
             [&](const httplib::Request& req, httplib::Response& res) {
    try {
      std::string spec;
      const std::string rig = req.matches[1], ext = req.matches[3];
      const int64_t id = IdFrom(req.matches[2], "experiment id");
      const IoRecord r = LoadExperimentRecord(desk.options().experiments, rig, id, &spec);
      char tmpl[] = "/tmp/idrig-export-XXXXXX";
      const int fd = mkstemp(tmpl);
      if (fd < 0) throw std::runtime_error("cannot create a temporary file");
      close(fd);
      const std::string path = std::string(tmpl) + "." + ext;
      std::rename(tmpl, path.c_str());
      WriteRecordFile(r, path, {{"rig_id", rig}, {"experiment_id", std::to_string(id)}, {"signal_spec", spec}});
      std::ifstream in(path, std::ios::binary);
      std::ostringstream bytes;
      bytes << in.rdbuf();
      std::remove(path.c_str());
      const std::string name = rig + "_" + std::to_string(id) + "." + ext;
      res.set_header("Content-Disposition", "attachment; filename=\"" + name + "\"");
      res.set_content(bytes.str(), ext == "csv" ? "text/csv" : "application/octet-stream");
    } catch (const std::exception&) {
      Reply(res, [&]() -> json { throw; });
    }
  });
  server.Get("/api/models", [&](const httplib::Request& req, httplib::Response& res) {
    Reply(res, [&] {
      auto c = desk.OpenCatalog();
      json list = json::array();
      const std::string experiment = Param(req, "experiment");
      for (const auto& m : c->Models(Param(req, "rig"), Param(req, "method")))
        if (experiment.empty() || std::to_string(m.experiment_id) == experiment)
          list.push_back(ModelSummaryJson(*c, m));
      return list;
    });
  });
  server.Get(R"(/api/models/(\d+))", [&](const httplib::Request& req, httplib::Response& res) {
    Reply(res, [&] {
      auto c = desk.OpenCatalog();
      const ModelRecord m = RequireModel(*c, IdFrom(req.matches[1], "model id"), desk.options().db);
      json j = ModelSummaryJson(*c, m);
      j["model"] = json::parse(m.model_json);
      json metrics = json::array();
      for (const auto& x : c->Metrics(m.model_id))
        metrics.push_back({{"name", x.name}, {"value", x.value}, {"unit", x.unit}});
      j["metric_values"] = metrics;
      const json report = json::parse(m.report_json, nullptr, false);
      if (report.is_object()) {
        j["report_status"] = report.value("status", "");
        j["report_message"] = report.value("message", "");
      }
      return j;
    });
  });
  auto model_view = [&](const char* pattern, json (*view)(const ModelRecord&)) {
    server.Get(pattern, [&desk, view](const httplib::Request& req, httplib::Response& res) {
      Reply(res, [&] {
        auto c = desk.OpenCatalog();
        return view(RequireModel(*c, IdFrom(req.matches[1], "model id"), desk.options().db));
      });
    });
  };
  model_view(R"(/api/models/(\d+)/bode)", &BodeJson);
  model_view(R"(/api/models/(\d+)/step)", &StepJson);
  model_view(R"(/api/models/(\d+)/poles)", &PoleZeroJson);
  model_view(R"(/api/models/(\d+)/stabilisation)", &StabilisationJson);
  server.Get("/api/compare", [&](const httplib::Request& req, httplib::Response& res) {
    Reply(res, [&] {
      auto c = desk.OpenCatalog();
      const ModelRecord a = RequireModel(*c, IdFrom(Param(req, "a"), "a"), desk.options().db);
      const ModelRecord b = RequireModel(*c, IdFrom(Param(req, "b"), "b"), desk.options().db);
      return json{{"a", a.model_id}, {"b", b.model_id}, {"rows", CompareJson(CompareModels(*c, a, b))}};
    });
  });
  server.Get("/api/history", [&](const httplib::Request& req, httplib::Response& res) {
    Reply(res, [&] {
      auto c = desk.OpenCatalog();
      const std::string rig = Param(req, "rig");
      if (rig.empty()) throw std::invalid_argument("history needs ?rig=RIG");
      return HistoryJson(*c, rig, Param(req, "param", "wn_1"), Param(req, "method"));
    });
  });
  server.Get("/api/jobs", [&](const httplib::Request& req, httplib::Response& res) {
    Reply(res, [&] {
      auto c = desk.OpenCatalog();
      json list = json::array();
      for (const auto& j : c->Jobs(Param(req, "state")))
        list.push_back({{"request_id", j.request_id}, {"rig_id", j.rig_id}, {"experiment_id", j.experiment_id},
                        {"method", j.method}, {"state", j.state}, {"worker_id", j.worker_id},
                        {"attempts", j.attempts}, {"created_utc", UtcTimeText(j.created_utime)},
                        {"message", j.message}});
      return list;
    });
  });
  server.Get("/api/gaps", [&](const httplib::Request& req, httplib::Response& res) {
    Reply(res, [&] {
      auto c = desk.OpenCatalog();
      json list = json::array();
      for (const auto& d : c->Diagnoses(Param(req, "rig"))) {
        const json r = json::parse(d.report_json, nullptr, false);
        json verdict = r.is_object() && r.contains("verdict") ? r["verdict"] : json::object();
        list.push_back({{"report_id", d.report_id}, {"rig_id", d.rig_id}, {"model_id", d.model_id},
                        {"experiment_id", d.experiment_id}, {"created_utc", UtcTimeText(d.created_utime)},
                        {"verdict", verdict}});
      }
      return list;
    });
  });
  server.Get(R"(/api/gaps/(\d+))", [&](const httplib::Request& req, httplib::Response& res) {
    Reply(res, [&] {
      const DiagnosisRecord d = desk.RequireDiagnosis(req.matches[1]);
      const json report = json::parse(d.report_json);
      return json{{"report_id", d.report_id}, {"rig_id", d.rig_id}, {"model_id", d.model_id},
                  {"experiment_id", d.experiment_id}, {"created_utc", UtcTimeText(d.created_utime)},
                  {"text", GapReportText(report)}, {"report", report}};
    });
  });
  // The where / which / how-far plots of a report: the CLI's SVGs (core/io/gap_svg.h), by name.
  server.Get(R"(/api/gaps/(\d+)/plots)", [&](const httplib::Request& req, httplib::Response& res) {
    Reply(res, [&] {
      const DiagnosisRecord d = desk.RequireDiagnosis(req.matches[1]);
      json out = json::object();
      for (const auto& [name, svg] : GapReportSvgs(json::parse(d.report_json))) out[name] = svg;
      return out;
    });
  });
  // Read-only: whatever is not a GET is refused, naming why.
  auto refuse = [](const httplib::Request& req, httplib::Response& res) {
    res.status = 405;
    res.set_header("Allow", "GET");
    res.set_content(json({{"error", "the dashboard is read-only: " + req.method + " is not served"}}).dump(),
                    "application/json");
  };
  server.Post(".*", refuse);
  server.Put(".*", refuse);
  server.Delete(".*", refuse);
  server.Patch(".*", refuse);
}

std::string FindWebDir(const std::string& given) {
  if (!given.empty()) {
    if (!IsFile(given + "/index.html"))
      throw std::invalid_argument("--web-dir '" + given + "' has no index.html");
    return given;
  }
  for (const std::string& d : {ExecutableDir() + "/../web", ExecutableDir() + "/../share/idrig/web"})
    if (IsFile(d + "/index.html")) return d;
  return "";
}

void Serve(const ServeOptions& options) {
  if (options.port < 0 || options.port > 65535)
    throw std::invalid_argument("--port must be 0..65535 (0: any free port)");
  if (!IsFile(options.db))
    throw std::invalid_argument("catalogue '" + options.db +
                                "' does not exist (--db; `idrig demo` makes idrig-demo/catalog.db)");
  const std::string web = FindWebDir(options.web_dir);
  Desk desk(options);
  httplib::Server server;
  server.set_file_extension_and_mimetype_mapping("js", "text/javascript");
  server.set_file_extension_and_mimetype_mapping("css", "text/css");
  Routes(server, desk);
  if (!web.empty()) {
    server.set_mount_point("/", web);
  } else {
    server.Get("/", [](const httplib::Request&, httplib::Response& res) {
      res.set_content("<p>idrig serve: the front end is not built. Run <code>bash deploy/build-web.sh</code> "
                      "(or give --web-dir); the JSON API is at <a href='/api/summary'>/api/summary</a>.</p>",
                      "text/html");
    });
  }
  int port = options.port;
  if (port == 0) {
    port = server.bind_to_any_port(options.bind);
  } else if (!server.bind_to_port(options.bind, port)) {
    port = -1;
  }
  if (port <= 0)
    throw std::runtime_error("cannot listen on " + options.bind + ":" + std::to_string(options.port) +
                             " (in use? another --port, or --port 0 for any free one)");
  g_server = &server;
  signal(SIGINT, StopServer);
  signal(SIGTERM, StopServer);
  std::cout << "idrig serve: http://" << options.bind << ":" << port << "/  (read-only; catalogue "
            << options.db << ", experiments " << options.experiments
            << (options.url.empty() ? "" : ", live bus " + options.url)
            << (web.empty() ? ", front end NOT built" : ", pages from " + web) << "; Ctrl-C stops)\n"
            << std::flush;
  server.listen_after_bind();
  g_server = nullptr;
}

}  // namespace

void RegisterServeCommand(CLI::App& app) {
  auto options = std::make_shared<ServeOptions>();
  auto* cmd = app.add_subcommand(
      "serve", "the dashboard: a local, read-only web app over the catalogue, the experiment "
               "store and (with --url) the live bus");
  cmd->add_option("--db", options->db, "catalogue (idrig-catalog's db_path)");
  cmd->add_option("--experiments", options->experiments, "experiment store (idrig-logger's db_path)");
  cmd->add_option("--url", options->url, "LCM URL to listen on for service and experiment status");
  cmd->add_option("--port", options->port, "TCP port (0: any free port, printed)");
  cmd->add_option("--bind", options->bind, "address to bind (default 127.0.0.1: this machine only)");
  cmd->add_option("--web-dir", options->web_dir, "front end directory (default: build/web next to the binary)");
  cmd->callback([options] { Serve(*options); });
}

}  // namespace idrig
