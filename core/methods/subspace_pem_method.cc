// Subspace and prediction-error methods on u/y records (core/numeric/time_domain/subspace.h,
// pem.h):
//   idrig identify --method n4sid --data rec.csv [--order 8] [--option weighting=cva|moesp|n4sid]
//                  [--option block_rows=15] [--option feedthrough=true] [--option enforce_stability=true]
//   idrig identify --method oe|armax|bj --data rec.csv [--order 3] [--option input_delay=1] …
// MIMO records: n4sid is MIMO; oe/armax/bj fit one MISO model per output and stack them.
// `auto` (the default of `idrig identify`) is in auto_method.cc.
#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/io/model_json.h"
#include "core/methods/registry.h"
#include "core/methods/report_json.h"
#include "core/methods/subspace_pem_method.h"
#include "core/numeric/time_domain/pem.h"
#include "core/numeric/time_domain/subspace.h"
#include "core/numeric/validation.h"

namespace idrig {
namespace {

using nlohmann::json;

using report_json::Complex;
using report_json::Mat;
using report_json::Vec;

int GetInt(const json& o, const char* key, int fallback) {
  if (!o.contains(key)) return fallback;
  if (!o[key].is_number_integer()) throw std::invalid_argument(std::string("option '") + key + "' must be an integer");
  return o[key].get<int>();
}
double GetDouble(const json& o, const char* key, double fallback) {
  if (!o.contains(key)) return fallback;
  if (!o[key].is_number()) throw std::invalid_argument(std::string("option '") + key + "' must be a number");
  return o[key].get<double>();
}
bool GetBool(const json& o, const char* key, bool fallback) {
  if (!o.contains(key)) return fallback;
  if (!o[key].is_boolean()) throw std::invalid_argument(std::string("option '") + key + "' must be true or false");
  return o[key].get<bool>();
}

std::string PoleText(const Eigen::VectorXcd& p) {
  std::ostringstream t;
  t << std::setprecision(6);
  for (int i = 0; i < p.size(); ++i)
    t << " " << p(i).real() << (p(i).imag() < 0 ? "-" : "+") << std::abs(p(i).imag()) << "j";
  return t.str();
}

std::string MatrixText(const char* name, const Eigen::MatrixXd& m) {
  std::ostringstream s;
  s << std::setprecision(6) << "  " << name << " =\n";
  for (int r = 0; r < m.rows(); ++r) {
    s << "    [";
    for (int c = 0; c < m.cols(); ++c) s << (c ? ", " : "") << std::setw(12) << m(r, c);
    s << "]\n";
  }
  return s.str();
}

std::string FitText(const Eigen::VectorXd& fit) {
  std::ostringstream t;
  t << std::setprecision(4);
  for (int i = 0; i < fit.size(); ++i) t << (i ? ", " : "") << "y" << i + 1 << " " << fit(i) << " %";
  return t.str();
}

// ---------------------------------------------------------------- n4sid
MethodReport RunSubspace(const MethodInput& input, const json& o) {
  CheckOptionKeys(o, {"order", "max_order", "block_rows", "weighting", "enforce_stability", "feedthrough",
                      "input_delay", "estimate_initial_state"},
                  "n4sid");
  SubspaceOptions options;
  options.order = GetInt(o, "order", 0);
  options.max_order = GetInt(o, "max_order", options.max_order);
  options.block_rows = GetInt(o, "block_rows", 0);
  if (o.contains("weighting")) {
    if (!o["weighting"].is_string()) throw std::invalid_argument("option 'weighting' must be moesp, n4sid or cva");
    options.weighting = ParseSubspaceWeighting(o["weighting"].get<std::string>());
  }
  options.enforce_stability = GetBool(o, "enforce_stability", false);
  options.feedthrough = GetBool(o, "feedthrough", false);
  options.input_delay = GetInt(o, "input_delay", 0);
  options.estimate_initial_state = GetBool(o, "estimate_initial_state", true);
  const SubspaceResult r = IdentifySubspace(*input.record, options);
  MethodReport report;
  json& j = report.json;
  j["model"] = ModelToJson(r.model);
  j["status"] = ToString(r.status);
  j["message"] = r.message;
  j["fit_percent"] = r.fit_percent;
  json d;
  d["weighting"] = ToString(options.weighting);
  d["order"] = r.order;
  d["order_rule"] = r.order_rule;
  d["block_rows"] = r.block_rows;
  d["singular_values"] = Vec(r.singular_values);
  d["gap"] = std::isfinite(r.gap) ? json(r.gap) : json("inf");
  d["fit_percent_per_output"] = Vec(r.fit_per_output);
  d["initial_state"] = Vec(r.initial_state);
  d["spectral_radius"] = r.spectral_radius;
  d["stabilised"] = r.stabilised;
  d["discrete_poles"] = Complex(Poles(r.model));
  const Eigen::VectorXd stds = r.parameter_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  const int nb = static_cast<int>(r.model.B.size());
  d["B_std"] = Mat(Eigen::Map<const Eigen::MatrixXd>(stds.data(), r.model.B.rows(), r.model.B.cols()));
  if (options.feedthrough)
    d["D_std"] = Mat(Eigen::Map<const Eigen::MatrixXd>(stds.data() + nb, r.model.D.rows(), r.model.D.cols()));
  d["warnings"] = r.warnings;
  j["details"] = d;

  std::ostringstream t;
  t << std::setprecision(6);
  t << "Subspace identification (" << ToString(options.weighting)
    << "; Van Overschee & De Moor 1996, Verhaegen 1994): " << r.message << ", status " << ToString(r.status) << "\n";
  t << "\nsingular values (order " << r.order << " by " << r.order_rule << ", gap s_n/s_n+1 = " << r.gap << "):\n ";
  for (int i = 0; i < std::min<int>(r.singular_values.size(), 3 * std::max(r.order, 4)); ++i)
    t << " " << r.singular_values(i) << (i + 1 == r.order ? " |" : "");
  t << "\n\nx[k+1] = A x[k] + B u[k" << (options.input_delay ? "-" + std::to_string(options.input_delay) : "")
    << "], y[k] = C x[k] + D u, Ts = " << r.model.sample_time << " s\n"
    << MatrixText("A", r.model.A) << MatrixText("B", r.model.B) << MatrixText("C", r.model.C)
    << MatrixText("D", r.model.D)
    << MatrixText("B std", Eigen::Map<const Eigen::MatrixXd>(stds.data(), r.model.B.rows(), r.model.B.cols()));
  t << "  x0' = [" << r.initial_state.transpose() << "]\n";
  t << "\ndiscrete poles:" << PoleText(Poles(r.model)) << "\nspectral radius " << r.spectral_radius << "\n";
  t << "fit (simulation from x0, 100(1-NRMSE)): " << FitText(r.fit_per_output) << "\n";
  for (const auto& w : r.warnings) t << "warning: " << w << "\n";
  report.text = t.str();
  return report;
}

// ---------------------------------------------------------------- oe / armax / bj
StateSpace Stack(const std::vector<StateSpace>& rows) {
  int n = 0;
  for (const auto& s : rows) n += s.Order();
  const int nu = rows.front().NumInputs(), ny = static_cast<int>(rows.size());
  StateSpace out;
  out.A = Eigen::MatrixXd::Zero(n, n);
  out.B = Eigen::MatrixXd::Zero(n, nu);
  out.C = Eigen::MatrixXd::Zero(ny, n);
  out.D = Eigen::MatrixXd::Zero(ny, nu);
  int at = 0;
  for (int r = 0; r < ny; ++r) {
    const int k = rows[r].Order();
    out.A.block(at, at, k, k) = rows[r].A;
    out.B.middleRows(at, k) = rows[r].B;
    out.C.block(r, at, 1, k) = rows[r].C;
    out.D.row(r) = rows[r].D;
    at += k;
  }
  out.sample_time = rows.front().sample_time;
  out.delay_s = rows.front().delay_s;
  return out;
}

std::string PolyText(const Eigen::VectorXd& p, int first_power, const Eigen::VectorXd* std_dev = nullptr) {
  std::ostringstream s;
  s << std::setprecision(6);
  for (int k = 0; k < p.size(); ++k) {
    s << (k ? (p(k) < 0 ? " - " : " + ") : (p(k) < 0 ? "-" : "")) << std::abs(p(k));
    if (std_dev && k < std_dev->size() && (*std_dev)(k) > 0) s << "(±" << std::setprecision(2) << (*std_dev)(k) << std::setprecision(6) << ")";
    const int power = first_power + k;
    if (power > 0) s << " q^-" << power;
  }
  return s.str();
}

MethodReport RunPem(const MethodInput& input, const json& o, PemStructure structure) {
  const std::string name = ToString(structure);
  CheckOptionKeys(o, {"order", "max_order", "nb", "nf", "na", "nc", "nd", "input_delay", "max_iterations",
                      "tolerance", "subspace_start", "steiglitz_mcbride_start"},
                  name);
  PemOptions options;
  options.structure = structure;
  options.order = GetInt(o, "order", 0);
  options.max_order = GetInt(o, "max_order", options.max_order);
  options.nb = GetInt(o, "nb", -1);
  options.nf = GetInt(o, "nf", -1);
  options.na = GetInt(o, "na", -1);
  options.nc = GetInt(o, "nc", -1);
  options.nd = GetInt(o, "nd", -1);
  options.input_delay = GetInt(o, "input_delay", 1);
  options.max_iterations = GetInt(o, "max_iterations", options.max_iterations);
  options.tolerance = GetDouble(o, "tolerance", options.tolerance);
  options.subspace_start = GetBool(o, "subspace_start", true);
  options.steiglitz_mcbride_start = GetBool(o, "steiglitz_mcbride_start", true);
  const IoRecord& record = *input.record;
  const int ny = record.NumOutputs();
  std::vector<PemResult> results;
  for (int out = 0; out < ny; ++out) {
    options.output = out;
    results.push_back(IdentifyPem(record, options));
  }
  MethodReport report;
  json& j = report.json;
  std::ostringstream t;
  t << std::setprecision(6);
  const char* title = structure == PemStructure::kOutputError ? "Output error y = B/F u + e"
                      : structure == PemStructure::kArmax     ? "ARMAX A y = B u + C e"
                                                              : "Box-Jenkins y = B/F u + C/D e";
  t << title << " (prediction-error method, Ljung 1999 §10.3: Levenberg-Marquardt on exact gradients)"
    << (ny > 1 ? ", one MISO model per output" : "") << "\n";
  SolverStatus status = SolverStatus::kOk;
  std::vector<StateSpace> rows;
  Eigen::VectorXd fits(ny);
  json per_output = json::array();
  std::string message;
  for (int out = 0; out < ny; ++out) {
    const PemResult& r = results[out];
    if (r.status != SolverStatus::kOk && status == SolverStatus::kOk) status = r.status;
    message += (out ? "; " : "") + (ny > 1 ? "y" + std::to_string(out + 1) + ": " : std::string()) + r.message;
    if (r.status == SolverStatus::kFailed) {
      per_output.push_back({{"status", ToString(r.status)}, {"message", r.message}});
      fits(out) = 0.0;
      continue;
    }
    rows.push_back(r.model);
    fits(out) = r.fit_percent;
    json d;
    d["order"] = r.order;
    d["input_delay_samples"] = r.input_delay;
    d["a"] = Vec(r.a);
    d["c"] = Vec(r.c);
    d["d"] = Vec(r.d);
    json b = json::array(), f = json::array(), tfs = json::array();
    for (size_t k = 0; k < r.b.size(); ++k) {
      b.push_back(Vec(r.b[k]));
      f.push_back(Vec(r.f[k]));
      tfs.push_back(ModelToJson(r.input_tfs[k]));
    }
    d["b"] = b;
    d["f"] = f;
    d["input_tfs"] = tfs;
    json params = json::array();
    for (size_t k = 0; k < r.parameter_names.size(); ++k)
      params.push_back({{"name", r.parameter_names[k]}, {"value", r.theta(k)}, {"std", r.theta_std(k)}});
    d["parameters"] = params;
    d["covariance"] = Mat(r.covariance);
    d["noise_variance"] = r.noise_variance;
    d["iterations"] = r.iterations;
    d["final_cost"] = r.final_cost;
    d["discrete_poles"] = Complex(Poles(r.model));
    json starts = json::array();
    for (const auto& s : r.starts)
      starts.push_back({{"start", s.name}, {"initial_cost", s.initial_cost}, {"final_cost", s.final_cost},
                        {"iterations", s.iterations}, {"stable", s.stable}, {"chosen", s.chosen}});
    d["starts"] = starts;
    json table = json::array();
    for (const auto& c : r.order_table) table.push_back({{"order", c.order}, {"validation_fit_percent", c.validation_fit_percent}});
    d["order_table"] = table;
    d["fit_percent"] = r.fit_percent;
    d["status"] = ToString(r.status);
    d["warnings"] = r.warnings;
    per_output.push_back(d);

    t << "\n" << (ny > 1 ? "output y" + std::to_string(out + 1) + ": " : std::string()) << r.message << ", status "
      << ToString(r.status) << "\n";
    if (!r.order_table.empty()) {
      t << "  order on held-out data (fit % on the last third):";
      for (const auto& c : r.order_table) t << "  n=" << c.order << ": " << std::setprecision(4) << c.validation_fit_percent;
      t << std::setprecision(6) << "   -> n = " << r.order << "\n";
    }
    for (const auto& s : r.starts)
      t << "  start " << std::setw(18) << std::left << s.name << std::right << " cost " << s.initial_cost << " -> "
        << s.final_cost << " (" << s.iterations << " it" << (s.stable ? "" : ", unstable") << ")"
        << (s.chosen ? "  <- kept" : "") << "\n";
    int at = 0;
    auto poly_block = [&](const char* label, const Eigen::VectorXd& p, int first_power, bool monic) {
      const int free = static_cast<int>(p.size()) - (monic ? 1 : 0);
      if (free <= 0) return;
      Eigen::VectorXd sd = Eigen::VectorXd::Zero(p.size());
      sd.tail(free) = r.theta_std.segment(at, free);
      at += free;
      t << "  " << label << " = " << PolyText(p, first_power, &sd) << "\n";
    };
    // θ order (a, b_1…b_nu, c, d, f_1…f_nu), as the standard errors are laid out.
    poly_block("A(q)", r.a, 0, true);
    for (size_t k = 0; k < r.b.size(); ++k)
      poly_block(r.b.size() > 1 ? ("B" + std::to_string(k + 1) + "(q)").c_str() : "B(q)", r.b[k], r.input_delay, false);
    poly_block("C(q)", r.c, 0, true);
    poly_block("D(q)", r.d, 0, true);
    for (size_t k = 0; k < r.f.size(); ++k)
      poly_block(r.f.size() > 1 ? ("F" + std::to_string(k + 1) + "(q)").c_str() : "F(q)", r.f[k], 0, true);
    t << "  noise variance " << r.noise_variance << "; discrete poles:" << PoleText(Poles(r.model)) << "\n";
    for (const auto& w : r.warnings) t << "  warning: " << w << "\n";
  }
  if (rows.empty()) {
    j["status"] = ToString(SolverStatus::kFailed);
    j["message"] = message;
    j["fit_percent"] = 0.0;
    j["model"] = nullptr;
    j["details"] = {{"outputs", per_output}};
    report.text = t.str();
    return report;
  }
  if (static_cast<int>(rows.size()) != ny) status = SolverStatus::kFailed;
  if (ny == 1 && record.NumInputs() == 1) j["model"] = ModelToJson(results[0].input_tfs[0]);
  else j["model"] = ModelToJson(Stack(rows));
  j["status"] = ToString(status);
  j["message"] = message;
  j["fit_percent"] = fits.mean();
  json d;
  d["structure"] = name;
  d["fit_percent_per_output"] = Vec(fits);
  d["outputs"] = per_output;
  j["details"] = d;
  t << "\nfit (simulation from rest, 100(1-NRMSE)): " << FitText(fits) << "\n";
  report.text = t.str();
  return report;
}

}  // namespace

std::vector<MethodInfo> SubspacePemMethods() {
  return {
      {"n4sid", "subspace identification, MIMO state space (MOESP/N4SID/CVA weighting, order from the singular values)",
       true, [](const MethodInput& in, const json& o) { return RunSubspace(in, o); }},
      {"oe", "output-error model B/F by prediction-error minimisation (MISO per output), with standard errors", true,
       [](const MethodInput& in, const json& o) { return RunPem(in, o, PemStructure::kOutputError); }},
      {"armax", "ARMAX model A y = B u + C e by prediction-error minimisation (MISO per output)", true,
       [](const MethodInput& in, const json& o) { return RunPem(in, o, PemStructure::kArmax); }},
      {"bj", "Box-Jenkins model y = B/F u + C/D e by prediction-error minimisation (MISO per output)", true,
       [](const MethodInput& in, const json& o) { return RunPem(in, o, PemStructure::kBoxJenkins); }},
      AutoMethod(),
  };
}

}  // namespace idrig
