// `finite-frequency`: seed 003's finite-frequency identification (algorithm 2.1 of [Aleksandrov])
// on a record whose input is the test signal (5) started at the first sample.
//   idrig identify --data r.csv --method finite-frequency --order 3 --option numerator_degree=1
//     --option base_omega=0.177 --option "frequencies=[0.177,1.24,8.69]" [--option amplitudes=5]
// Options: order (n), numerator_degree (γ), base_omega (ω_b, rad/s), frequencies (ω_k, rad/s,
// integer multiples of ω_b) or multiples (n_k), amplitudes (ρ_k: a number or a list; default:
// measured from the input by the Fourier filter), epsilon_d, epsilon_k, consecutive,
// min_base_periods, max_base_periods, skip_base_periods, filter_time, lambda, input_bound,
// output_bound, zoh_correction (default true: the input was held between samples),
// numerator_tolerance. Defaults (issue 15): without base_omega/frequencies/multiples the test
// signal is found in the input's spectrum; without numerator_degree γ is chosen by the residual
// of (12) over γ = 0..n−1 (finite_frequency_defaults.h).
#include <cmath>
#include <sstream>

#include "core/io/model_json.h"
#include "core/methods/registry.h"
#include "core/numeric/finite_frequency/finite_frequency.h"
#include "core/numeric/finite_frequency/finite_frequency_defaults.h"

namespace idrig {
namespace {

using nlohmann::json;

json Vec(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

std::vector<double> Numbers(const json& o, const char* key) {
  const json& v = o.at(key);
  if (v.is_number()) return {v.get<double>()};
  if (!v.is_array()) throw std::invalid_argument(std::string("option '") + key + "' must be a number or a list of numbers");
  std::vector<double> out;
  for (const auto& x : v) {
    if (!x.is_number()) throw std::invalid_argument(std::string("option '") + key + "' must hold numbers only");
    out.push_back(x.get<double>());
  }
  return out;
}

MethodReport Run(const MethodInput& input, const json& o) {
  CheckOptionKeys(o, {"order", "numerator_degree", "base_omega", "frequencies", "multiples",
                      "amplitudes", "epsilon_d", "epsilon_k", "consecutive", "min_base_periods",
                      "max_base_periods", "skip_base_periods", "filter_time", "lambda",
                      "input_bound", "output_bound", "zoh_correction", "numerator_tolerance"},
                  "finite-frequency");
  const IoRecord& record = *input.record;
  FiniteFrequencyOptions options;
  auto get_int = [&](const char* key, int* out) {
    if (!o.contains(key)) return;
    if (!o[key].is_number_integer()) throw std::invalid_argument(std::string("option '") + key + "' must be an integer");
    *out = o[key].get<int>();
  };
  auto get_double = [&](const char* key, double* out) {
    if (!o.contains(key)) return;
    if (!o[key].is_number()) throw std::invalid_argument(std::string("option '") + key + "' must be a number");
    *out = o[key].get<double>();
  };
  get_int("order", &options.order);
  get_int("numerator_degree", &options.numerator_degree);
  get_double("epsilon_d", &options.epsilon_d);
  get_double("epsilon_k", &options.epsilon_k);
  get_int("consecutive", &options.consecutive);
  get_int("min_base_periods", &options.min_base_periods);
  get_int("max_base_periods", &options.max_base_periods);
  get_int("skip_base_periods", &options.skip_base_periods);
  get_double("filter_time", &options.filter_time);
  get_double("lambda", &options.lambda);
  get_double("input_bound", &options.input_bound);
  get_double("output_bound", &options.output_bound);
  if (options.order < 1) throw std::invalid_argument("finite-frequency needs --order n (>= 1)");
  options.zoh_correction = true;  // a record's input is held between samples (see finite_frequency.h)
  if (o.contains("zoh_correction")) {
    if (!o["zoh_correction"].is_boolean()) throw std::invalid_argument("option 'zoh_correction' must be true or false");
    options.zoh_correction = o["zoh_correction"].get<bool>();
  }
  double base_omega = 0.0;
  std::vector<double> omegas;
  json found_json = nullptr;
  if (!o.contains("base_omega") && !o.contains("frequencies") && !o.contains("multiples")) {
    // Not given: the test signal (5) is found in the record's input (finite_frequency_defaults.h).
    const FoundTestSignal found = FindTestSignal(record.u.col(0), record.sample_time);
    for (size_t k = 0; k < found.phases.size(); ++k)
      if (std::abs(found.phases[k]) > 0.01) {
        std::ostringstream m;
        m << "finite-frequency: the input's line " << k + 1 << " (" << found.signal.Omegas()(k)
          << " rad/s) has phase " << found.phases[k]
          << " rad; the test signal (5) is u = sum rho_k sin(omega_k (t - t0)) with t0 the record's first sample "
             "(zero phases): cut the record to start at t0";
        throw std::invalid_argument(m.str());
      }
    base_omega = found.signal.base_omega;
    const Eigen::VectorXd w = found.signal.Omegas();
    omegas.assign(w.data(), w.data() + w.size());
    found_json = {{"base_omega", base_omega}, {"multiples", found.signal.multiples},
                  {"amplitudes", found.signal.amplitudes}, {"explained_variance", found.explained}};
  } else {
    get_double("base_omega", &base_omega);
    if (!(base_omega > 0.0))
      throw std::invalid_argument("finite-frequency needs --option base_omega=ω_b (rad/s, > 0)");
    if (o.contains("frequencies") == o.contains("multiples"))
      throw std::invalid_argument("finite-frequency needs exactly one of --option frequencies=[ω_1,...] (rad/s) or multiples=[n_1,...]");
    if (o.contains("frequencies")) {
      omegas = Numbers(o, "frequencies");
    } else {
      for (double n : Numbers(o, "multiples")) omegas.push_back(n * base_omega);
    }
  }
  std::vector<double> amplitudes(omegas.size(), 1.0);
  const Eigen::VectorXd omega_vector = Eigen::Map<Eigen::VectorXd>(omegas.data(), omegas.size());
  options.signal = MakeFiniteFrequencySignal(base_omega, omega_vector, amplitudes);
  bool measured_amplitudes = false;
  if (o.contains("amplitudes")) {
    amplitudes = Numbers(o, "amplitudes");
    if (amplitudes.size() == 1) amplitudes.assign(omegas.size(), amplitudes[0]);
    if (amplitudes.size() != omegas.size())
      throw std::invalid_argument("option 'amplitudes' has " + std::to_string(amplitudes.size()) +
                                  " values for " + std::to_string(omegas.size()) + " frequencies");
  } else {
    // ρ_k from the input itself: the filter (6) with unit amplitudes gives α_k = ρ_k for
    // u = Σ ρ_k sin ω_k t (after the (−λ) block for ũ = u e^(λt)).
    const auto u = FourierFilterPerBasePeriod(record.u.col(0), record.sample_time, options.signal,
                                              options.lambda);
    if (u.empty()) throw std::invalid_argument("the record is shorter than one base period");
    for (size_t k = 0; k < omegas.size(); ++k) amplitudes[k] = u.back().alpha[k];
    measured_amplitudes = true;
  }
  options.signal.amplitudes = amplitudes;
  json numerator_table = nullptr;
  if (!o.contains("numerator_degree")) {
    // Not given: the smallest γ < n that fits the frequency equations as well as any.
    double tolerance = 1e-3;
    get_double("numerator_tolerance", &tolerance);
    const NumeratorDegreeChoice choice = ChooseNumeratorDegree(record, options, tolerance);
    options.numerator_degree = choice.numerator_degree;
    numerator_table = json::array();
    for (const auto& row : choice.table)
      numerator_table.push_back({{"numerator_degree", row.numerator_degree},
                                 {"relative_residual", std::isfinite(row.residual) ? json(row.residual) : json(nullptr)},
                                 {"status", row.status}});
  }
  const FiniteFrequencyResult r = IdentifyFiniteFrequency(record, options);

  MethodReport report;
  report.expect_stable = !(options.lambda > 0.0);  // (31)–(35): an unstable plant on purpose
  json& j = report.json;
  j["model"] = ModelToJson(r.model);
  j["status"] = ToString(r.status);
  j["message"] = r.message;
  j["fit_percent"] = std::isnan(r.fit_percent) ? json(nullptr) : json(r.fit_percent);
  json d;
  d["d"] = Vec(r.d);
  d["k"] = Vec(r.k);
  d["base_omega"] = base_omega;
  d["test_frequencies"] = omegas;
  d["multiples"] = options.signal.multiples;
  d["amplitudes"] = amplitudes;
  d["amplitudes_measured_from_input"] = measured_amplitudes;
  d["base_periods"] = r.base_periods;
  d["tau"] = r.tau;
  d["stopping_rule_met"] = r.stopping_rule_met;
  d["bound_reached"] = r.bound_reached;
  d["relative_frequency_residual"] = r.final_cost;
  d["zoh_correction"] = options.zoh_correction;
  d["numerator_degree"] = options.numerator_degree;
  d["numerator_degree_chosen"] = !numerator_table.is_null();
  if (!numerator_table.is_null()) d["numerator_table"] = numerator_table;
  d["test_signal_found"] = !found_json.is_null();
  if (!found_json.is_null()) d["found_test_signal"] = found_json;
  json history = json::array();
  for (const auto& e : r.history)
    history.push_back({{"q", e.base_periods}, {"tau", e.tau}, {"alpha", Vec(e.alpha)},
                       {"beta", Vec(e.beta)}, {"d", Vec(e.d)}, {"k", Vec(e.k)},
                       {"rule_met", e.rule_met}});
  d["history"] = history;
  j["details"] = d;
  std::ostringstream t;
  t.precision(6);
  t << "finite-frequency identification [Aleksandrov]: " << r.message << "\n";
  t << "  d_1..d_n:";
  for (int i = 0; i < r.d.size(); ++i) t << " " << r.d[i];
  t << "\n  k_0..k_g:";
  for (int i = 0; i < r.k.size(); ++i) t << " " << r.k[i];
  t << "\n";
  report.text = t.str();
  return report;
}

}  // namespace

std::vector<MethodInfo> FiniteFrequencyMethods() {
  return {{"finite-frequency",
           "finite-frequency identification from a multisine test (seed 003): options "
           "numerator_degree, base_omega, frequencies|multiples, amplitudes",
           true, [](const MethodInput& in, const json& o) { return Run(in, o); }}};
}

}  // namespace idrig
