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
#include "core/io/mat_io.h"
#include "core/io/model_json.h"
#include "core/io/svg_plot.h"
#include "core/methods/registry.h"
#include "core/transport/channels.h"
#include "tools/idrig/catalog_views.h"
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
        "write a model as idrig.model/1 JSON (lineage under \"identification\") or, for --out FILE.mat, as MATLAB variables for tf/ss");
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
      const ModelRecord m = RequireModel(catalog, args->id, args->db);
      nlohmann::json lineage = ModelLineageJson(m);
      for (const auto& x : catalog.Metrics(m.model_id))
        if (x.name == "record_fit_percent" || x.name == "dc_gain" || x.name == "order")
          lineage[x.name] = x.value;
      const bool mat = out->size() > 4 && out->compare(out->size() - 4, 4, ".mat") == 0;
      if (mat) {  // MATLAB: tf(num, den, Ts, 'InputDelay', delay) or ss(A, B, C, D, Ts, ...)
        const nlohmann::json model = nlohmann::json::parse(m.model_json);
        const OperatingPoint op = OperatingPointFromModelJson(model);
        WriteMatModel(ModelFromJson(model), *out, lineage, op);
        std::cerr << "wrote model " << m.model_id << " to " << *out << " (variables "
                  << (model.value("kind", "") == "tf" ? "num, den" : "A, B, C, D")
                  << (op.empty() ? "" : ", u0, y0 (operating point)") << ", Ts, delay, lineage)\n";
        return;
      }
      nlohmann::json j = nlohmann::json::parse(m.model_json);
      j["identification"] = lineage;
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
      const ModelRecord a = RequireModel(catalog, args->id, args->db);
      const ModelRecord b = RequireModel(catalog, *other, args->db);
      const auto rows = CompareModels(catalog, a, b);
      const std::string ha = "model " + std::to_string(a.model_id), hb = "model " + std::to_string(b.model_id);
      size_t w0 = 4, w1 = ha.size(), w2 = hb.size();
      auto name = [](const CompareRow& r) { return r.unit.empty() || r.unit == "1" ? r.name : r.name + " [" + r.unit + "]"; };
      for (const auto& r : rows) {
        w0 = std::max(w0, name(r).size());
        w1 = std::max(w1, std::min<size_t>(r.a.size(), 40));
        w2 = std::max(w2, std::min<size_t>(r.b.size(), 40));
      }
      auto cut = [](const std::string& t) { return t.size() > 40 ? t.substr(0, 39) + "~" : t; };
      std::cout << std::left << std::setw(w0 + 2) << "" << std::setw(w1 + 2) << ha << std::setw(w2 + 2) << hb
                << "difference (b - a)\n";
      for (const auto& r : rows)
        std::cout << std::left << std::setw(w0 + 2) << name(r) << std::setw(w1 + 2) << cut(r.a)
                  << std::setw(w2 + 2) << cut(r.b) << r.difference << "\n";
    });
    history->callback([args, svg] {
      Catalog catalog(args->db, true);
      PrintHistory(catalog, args->rig, args->param, args->method);
      if (svg->empty()) return;
      const std::string text = LinePlotSvg(HistoryPlot(HistoryJson(catalog, args->rig, args->param, args->method)));
      std::ofstream file(*svg);
      if (!file) throw std::invalid_argument("cannot write '" + *svg + "'");
      file << text;
    });
  }
}

}  // namespace idrig
