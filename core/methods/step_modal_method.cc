// `step-prony`: seed 000 (Vidinčev) on a SISO step-response record t,u,y.
//   idrig identify --data step.csv --method step-prony [--order 4] [--option averaging=block] --json
// Options: order, max_order, spacing (samples per h), blocks (B), averaging (none|block|integral),
// solver (qr|tls|subspace), columns, x_inf, tail_fraction, settle_tolerance, horizon_factor,
// max_cluster_distance, refine, sliding, refit_x_inf.
//
// `modal-polyref`: seed 002 section 5 (Balda) on a MIMO record t,u1..,y1..: the impulse-response
// matrices G(kT) are first estimated by regularised FIR least squares (ridge by GCV), then the
// modes are identified from them.
//   idrig identify --data mimo.csv --method modal-polyref [--option modes=3] --json
// Options: fir_length, lambda, modes, p, p_min, p_max, first_sample, max_damping,
// max_frequency_hz, frequency_tolerance, damping_tolerance, min_stable_orders, min_stable_fraction,
// als_iterations.
#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/io/model_json.h"
#include "core/methods/registry.h"
#include "core/numeric/time_domain/modal_polyref.h"
#include "core/numeric/time_domain/step_prony.h"
#include "core/numeric/validation.h"

namespace idrig {
namespace {

using nlohmann::json;
using cd = std::complex<double>;

json Vec(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }
json Cx(cd c) { return json::array({c.real(), c.imag()}); }
json CVec(const Eigen::VectorXcd& v) {
  json out = json::array();
  for (int i = 0; i < v.size(); ++i) out.push_back(Cx(v(i)));
  return out;
}
json Mat(const Eigen::MatrixXd& m) {
  json rows = json::array();
  for (int r = 0; r < m.rows(); ++r) rows.push_back(Vec(m.row(r).transpose()));
  return rows;
}

struct Options {
  const json& o;
  void Int(const char* key, int* out) const {
    if (!o.contains(key)) return;
    if (!o[key].is_number_integer()) throw std::invalid_argument(std::string("option '") + key + "' must be an integer");
    *out = o[key].get<int>();
  }
  void Double(const char* key, double* out) const {
    if (!o.contains(key)) return;
    if (!o[key].is_number()) throw std::invalid_argument(std::string("option '") + key + "' must be a number");
    *out = o[key].get<double>();
  }
  void Bool(const char* key, bool* out) const {
    if (!o.contains(key)) return;
    if (o[key].is_boolean()) *out = o[key].get<bool>();
    else if (o[key].is_number_integer()) *out = o[key].get<int>() != 0;
    else throw std::invalid_argument(std::string("option '") + key + "' must be true or false");
  }
  std::string Word(const char* key, const std::string& fallback) const {
    if (!o.contains(key)) return fallback;
    if (!o[key].is_string()) throw std::invalid_argument(std::string("option '") + key + "' must be a word");
    return o[key].get<std::string>();
  }
};

std::string Complex(cd c) {
  std::ostringstream s;
  s << std::setprecision(6) << c.real() << (c.imag() < 0 ? " - " : " + ") << std::abs(c.imag()) << "j";
  return s.str();
}

MethodReport RunStepProny(const MethodInput& input, const json& o) {
  CheckOptionKeys(o, {"order", "max_order", "spacing", "blocks", "averaging", "solver", "columns", "x_inf",
                      "tail_fraction", "settle_tolerance", "horizon_factor", "max_cluster_distance", "refine",
                      "sliding", "refit_x_inf"},
                  "step-prony");
  const Options get{o};
  StepPronyOptions options;
  get.Int("order", &options.order);
  get.Int("max_order", &options.max_order);
  get.Int("spacing", &options.spacing);
  get.Int("blocks", &options.blocks);
  get.Int("columns", &options.columns);
  get.Double("x_inf", &options.x_inf);
  get.Double("tail_fraction", &options.tail_fraction);
  get.Double("settle_tolerance", &options.settle_tolerance);
  get.Double("horizon_factor", &options.horizon_factor);
  get.Double("max_cluster_distance", &options.max_cluster_distance);
  get.Bool("refine", &options.refine);
  get.Bool("sliding", &options.sliding);
  get.Bool("refit_x_inf", &options.refit_x_inf);
  const std::string averaging = get.Word("averaging", "block");
  if (averaging == "none") options.averaging = StepAveraging::kNone;
  else if (averaging == "block") options.averaging = StepAveraging::kBlock;
  else if (averaging == "integral") options.averaging = StepAveraging::kIntegral;
  else throw std::invalid_argument("option 'averaging' must be none, block or integral (got '" + averaging + "')");
  const std::string solver = get.Word("solver", "subspace");
  if (solver == "qr") options.solver = StepLpSolver::kQr;
  else if (solver == "tls") options.solver = StepLpSolver::kTls;
  else if (solver == "subspace") options.solver = StepLpSolver::kSubspace;
  else throw std::invalid_argument("option 'solver' must be qr, tls or subspace (got '" + solver + "')");

  const StepPronyResult r = IdentifyStepResponse(*input.record, options);
  MethodReport report;
  json& j = report.json;
  j["model"] = ModelToJson(r.tf);
  j["status"] = ToString(r.status);
  j["message"] = r.message;
  j["fit_percent"] = r.fit_percent;
  json d;
  d["order"] = r.order;
  json poles = json::array();
  for (const auto& p : r.poles) {
    poles.push_back({{"pole", Cx(p.Pole())},
                     {"b", Cx(p.b)},
                     {"multiplicity", p.multiplicity},
                     {"complex_pair", p.complex_pair},
                     {"natural_frequency_rad_s", p.NaturalFrequency()},
                     {"damping_ratio", p.DampingRatio()},
                     {"residues", CVec(p.residues)},
                     {"residues_eq20", CVec(p.residues_eq20)},
                     {"residues_least_squares", CVec(p.residues_ls)}});
  }
  d["poles"] = poles;
  d["pole_residue_form"] = "K(p) = sum_v sum_j A_vj / (p + b_v)^(N_v + 1 - j), Eq. (1); pole = -b";
  d["residue_method"] = r.residue_method;
  d["residue_rss"] = {{"eq20", r.residue_rss_eq20}, {"least_squares", r.residue_rss_ls}};
  d["residue_condition_number"] = {{"eq20", r.residue_condition_eq20}, {"least_squares", r.residue_condition_ls}};
  d["lp_coefficients_D"] = Vec(r.lp_coefficients);
  d["lp_condition_number"] = r.lp_condition_number;
  d["lp_equations"] = r.lp_equations;
  d["lp_roots_z"] = CVec(r.roots_z);
  d["lp_poles"] = CVec(r.lp_poles);
  d["refined"] = r.refined;
  d["cluster_tolerance_z"] = r.cluster_tolerance;
  json table = json::array();
  for (const auto& row : r.order_table)
    table.push_back({{"order", row.order}, {"lp_residual", row.residual}, {"condition_number", row.condition_number},
                     {"fit_rss", row.fit_rss}, {"chosen", row.order == r.order}});
  d["order_table"] = table;
  d["h_s"] = r.h;
  d["spacing_samples"] = r.spacing;
  d["blocks_B"] = r.blocks;
  d["averaging"] = ToString(r.averaging);
  d["solver"] = ToString(r.solver);
  d["step_amplitude"] = r.step_amplitude;
  d["step_time_s"] = r.step_time;
  d["x_inf"] = r.x_inf;
  d["x_inf_tail"] = r.x_inf_tail;
  d["x_inf_model"] = r.x_inf_model;
  d["noise_sigma"] = r.noise_sigma;
  d["state_space"] = ModelToJson(ToStateSpace(r.tf));
  d["warnings"] = r.warnings;
  j["details"] = d;

  std::ostringstream t;
  t << std::setprecision(6);
  t << "Step response, multiple poles (seed 000, Vidincev): " << r.message << ", solver status " << ToString(r.status) << "\n";
  t << "step C = " << r.step_amplitude << " at t = " << r.step_time << " s; x(inf) = " << r.x_inf << " (tail "
    << r.x_inf_tail << ", model " << r.x_inf_model << "); h = " << r.h << " s, B = " << r.blocks << ", averaging "
    << ToString(r.averaging) << ", solver " << ToString(r.solver) << "\n";
  if (!r.order_table.empty()) {
    t << "\norder  LP residual (38)   cond       fit RSS\n";
    for (const auto& row : r.order_table)
      t << std::setw(5) << row.order << "  " << std::setw(14) << row.residual << "  " << std::setw(10)
        << row.condition_number << "  " << std::setw(12) << row.fit_rss << (row.order == r.order ? "   <- chosen" : "")
        << "\n";
  }
  t << "\npoles (pole = -b, multiplicity, residues A_v1..A_vN):\n";
  for (const auto& p : r.poles) {
    t << "  " << Complex(p.Pole()) << (p.complex_pair ? " (and conjugate)" : "") << "  x" << p.multiplicity << "  A:";
    for (int i = 0; i < p.residues.size(); ++i) t << " " << Complex(p.residues(i));
    t << "\n";
  }
  t << "residues by " << r.residue_method << " (RSS eq20 " << r.residue_rss_eq20 << ", least squares "
    << r.residue_rss_ls << ")\n";
  t << "fit (100(1-NRMSE)) " << r.fit_percent << " %\n";
  for (const auto& w : r.warnings) t << "warning: " << w << "\n";
  report.text = t.str();
  return report;
}

MethodReport RunModalPolyref(const MethodInput& input, const json& o) {
  CheckOptionKeys(o, {"order", "fir_length", "lambda", "modes", "p", "p_min", "p_max", "first_sample", "max_damping",
                      "max_frequency_hz", "frequency_tolerance", "damping_tolerance", "min_stable_orders",
                      "min_stable_fraction", "als_iterations"},
                  "modal-polyref");
  const Options get{o};
  const IoRecord& record = *input.record;
  ModalPolyrefOptions options;
  get.Int("modes", &options.modes);
  int order = 0;  // --order N: N/2 modes (state dimension)
  get.Int("order", &order);
  if (order > 0 && options.modes == 0) options.modes = (order + 1) / 2;
  get.Int("p", &options.p);
  get.Int("p_min", &options.p_min);
  get.Int("p_max", &options.p_max);
  get.Int("first_sample", &options.first_sample);
  get.Double("max_damping", &options.max_damping);
  get.Double("max_frequency_hz", &options.max_frequency_hz);
  get.Double("frequency_tolerance", &options.frequency_tolerance);
  get.Double("damping_tolerance", &options.damping_tolerance);
  get.Int("min_stable_orders", &options.min_stable_orders);
  get.Double("min_stable_fraction", &options.min_stable_fraction);
  get.Int("als_iterations", &options.als_iterations);
  int fir_length = std::min(200, record.NumSamples() / (3 * std::max(1, record.NumInputs())));
  get.Int("fir_length", &fir_length);
  double lambda = 0.0;
  get.Double("lambda", &lambda);

  const FirEstimate fir = EstimateImpulseResponseFir(record, fir_length, lambda);
  ModalPolyrefResult r = IdentifyModalPolyref(fir.impulse_responses, record.sample_time, options);
  r.impulse_response_source = fir.method;
  if (r.modes.empty())
    throw std::invalid_argument("modal-polyref: no oscillatory pole with 0 < zeta <= max_damping in the band at any "
                                "order p; the record shows no resonance (try max_damping, max_frequency_hz, p_max)");
  const StateSpace model = ModalStateSpace(r, options.first_sample);
  double fit = 0.0;
  Eigen::VectorXd fits;
  if (!r.modes.empty()) {
    const Eigen::MatrixXd y = Simulate(model, record.u, record.sample_time);
    fits = FitPercent(record.y, y);
    fit = fits.mean();
  }

  MethodReport report;
  json& j = report.json;
  j["model"] = ModelToJson(model);
  j["status"] = ToString(r.status);
  j["message"] = r.message + "; G(kT) estimated by " + fir.method;
  j["fit_percent"] = fit;
  json d;
  d["impulse_response_source"] = r.impulse_response_source;
  d["fir"] = {{"length", fir_length}, {"lambda", fir.lambda}, {"condition_number", fir.condition_number},
              {"fit_percent", fir.fit_percent}};
  d["outputs"] = r.outputs;
  d["inputs"] = r.inputs;
  d["p"] = r.p;
  d["p_eq42"] = r.p_eq42;
  d["excitation_condition_number"] = r.excitation_condition_number;
  d["impulse_fit_percent"] = r.fit_percent_impulse;
  d["simulation_fit_percent_per_output"] = fits.size() ? Vec(fits) : json::array();
  json modes = json::array();
  for (const auto& m : r.modes)
    modes.push_back({{"s", Cx(m.s)},
                     {"natural_frequency_hz", m.natural_frequency_hz},
                     {"natural_frequency_rad_s", m.natural_frequency_rad_s},
                     {"damping_ratio", m.damping_ratio},
                     {"orders_found", m.orders_found},
                     {"shape", CVec(m.shape)},
                     {"participation", CVec(m.participation)}});
  d["modes"] = modes;
  d["mac"] = Mat(r.mac);
  json diagram = json::array();
  for (const auto& pt : r.stabilisation)
    diagram.push_back({{"p", pt.p}, {"frequency_hz", pt.frequency_hz}, {"damping_ratio", pt.damping_ratio},
                       {"stable_frequency", pt.stable_frequency}, {"stable", pt.stable}});
  d["stabilisation_diagram"] = diagram;
  d["eigenvalues_z"] = CVec(r.eigenvalues_z);
  d["warnings"] = r.warnings;
  j["details"] = d;

  std::ostringstream t;
  t << std::setprecision(6);
  t << "MIMO modal identification from impulse responses (seed 002 section 5, Balda): " << r.message << ", solver status "
    << ToString(r.status) << "\n";
  t << "G(kT) (" << r.outputs << " outputs x " << r.inputs << " inputs, " << fir_length << " samples) estimated by "
    << fir.method << " (FIR fit " << fir.fit_percent << " %)\n\n";
  t << "mode   f [Hz]      zeta       orders  shape (|v|)\n";
  for (size_t i = 0; i < r.modes.size(); ++i) {
    const Mode& m = r.modes[i];
    t << std::setw(4) << i + 1 << "  " << std::setw(10) << m.natural_frequency_hz << "  " << std::setw(10)
      << m.damping_ratio << "  " << std::setw(6) << m.orders_found << " ";
    for (int k = 0; k < m.shape.size(); ++k) t << " " << std::abs(m.shape(k));
    t << "\n";
  }
  t << "\nMAC:\n";
  for (int i = 0; i < r.mac.rows(); ++i) {
    t << "  ";
    for (int k = 0; k < r.mac.cols(); ++k) t << std::fixed << std::setw(9) << std::setprecision(4) << r.mac(i, k);
    t << "\n";
  }
  t << std::defaultfloat << std::setprecision(6) << "\nstabilisation diagram: " << r.stabilisation.size() << " candidate poles over p = "
    << options.p_min << ".." << r.p << " (JSON details.stabilisation_diagram)\n";
  t << "simulation fit of the modal model on the record: " << fit << " %\n";
  for (const auto& w : r.warnings) t << "warning: " << w << "\n";
  report.text = t.str();
  return report;
}

}  // namespace

std::vector<MethodInfo> StepModalMethods() {
  return {
      {"step-prony", "continuous model with multiple complex poles from a step response (seed 000, Vidincev)", true,
       RunStepProny},
      {"modal-polyref",
       "MIMO modes (f, zeta, shapes, MAC, stabilisation) from impulse responses estimated by FIR (seed 002 sec. 5)",
       true, RunModalPolyref},
  };
}

}  // namespace idrig
