// `idrig models request|list|show|history|export|compare`: the model catalogue from the
// command line, and the printing of models that `idrig demo` shares (model_print.h).
// Channels, messages and the catalogue schema: docs/services.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>

#include "core/catalog/catalog.h"
#include "core/io/model_json.h"
#include "core/methods/registry.h"
#include "core/transport/channels.h"
#include "tools/idrig/commands.h"
#include "tools/idrig/model_print.h"
#include "tools/idrig/service_client.h"

namespace idrig {

std::string TimeText(int64_t utime) {
  const std::time_t t = static_cast<std::time_t>(utime / 1000000);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%d %H:%M:%S", std::gmtime(&t));
  return buffer;
}

namespace {

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

}  // namespace

std::string Number(double value, int precision) {
  if (!std::isfinite(value)) return "-";
  std::ostringstream s;
  s << std::setprecision(precision) << value;
  return s.str();
}

namespace {

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

}  // namespace

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

namespace {

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

}  // namespace

void RegisterModelsCommands(CLI::App& app) {
  // ---- models request|list|show|history
  {
    auto* group = app.add_subcommand("models", "request identification; query the model catalogue");
    group->require_subcommand(1);
    struct Args {
      std::string db = "idrig-demo/catalog.db", rig, method, param = "wn_1", url = DefaultLcmUrl(),
                  options = "{}", key_file;
      double timeout = 10.0, wait_timeout = 300.0;
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
    request->add_flag("--wait", args->wait,
                      "wait until the model is stored (exit 1 with the job's error if it fails)");
    request->add_option("--key-file", args->key_file, "operator key (default $IDRIG_KEY_FILE)");
    request->add_option("--timeout", args->timeout,
                        "seconds to re-send the request until the catalogue acknowledges it")
        ->check(CLI::PositiveNumber);
    request->add_option("--wait-timeout", args->wait_timeout, "seconds to wait with --wait")
        ->check(CLI::PositiveNumber);
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
      FindMethod(args->method);  // an unknown method: std::invalid_argument listing them (exit 2)
      if (!nlohmann::json::parse(args->options, nullptr, false).is_object())
        throw std::invalid_argument("--options must be a JSON object, got '" + args->options + "'");
      ServiceClient client(args->url, OperatorKeyPath(args->key_file));
      const int64_t id = NewId();
      auto send = [&] {
        client.RequestIdentify(args->rig, id, args->experiment, args->method, args->options);
      };
      // Re-sent until the catalogue has it as a job (or refuses it): no request is lost silently.
      const request_reply_t& accepted = client.AwaitReply(
          id, "catalog", "idrig-catalog", send, args->timeout,
          {request_reply_t::STATE_ACCEPTED, request_reply_t::STATE_DONE, request_reply_t::STATE_FAILED});
      std::cout << id << "\n" << std::flush;
      std::cerr << "request " << id << " acknowledged by the catalogue: " << accepted.message << "\n";
      if (!args->wait) return;
      const request_reply_t& end = client.AwaitReply(
          id, "catalog", "idrig-catalog", send, args->wait_timeout,
          {request_reply_t::STATE_DONE, request_reply_t::STATE_FAILED}, 2.0);
      if (end.state == request_reply_t::STATE_FAILED)
        throw CommandFailure("job " + std::to_string(id) + " failed: " + end.message);
      std::cerr << "stored as model " << end.model_id << " (" << end.message << ")\n";
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
}

}  // namespace idrig
