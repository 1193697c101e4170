// `arx` and `arx-oe`: seed 001's regularised ARX with all five equivalent forms.
#include <iomanip>
#include <sstream>

#include "core/io/model_json.h"
#include "core/methods/registry.h"
#include "core/methods/report_json.h"
#include "core/numeric/time_domain/arx.h"

namespace idrig {
namespace {

using nlohmann::json;

using report_json::Complex;
using report_json::Mat;
using report_json::Vec;

std::string Row(const Eigen::MatrixXd& m) {
  std::ostringstream s;
  s << std::setprecision(6);
  for (int r = 0; r < m.rows(); ++r) {
    s << "    [";
    for (int c = 0; c < m.cols(); ++c) s << (c ? ", " : "") << std::setw(12) << m(r, c);
    s << "]\n";
  }
  return s.str();
}

std::string Poly(const Eigen::VectorXd& p, const char* var) {
  std::ostringstream s;
  s << std::setprecision(6);
  const int deg = static_cast<int>(p.size()) - 1;
  bool first = true;
  for (int i = 0; i <= deg; ++i) {
    const int power = deg - i;
    if (p(i) == 0.0 && deg > 0) continue;
    s << (first ? (p(i) < 0 ? "-" : "") : (p(i) < 0 ? " - " : " + ")) << std::abs(p(i));
    if (power >= 1) s << " " << var;
    if (power >= 2) s << "^" << power;
    first = false;
  }
  return first ? "0" : s.str();
}

constexpr int kMaxLogSeriesTerms = 10000;
constexpr int kMaxOeIterations = 1000;

ArxOptions ParseOptions(const json& o, bool output_error) {
  CheckOptionKeys(o, {"order", "max_order", "input_delay", "decimation", "first_equation",
                      "max_equations", "epsilon", "oe_iterations", "oe_tolerance", "log_series_terms"},
                  output_error ? "arx-oe" : "arx");
  ArxOptions options;
  auto get_int = [&](const char* key, int* out) {
    if (!o.contains(key)) return;
    if (!o[key].is_number_integer()) throw std::invalid_argument(std::string("option '") + key + "' must be an integer");
    *out = o[key].get<int>();
  };
  get_int("order", &options.order);
  get_int("max_order", &options.max_order);
  get_int("input_delay", &options.input_delay);
  get_int("decimation", &options.decimation);
  get_int("first_equation", &options.first_equation);
  get_int("max_equations", &options.max_equations);
  get_int("log_series_terms", &options.log_series_terms);
  options.oe_iterations = output_error ? 30 : 0;
  get_int("oe_iterations", &options.oe_iterations);
  // Without a bound, one request held a worker for hours: log_series_terms = 2^31 - 1 matrix
  // products (the automatic summation stops at 10 000 terms), or as many output-error fits.
  if (options.log_series_terms > kMaxLogSeriesTerms)
    throw std::invalid_argument("option 'log_series_terms' must be <= " +
                                std::to_string(kMaxLogSeriesTerms) + " (got " +
                                std::to_string(options.log_series_terms) + ")");
  if (options.oe_iterations > kMaxOeIterations)
    throw std::invalid_argument("option 'oe_iterations' must be <= " +
                                std::to_string(kMaxOeIterations) + " (got " +
                                std::to_string(options.oe_iterations) + ")");
  if (o.contains("oe_tolerance")) {
    if (!o["oe_tolerance"].is_number() || !(o["oe_tolerance"].get<double>() > 0.0))
      throw std::invalid_argument("option 'oe_tolerance' must be a positive number");
    options.oe_tolerance = o["oe_tolerance"].get<double>();
  }
  if (o.contains("epsilon")) {
    if (!o["epsilon"].is_number()) throw std::invalid_argument("option 'epsilon' must be a number");
    options.epsilon = o["epsilon"].get<double>();
  }
  return options;
}

MethodReport Run(const MethodInput& input, const json& options_json, bool output_error) {
  const ArxOptions options = ParseOptions(options_json, output_error);
  const ArxResult r = IdentifyArx(*input.record, options);
  MethodReport report;
  json& j = report.json;
  const TransferFunction& best = r.continuous_recovered ? r.continuous_tf : r.discrete_tf;
  j["model"] = ModelToJson(best);
  j["status"] = ToString(r.status);
  j["message"] = r.message;
  j["fit_percent"] = r.fit_percent;
  json d;
  d["order"] = r.order;
  d["input_delay_samples"] = r.input_delay;
  d["equations"] = r.equations;
  d["epsilon"] = r.epsilon;
  d["epsilon_rule"] = r.epsilon_rule;
  d["condition_number"] = r.condition_number;
  d["iterations"] = r.iterations;
  if (output_error) d["oe_relative_change"] = r.oe_relative_change;
  d["g"] = Vec(r.g);
  d["g_std"] = Vec(r.g_std);
  d["covariance"] = Mat(r.covariance);
  d["noise_variance"] = r.noise_variance;
  d["difference_equation"] = {{"c", Vec(r.c)}, {"d", Vec(r.d)}, {"text", r.DifferenceEquation()}};
  d["discrete_tf"] = ModelToJson(r.discrete_tf);
  d["difference_system_Rd1"] = {{"Phi", Mat(r.discrete_compact.A)}, {"Gamma", Vec(r.discrete_compact.B)}};
  d["discrete_poles"] = Complex(Poles(r.discrete_tf));
  d["y_inf_eq_2_4"] = r.y_inf_sum;
  d["y_inf_eq_1_15"] = r.y_inf_matrix;
  d["continuous_recovered"] = r.continuous_recovered;
  if (r.continuous_recovered) {
    d["continuous_tf"] = ModelToJson(r.continuous_tf);
    d["cauchy_form_R1"] = {{"A", Mat(r.continuous_compact.A)}, {"B", Vec(r.continuous_compact.B)},
                           {"H", Vec(r.continuous_compact.H.transpose())}};
    d["continuous_poles"] = Complex(Poles(r.continuous_tf));
    d["log_series"] = {{"terms", r.log_series.terms}, {"spectral_radius_x", r.log_series.spectral_radius_x},
                       {"tail_bound", r.log_series.tail_bound},
                       {"difference_from_eigen_log", r.log_series.truncation_error}};
  } else {
    d["continuous_message"] = r.continuous_message;
  }
  d["residuals"] = {{"white", r.residuals.white}, {"independent_of_input", r.residuals.independent},
                    {"ljung_box_q", r.residuals.portmanteau_q}, {"ljung_box_threshold", r.residuals.portmanteau_threshold},
                    {"cross_q", r.residuals.cross_q}, {"cross_threshold", r.residuals.cross_threshold},
                    {"band", r.residuals.band}};
  json table = json::array();
  for (const auto& c : r.order_table)
    table.push_back({{"order", c.order}, {"validation_nrmse", c.validation_nrmse}, {"mdl", c.mdl}, {"epsilon", c.epsilon}});
  d["order_table"] = table;
  d["warnings"] = r.warnings;
  j["details"] = d;

  std::ostringstream t;
  t << std::setprecision(6);
  t << (output_error ? "ARX + output-error refinement" : "Regularised ARX") << " (seed 001, Eqs. (2.7)-(2.11)): "
    << r.message << ", solver status " << ToString(r.status) << "\n";
  if (!r.order_table.empty()) {
    t << "\nOrder selection (simulation NRMSE on the held-out last third):\n";
    for (const auto& c : r.order_table)
      t << "  n = " << c.order << "  NRMSE " << c.validation_nrmse << (c.order == r.order ? "   <- chosen" : "") << "\n";
  }
  t << "\ncondition number of F_L " << r.condition_number << "; epsilon " << r.epsilon << " (" << r.epsilon_rule << ")\n";
  t << "\n1. Difference equation (2.1):\n    " << r.DifferenceEquation() << "\n";
  t << "   parameter std (g = (-c; d)):";
  for (int i = 0; i < r.g_std.size(); ++i) t << " " << r.g_std(i);
  t << "\n\n2. W(z) (1.14), Ts = " << r.sample_time << " s:\n    (" << Poly(r.discrete_tf.num, "z") << ") / ("
    << Poly(r.discrete_tf.den, "z") << ")\n";
  t << "\n3. Difference system Rd1 (1.12)-(1.13): x[k+1] = Phi1 x[k] + Gamma1 u[k], y = (1 0 ... 0) x\n  Phi1 =\n"
    << Row(r.discrete_compact.A) << "  Gamma1' =\n" << Row(r.discrete_compact.B.transpose());
  if (r.continuous_recovered) {
    t << "\n4. Cauchy form R1* (1.7), from R* by the log series (1.16) (" << r.log_series.terms
      << " terms, |series - logm| = " << r.log_series.truncation_error << "):\n  A =\n"
      << Row(r.continuous_compact.A) << "  B' =\n" << Row(r.continuous_compact.B.transpose());
    t << "\n5. W(p) (1.2):\n    (" << Poly(r.continuous_tf.num, "s") << ") / (" << Poly(r.continuous_tf.den, "s") << ")";
    if (r.continuous_tf.delay_s > 0) t << " * exp(-" << r.continuous_tf.delay_s << " s)";
    t << "\n    poles:";
    const Eigen::VectorXcd p = Poles(r.continuous_tf);
    for (int i = 0; i < p.size(); ++i) t << " " << p(i).real() << (p(i).imag() < 0 ? "-" : "+") << std::abs(p(i).imag()) << "j";
    t << "\n";
  } else {
    t << "\n4-5. No continuous model: " << r.continuous_message << "\n";
  }
  t << "\ny(inf): " << r.y_inf_sum << " by (2.4), " << r.y_inf_matrix << " by (1.15)\n";
  t << "fit (simulation, 100(1-NRMSE)): " << r.fit_percent << " %\n" << r.residuals.Summary() << "\n";
  for (const auto& w : r.warnings) t << "warning: " << w << "\n";
  report.text = t.str();
  return report;
}

}  // namespace

std::vector<MethodInfo> ArxMethods() {
  return {
      {"arx", "regularised least-squares ARX, all five forms, continuous model (seed 001)", true,
       [](const MethodInput& in, const json& o) { return Run(in, o, false); }},
      {"arx-oe", "ARX refined to output error by Steiglitz-McBride iterations (unbiased under output noise)", true,
       [](const MethodInput& in, const json& o) { return Run(in, o, true); }},
  };
}

}  // namespace idrig
