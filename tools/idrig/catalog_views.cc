#include "tools/idrig/catalog_views.h"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <idrig/measurement_block_t.hpp>
#include <map>
#include <set>
#include <sstream>

#include "core/catalog/experiment_store.h"
#include "core/io/csv.h"
#include "core/io/mat_io.h"
#include "core/io/model_json.h"
#include "core/numeric/model/response_band.h"
#include "services/worker/worker_service.h"

namespace idrig {
namespace {

using json = nlohmann::json;

std::string Num(double v, int precision = 6) {
  if (!std::isfinite(v)) return "-";
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

json Finite(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

std::map<std::string, Metric> MetricsByName(Catalog& catalog, int64_t model_id) {
  std::map<std::string, Metric> out;
  for (const auto& m : catalog.Metrics(model_id)) out[m.name] = m;
  return out;
}

std::string UnitOf(const std::string& metric) {
  if (metric.rfind("wn_", 0) == 0 || metric.rfind("pole_", 0) == 0) return "rad/s";
  if (metric.find("fit_percent") != std::string::npos) return "%";
  if (metric.rfind("zeta_", 0) == 0 || metric == "order") return "1";
  if (metric == "dc_gain") return "output/input";
  return "";
}

bool Exists(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0;
}

// The SISO channel (1, 1) of a stored model, as a state-space model.
StateSpace StoredModel(const ModelRecord& m, LtiModel* as_stored = nullptr) {
  const LtiModel model = ModelFromJson(json::parse(m.model_json));
  if (as_stored) *as_stored = model;
  return ToStateSpace(model);
}

// Pole magnitudes in rad/s (discrete poles mapped by s = ln z / Ts).
std::vector<double> PoleSpeeds(const StateSpace& ss) {
  std::vector<double> out;
  for (const auto& p : Poles(ss)) {
    const std::complex<double> s = ss.IsDiscrete() ? std::log(p) / ss.sample_time : p;
    if (std::abs(s) > 1e-9 && std::isfinite(std::abs(s))) out.push_back(std::abs(s));
  }
  return out;
}

Eigen::VectorXd LogGrid(double lo, double hi, int n) {
  Eigen::VectorXd w(n);
  for (int k = 0; k < n; ++k) w(k) = lo * std::pow(hi / lo, k / (n - 1.0));
  return w;
}

std::vector<double> Std(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

}  // namespace

std::string UtcTimeText(int64_t utime) { return UtcText(utime * 1e-6); }

json ModelLineageJson(const ModelRecord& m) {
  return {{"model_id", m.model_id},
          {"request_id", m.request_id},
          {"rig_id", m.rig_id},
          {"experiment_id", m.experiment_id},
          {"signal_spec", m.signal_spec},
          {"method", m.method},
          {"options", json::parse(m.options_json, nullptr, false)},
          {"data_hash", m.data_hash},
          {"n_samples", m.n_samples},
          {"sample_time_s", m.sample_time_s},
          {"software_version", m.software_version},
          {"worker_id", m.worker_id},
          {"compute_s", m.compute_s},
          {"created_utime", m.created_utime},
          {"created_utc", UtcTimeText(m.created_utime)},
          {"fit_percent", Finite(m.fit_percent)},
          {"status", m.status}};
}

json ModelSummaryJson(Catalog& catalog, const ModelRecord& m) {
  json j = ModelLineageJson(m);
  const auto metrics = MetricsByName(catalog, m.model_id);
  auto get = [&](const std::string& n) {
    auto it = metrics.find(n);
    return it == metrics.end() ? json(nullptr) : Finite(it->second.value);
  };
  j["record_fit_percent"] = get("record_fit_percent");
  j["order"] = get("order");
  j["dc_gain"] = get("dc_gain");
  json poles = json::array();
  for (int k = 1; metrics.count("pole_" + std::to_string(k) + "_re"); ++k)
    poles.push_back({metrics.at("pole_" + std::to_string(k) + "_re").value,
                     metrics.at("pole_" + std::to_string(k) + "_im").value});
  j["poles"] = poles;
  json names = json::array();
  for (const auto& [name, x] : metrics) names.push_back(name);
  j["metrics"] = names;
  return j;
}

ModelRecord RequireModel(Catalog& catalog, int64_t model_id, const std::string& db_path) {
  auto m = catalog.Model(model_id);
  if (!m) throw std::invalid_argument("no model " + std::to_string(model_id) + " in " + db_path);
  return *m;
}

std::vector<CompareRow> CompareModels(Catalog& catalog, const ModelRecord& a, const ModelRecord& b) {
  std::vector<CompareRow> rows;
  auto text = [&](const std::string& name, const std::string& x, const std::string& y) {
    rows.push_back({name, "", x, y, x == y ? "same" : "differs"});
  };
  auto number = [&](const std::string& name, const std::string& unit, double x, double y) {
    std::string d = "-";
    if (std::isfinite(x) && std::isfinite(y)) {
      d = Num(y - x, 4);
      if (std::abs(x) > 1e-300 && y != x) d += " (" + Num(100.0 * (y - x) / std::abs(x), 3) + " %)";
    }
    rows.push_back({name, unit, Num(x), Num(y), d});
  };
  text("method", a.method, b.method);
  text("options", a.options_json, b.options_json);
  text("rig", a.rig_id, b.rig_id);
  text("experiment", std::to_string(a.experiment_id), std::to_string(b.experiment_id));
  text("signal", a.signal_spec, b.signal_spec);
  text("data sha256", a.data_hash.substr(0, 16), b.data_hash.substr(0, 16));
  number("samples", "", static_cast<double>(a.n_samples), static_cast<double>(b.n_samples));
  number("Ts", "s", a.sample_time_s, b.sample_time_s);
  text("worker", a.worker_id, b.worker_id);
  text("idrig version", a.software_version, b.software_version);
  text("stored (UTC)", UtcTimeText(a.created_utime), UtcTimeText(b.created_utime));
  number("compute", "s", a.compute_s, b.compute_s);
  const auto ma = MetricsByName(catalog, a.model_id), mb = MetricsByName(catalog, b.model_id);
  std::set<std::string> names;
  for (const auto& [k, v] : ma) names.insert(k);
  for (const auto& [k, v] : mb) names.insert(k);
  for (const auto& n : names) {
    const double x = ma.count(n) ? ma.at(n).value : std::nan("");
    const double y = mb.count(n) ? mb.at(n).value : std::nan("");
    const std::string unit = ma.count(n) && !ma.at(n).unit.empty()   ? ma.at(n).unit
                             : mb.count(n) && !mb.at(n).unit.empty() ? mb.at(n).unit
                                                                     : UnitOf(n);
    number(n, unit, x, y);
  }
  return rows;
}

json CompareJson(const std::vector<CompareRow>& rows) {
  json out = json::array();
  for (const auto& r : rows)
    out.push_back({{"name", r.name}, {"unit", r.unit}, {"a", r.a}, {"b", r.b}, {"difference", r.difference}});
  return out;
}

json HistoryJson(Catalog& catalog, const std::string& rig, const std::string& metric,
                 const std::string& method) {
  const auto history = catalog.History(rig, metric, method);
  std::map<std::string, json> by_method;
  std::string unit = UnitOf(metric);
  for (const auto& [m, value] : history) {
    if (!by_method.count(m.method)) by_method[m.method] = json::array();
    by_method[m.method].push_back({{"model_id", m.model_id},
                                   {"utime", m.created_utime},
                                   {"t", m.created_utime * 1e-6},
                                   {"utc", UtcTimeText(m.created_utime)},
                                   {"experiment_id", m.experiment_id},
                                   {"value", Finite(value)}});
  }
  json series = json::array();
  for (auto& [name, points] : by_method) series.push_back({{"method", name}, {"points", points}});
  return {{"rig", rig}, {"param", metric}, {"unit", unit}, {"count", history.size()}, {"series", series}};
}

LinePlot HistoryPlot(const json& history) {
  LinePlot plot;
  const std::string param = history.at("param"), rig = history.at("rig");
  plot.title = param + " of rig " + rig + ", one series per method";
  plot.y = PlotAxis(param, history.at("unit"));
  std::vector<double> times;
  for (const auto& s : history.at("series"))
    for (const auto& p : s.at("points")) times.push_back(p.at("t").get<double>());
  if (times.empty())
    throw std::invalid_argument("no model of rig '" + rig + "' has metric '" + param + "'");
  std::sort(times.begin(), times.end());
  const double span = times.back() - times.front();
  double closest = span;
  for (size_t i = 1; i < times.size(); ++i) closest = std::min(closest, times[i] - times[i - 1]);
  // On a ~650 px time axis, points closer than 1/100 of the span (6.5 px) overlap: then the
  // axis is the storage order, each tick labelled with its storage time.
  const bool ordinal = times.size() > 1 && closest < span / 100.0;
  std::map<double, int> rank;
  for (double t : times) rank.emplace(t, static_cast<int>(rank.size()));
  if (ordinal) {
    plot.x = PlotAxis("models in storage order, labelled with the storage time (UTC)");
    const size_t every = std::max<size_t>(1, (rank.size() + 11) / 12);
    // Models stored in the same second get milliseconds, so that no two ticks read the same.
    bool same_second = false;
    for (size_t i = 1; i < times.size(); ++i)
      same_second |= std::floor(times[i]) == std::floor(times[i - 1]) && times[i] != times[i - 1];
    for (const auto& [t, i] : rank)
      if (i % every == 0) {
        const std::string utc = UtcText(t);
        std::string label = span > 43200 ? utc.substr(5, 11) + utc.substr(16) : utc.substr(11);
        if (same_second) {
          char ms[8];
          std::snprintf(ms, sizeof(ms), ".%03d", static_cast<int>((t - std::floor(t)) * 1000));
          label += ms;
        }
        plot.x.ticks.push_back({static_cast<double>(i), label});
      }
  } else {
    plot.x = PlotAxis("time stored", "", true);
  }
  for (const auto& s : history.at("series")) {
    PlotSeries series(s.at("method").get<std::string>());
    for (const auto& p : s.at("points")) {
      const double t = p.at("t").get<double>();
      series.x.push_back(ordinal ? rank.at(t) : t);
      series.y.push_back(p.at("value").is_number() ? p.at("value").get<double>() : std::nan(""));
      series.tips.push_back("model " + std::to_string(p.at("model_id").get<int64_t>()) + " (" +
                            series.name + "), stored " + p.at("utc").get<std::string>() +
                            " UTC: " + Num(series.y.back()) + " " + plot.y.unit);
    }
    plot.series.push_back(std::move(series));
  }
  return plot;
}

json BodeJson(const ModelRecord& m) {
  LtiModel stored;
  const StateSpace ss = StoredModel(m, &stored);
  const auto speeds = PoleSpeeds(ss);
  double lo = 0.01, hi = 100.0;
  if (!speeds.empty()) {
    lo = 0.05 * *std::min_element(speeds.begin(), speeds.end());
    hi = 20.0 * *std::max_element(speeds.begin(), speeds.end());
  }
  const json report = json::parse(m.report_json, nullptr, false);
  const json* details = report.is_object() && report.contains("details") ? &report["details"] : nullptr;
  bool has_band = details && details->contains("covariance") && details->contains("g") &&
                  m.sample_time_s > 0 && (*details)["g"].size() > 0;
  std::string no_band = has_band ? "" : "method " + m.method + " stores no parameter covariance";
  // arx-oe keeps the covariance of its first least-squares fit beside the refined g: the two do
  // not belong together (propagated, they give a band 40x wider than the least-squares one on
  // the demo's step record), so no band is drawn for it.
  if (has_band && details->contains("warnings"))
    for (const auto& w : (*details)["warnings"])
      if (w.is_string() && w.get<std::string>().find("covariance is that of the first") != std::string::npos) {
        has_band = false;
        no_band = "the stored covariance is that of the least-squares fit before the output-error "
                  "refinement, not of this model's parameters";
      }
  double nyquist = ss.IsDiscrete() ? M_PI / ss.sample_time : INFINITY;
  if (has_band) nyquist = std::min(nyquist, M_PI / m.sample_time_s);
  hi = std::min(hi, nyquist);
  lo = std::min(lo, hi / 1000.0);
  const Eigen::VectorXd omega = LogGrid(lo, hi, 300);
  std::vector<double> mag, phase;
  double previous = 0.0;
  for (int k = 0; k < omega.size(); ++k) {
    const std::complex<double> w = FrequencyResponse(ss, omega(k))(0, 0);
    mag.push_back(20.0 * std::log10(std::abs(w)));
    double p = std::arg(w);
    if (k > 0) p -= 2 * M_PI * std::round((p - previous) / (2 * M_PI));
    previous = p;
    phase.push_back(p * 180.0 / M_PI);
  }
  json out = {{"model_id", m.model_id}, {"method", m.method}, {"omega", Std(omega)},
              {"mag_db", mag}, {"phase_deg", phase}, {"domain", ss.IsDiscrete() ? "discrete" : "continuous"},
              {"nyquist_rad_s", std::isfinite(nyquist) ? json(nyquist) : json(nullptr)}};
  if (!has_band) out["no_band"] = no_band;
  if (has_band) {
    try {
      const auto& d = *details;
      const std::vector<double> gv = d["g"].get<std::vector<double>>();
      const Eigen::VectorXd g = Eigen::Map<const Eigen::VectorXd>(gv.data(), gv.size());
      Eigen::MatrixXd cov(g.size(), g.size());
      for (int r = 0; r < g.size(); ++r)
        for (int c = 0; c < g.size(); ++c) cov(r, c) = d["covariance"].at(r).at(c).get<double>();
      const ResponseBand b = ArxResponseBand(g, cov, m.sample_time_s, d.value("input_delay_samples", 1), omega);
      std::vector<double> lo_db, hi_db, lo_ph, hi_ph, mid_db;
      for (int k = 0; k < omega.size(); ++k) {
        const double db = 20.0 * std::log10(b.magnitude(k));
        const double sdb = 20.0 / std::log(10.0) * b.magnitude_std(k) / b.magnitude(k);
        mid_db.push_back(db);
        lo_db.push_back(db - 2 * sdb);
        hi_db.push_back(db + 2 * sdb);
        // The band's phase follows the stored model's unwrapping (same branch at each ω).
        const double ph = b.phase_rad(k) * 180.0 / M_PI;
        const double shift = 360.0 * std::round((phase[k] - ph) / 360.0);
        lo_ph.push_back(ph + shift - 2 * b.phase_std_rad(k) * 180.0 / M_PI);
        hi_ph.push_back(ph + shift + 2 * b.phase_std_rad(k) * 180.0 / M_PI);
      }
      std::string note = "±2σ of the discrete ARX least-squares estimate W(z) (first-order propagation of its covariance)";
      out["band"] = {{"mag_db_center", mid_db}, {"mag_db_lo", lo_db}, {"mag_db_hi", hi_db},
                     {"phase_deg_lo", lo_ph}, {"phase_deg_hi", hi_ph}, {"note", note}};
    } catch (const std::exception& e) {
      out["band_error"] = e.what();
    }
  }
  return out;
}

json StepJson(const ModelRecord& m) {
  const StateSpace ss = StoredModel(m);
  double slowest = 1.0;
  for (const auto& p : Poles(ss)) {
    const std::complex<double> s = ss.IsDiscrete() ? std::log(p) / ss.sample_time : p;
    if (s.real() < -1e-9) slowest = std::max(slowest, -1.0 / s.real());
  }
  const double horizon = std::min(8.0 * slowest, 1e4);
  const double dt = ss.IsDiscrete() ? ss.sample_time : horizon / 500.0;
  const int n = std::min(4000, static_cast<int>(std::ceil(horizon / dt)) + 1);
  const Eigen::MatrixXd y = StepResponse(ss, dt, n);
  std::vector<double> t(n), v(n);
  for (int k = 0; k < n; ++k) t[k] = k * dt + ss.delay_s, v[k] = y(k, 0);
  return {{"model_id", m.model_id}, {"method", m.method}, {"t", t}, {"y", v}};
}

json PoleZeroJson(const ModelRecord& m) {
  LtiModel stored;
  const StateSpace ss = StoredModel(m, &stored);
  auto pairs = [](const Eigen::VectorXcd& v) {
    json out = json::array();
    for (const auto& c : v) out.push_back({c.real(), c.imag()});
    return out;
  };
  const TransferFunction tf = std::holds_alternative<TransferFunction>(stored)
                                  ? std::get<TransferFunction>(stored)
                                  : ToTransferFunction(ss, 0, 0);
  return {{"model_id", m.model_id}, {"method", m.method},
          {"domain", ss.IsDiscrete() ? "discrete" : "continuous"}, {"Ts", ss.sample_time},
          {"poles", pairs(Poles(ss))}, {"zeros", pairs(Zeros(tf))}};
}

json StabilisationJson(const ModelRecord& m) {
  const json report = json::parse(m.report_json, nullptr, false);
  json points = json::array();
  if (report.is_object() && report.contains("details") &&
      report["details"].contains("stabilisation_diagram"))
    points = report["details"]["stabilisation_diagram"];
  return {{"model_id", m.model_id}, {"method", m.method}, {"points", points}};
}

json ExperimentsJson(Catalog* catalog, const std::string& store_path) {
  std::map<std::pair<std::string, int64_t>, json> rows;
  if (catalog)
    for (const auto& e : catalog->Experiments())
      rows[{e.rig_id, e.experiment_id}] = {{"rig_id", e.rig_id}, {"experiment_id", e.experiment_id},
          {"signal_spec", e.signal_spec}, {"sample_rate_hz", e.sample_rate_hz},
          {"samples_total", e.samples_total}, {"blocks_total", e.blocks_total}, {"state", e.state},
          {"start_utime", e.start_utime}, {"end_utime", e.end_utime},
          {"start_utc", e.start_utime ? UtcTimeText(e.start_utime) : ""}};
  if (!store_path.empty() && Exists(store_path)) {
    ExperimentStore store(store_path, true);
    for (const auto& e : store.Experiments()) {
      json& row = rows[{e.rig_id, e.experiment_id}];
      if (!row.contains("rig_id"))
        row = {{"rig_id", e.rig_id}, {"experiment_id", e.experiment_id}, {"signal_spec", e.signal_spec},
               {"sample_rate_hz", e.sample_rate_hz}, {"samples_total", e.samples_total},
               {"blocks_total", e.blocks_total}, {"state", e.ended ? "ended" : "running"}};
      row["blocks_stored"] = e.blocks_stored;
      row["commands_stored"] = e.commands_stored;
      row["missing_blocks"] = store.MissingCount(e.rig_id, e.experiment_id);
      row["in_store"] = true;
    }
  }
  json out = json::array();
  for (auto& [key, row] : rows) {
    if (!row.contains("in_store")) row["in_store"] = false;
    out.push_back(row);
  }
  return out;
}

IoRecord LoadExperimentRecord(const std::string& store_path, const std::string& rig,
                              int64_t experiment_id, std::string* signal_spec) {
  if (store_path.empty() || !Exists(store_path))
    throw std::invalid_argument("experiment store '" + store_path +
                                "' does not exist (the logger's db_path, e.g. idrig-demo/experiments.db)");
  ExperimentStore store(store_path, true);
  StoredExperiment e;
  if (!store.FindExperiment(rig, experiment_id, &e))
    throw std::invalid_argument("no experiment " + std::to_string(experiment_id) + " of rig '" + rig +
                                "' in " + store_path + " (idrig experiment list)");
  if (signal_spec) *signal_spec = e.signal_spec;
  std::map<int64_t, measurement_block_t> blocks;
  for (const auto& b : store.Blocks(rig, experiment_id)) {
    measurement_block_t m;
    if (m.decode(b.data.data(), 0, static_cast<int>(b.data.size())) < 0)
      throw std::invalid_argument(store_path + ": block " + std::to_string(b.seq) + " of experiment " +
                                  std::to_string(experiment_id) + " cannot be decoded");
    blocks[b.seq] = std::move(m);
  }
  const int64_t total = e.blocks_total > 0 ? e.blocks_total : (blocks.empty() ? 0 : blocks.rbegin()->first + 1);
  try {
    return AssembleRecord(blocks, total);
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(store_path + ", experiment " + std::to_string(experiment_id) + ": " +
                                error.what());
  }
}

void WriteRecordFile(const IoRecord& record, const std::string& path,
                     const std::map<std::string, std::string>& text) {
  auto ends = [&](const std::string& ext) {
    return path.size() > ext.size() && path.compare(path.size() - ext.size(), ext.size(), ext) == 0;
  };
  if (ends(".csv")) {
    WriteIoRecordCsv(record, path);
  } else if (ends(".mat")) {
    WriteMatRecord(record, path, text);
  } else {
    throw std::invalid_argument("--out '" + path + "': the file name must end in .csv or .mat");
  }
}

}  // namespace idrig
