// Frequency-domain methods of seed 002 ([Balda], sections 2–4) on an FRF file or a time record:
//   idrig identify --method levy-sk      --data frf.csv --order 4 [--option numerator_degree=3]
//   idrig identify --method stable-nls   --data frf.csv --order 4 [--option square_numerator=false]
//   idrig identify --method pole-residue --data frf.csv [--option peak_tolerance=0.05]
//                                                        [--option "peaks_hz=[11.4,16.6]"]
//   idrig identify --method mbk          --data frf.csv [--option variant=difference]
// --data: an FRF table (core/io/frf_csv.h: f_hz,re,im or re_<o>_<i>/im_<o>_<i> pairs), or a
// time record t,u…,y… (csv.h), whose FRF is estimated first: H1/Welch (options
// segment_length, overlap) or, with period_samples, the periodic estimator.
// Common options: output, input (1-based element of a MIMO FRF for the SISO methods),
// f_min_hz, f_max_hz (band), weight ("auto" (default): "inverse_std" when the FRF carries a
// variance — a sigma column, period averaging, Welch's coherence — else "none" | "f" as in
// Balda's listing | "inverse_std" | "inverse_magnitude" for noise relative to |H|).
#include <cmath>
#include <sstream>

#include "core/io/csv.h"
#include "core/io/frf_csv.h"
#include "core/io/model_json.h"
#include "core/methods/registry.h"
#include "core/numeric/frequency_domain/mbk.h"
#include "core/numeric/frequency_domain/pole_residue.h"
#include "core/numeric/frequency_domain/stable_nls.h"

namespace idrig {
namespace {

using nlohmann::json;
constexpr double kPi = 3.14159265358979323846;

const std::vector<std::string> kCommonKeys = {"output", "input", "f_min_hz", "f_max_hz", "weight",
                                              "segment_length", "overlap", "period_samples",
                                              "skip_periods", "zoh_correction"};

std::vector<std::string> Keys(std::vector<std::string> extra) {
  extra.insert(extra.end(), kCommonKeys.begin(), kCommonKeys.end());
  return extra;
}

double GetDouble(const json& o, const char* key, double fallback) {
  if (!o.contains(key)) return fallback;
  if (!o[key].is_number()) throw std::invalid_argument(std::string("option '") + key + "' must be a number");
  return o[key].get<double>();
}
int GetInt(const json& o, const char* key, int fallback) {
  if (!o.contains(key)) return fallback;
  if (!o[key].is_number_integer()) throw std::invalid_argument(std::string("option '") + key + "' must be an integer");
  return o[key].get<int>();
}
bool GetBool(const json& o, const char* key, bool fallback) {
  if (!o.contains(key)) return fallback;
  if (!o[key].is_boolean()) throw std::invalid_argument(std::string("option '") + key + "' must be true or false");
  return o[key].get<bool>();
}

struct LoadedFrf {
  Frf frf;
  std::string source;  // "frf-file", "welch", "periodic"
  double sample_time = 0.0;  // of the time record the FRF was estimated from (0: an FRF file)
  bool zoh_corrected = false;
};

// Reads the FRF file, or estimates the FRF from a time record; restricts to the band.
LoadedFrf Load(const MethodInput& input, const json& o) {
  LoadedFrf out;
  if (IsTimeRecordCsv(input.path)) {
    const IoRecord record = ReadIoRecordCsv(input.path);
    out.sample_time = record.sample_time;
    if (o.contains("period_samples")) {
      PeriodicOptions p;
      p.period_samples = GetInt(o, "period_samples", 0);
      p.skip_periods = GetInt(o, "skip_periods", 1);
      out.frf = EstimateFrfPeriodic(record, p);
      out.source = "periodic";
    } else {
      WelchOptions w;
      w.segment_length = GetInt(o, "segment_length", 0);
      w.overlap = GetDouble(o, "overlap", 0.5);
      out.frf = EstimateFrfWelch(record, w);
      out.source = "welch";
    }
    // The record's input is held between samples (a rig's actuator, `idrig simulate`): the FRF
    // of the samples is that of w(s)·Z(s), Z(jω) = e^(−jωTs/2)·sin(ωTs/2)/(ωTs/2), a
    // half-sample delay that a continuous low-order model can only mimic with a pole pair near
    // Nyquist. Divided out per line (variance by |Z|²); the aliases of the hold remain.
    if (GetBool(o, "zoh_correction", true)) {
      for (int k = 0; k < out.frf.NumLines(); ++k) {
        const double x = 0.5 * out.frf.omega(k) * record.sample_time;
        const std::complex<double> z =
            std::polar(x > 1e-12 ? std::sin(x) / x : 1.0, -x);
        out.frf.h[k] /= z;
        if (out.frf.variance.size()) out.frf.variance.row(k) /= std::norm(z);
      }
      out.zoh_corrected = true;
    }
  } else {
    out.frf = ReadFrfCsv(input.path);
    out.source = "frf-file";
  }
  const double lo = GetDouble(o, "f_min_hz", -1.0) * 2 * kPi, hi = GetDouble(o, "f_max_hz", 1e300) * 2 * kPi;
  if (o.contains("f_min_hz") || o.contains("f_max_hz")) {
    Frf band;
    std::vector<double> w;
    std::vector<int> keep;
    for (int k = 0; k < out.frf.NumLines(); ++k)
      if (out.frf.omega(k) >= lo && out.frf.omega(k) <= hi) keep.push_back(k);
    if (keep.empty()) throw std::invalid_argument("no FRF line lies within [f_min_hz, f_max_hz]");
    band.omega.resize(keep.size());
    for (size_t i = 0; i < keep.size(); ++i) {
      band.omega(i) = out.frf.omega(keep[i]);
      band.h.push_back(out.frf.h[keep[i]]);
    }
    if (out.frf.variance.size()) {
      band.variance.resize(keep.size(), out.frf.variance.cols());
      for (size_t i = 0; i < keep.size(); ++i) band.variance.row(i) = out.frf.variance.row(keep[i]);
    }
    band.averages = out.frf.averages;
    out.frf = band;
  }
  return out;
}

// The SISO element asked for, without the DC line; weights as asked. The default ("auto") is
// maximum likelihood when the FRF carries a noise variance per line (a sigma column, averaging
// over periods, or Welch's coherence): w_k = 1/σ_k, so that Σ w_k²|r_k|² is the negative
// log-likelihood of complex Gaussian noise; otherwise no weights. `*used` names the choice.
Frf SisoElement(const Frf& frf, const json& o, Eigen::VectorXd* weights, std::string* used = nullptr,
                const std::string& default_weight = "auto") {
  const int out = GetInt(o, "output", 1), in = GetInt(o, "input", 1);
  if (out < 1 || out > frf.NumOutputs() || in < 1 || in > frf.NumInputs())
    throw std::invalid_argument("output/input " + std::to_string(out) + "/" + std::to_string(in) +
                                " outside the FRF's " + std::to_string(frf.NumOutputs()) + "x" +
                                std::to_string(frf.NumInputs()));
  std::vector<int> keep;
  for (int k = 0; k < frf.NumLines(); ++k)
    if (frf.omega(k) > 0.0) keep.push_back(k);
  Eigen::VectorXd w(keep.size());
  Eigen::VectorXcd h(keep.size());
  Eigen::VectorXd wt = Eigen::VectorXd::Ones(keep.size());
  const char* kChoices = "option 'weight' must be auto, none, f, inverse_std or inverse_magnitude";
  if (o.contains("weight") && !o["weight"].is_string()) throw std::invalid_argument(kChoices);
  std::string weight = o.contains("weight") ? o["weight"].get<std::string>() : default_weight;
  if (weight == "auto") weight = frf.variance.size() ? "inverse_std" : "none";
  const int element = (out - 1) + frf.NumOutputs() * (in - 1);
  // A zero variance (a noise-free line, coherence 1) would give an infinite weight: floor it at
  // 10^-12 of the largest variance of the element.
  double floor = 0.0;
  if (weight == "inverse_std") {
    if (!frf.variance.size()) throw std::invalid_argument("weight=inverse_std needs an FRF with a variance (time record input)");
    for (int k : keep) floor = std::max(floor, frf.variance(k, element));
    floor *= 1e-12;
    if (!(floor > 0.0)) weight = "none";  // every line noise-free: nothing to weight by
  }
  for (size_t i = 0; i < keep.size(); ++i) {
    w(i) = frf.omega(keep[i]);
    h(i) = frf.h[keep[i]](out - 1, in - 1);
    if (weight == "f") wt(i) = w(i) / (2 * kPi);
    else if (weight == "inverse_magnitude") {
      if (!(std::abs(h(i)) > 0.0))
      {
        std::ostringstream m;
        m << "weight=inverse_magnitude: |H| is 0 at " << w(i) / (2 * kPi) << " Hz";
        throw std::invalid_argument(m.str());
      }
      wt(i) = 1.0 / std::abs(h(i));
    }
    else if (weight == "inverse_std") {
      wt(i) = 1.0 / std::sqrt(std::max(frf.variance(keep[i], element), floor));
    } else if (weight != "none") {
      throw std::invalid_argument(kChoices);
    }
  }
  *weights = wt.allFinite() ? wt : Eigen::VectorXd();
  if (weight == "none") *weights = Eigen::VectorXd();
  if (used) *used = weight;
  return MakeSisoFrf(w, h);
}

json NullIfNan(double v) { return std::isnan(v) ? json(nullptr) : json(v); }

json Complexes(const Eigen::VectorXcd& v) {
  json a = json::array();
  for (int i = 0; i < v.size(); ++i) a.push_back({v(i).real(), v(i).imag()});
  return a;
}

MethodReport Rational(const MethodInput& input, const json& o, bool stable) {
  const char* name = stable ? "stable-nls" : "levy-sk";
  CheckOptionKeys(o, Keys({"order", "numerator_degree", "sk_iterations", "square_numerator",
                           "max_function_evaluations", "refine"}), name);
  const int n = GetInt(o, "order", 0);
  if (n < 1) throw std::invalid_argument(std::string(name) + " needs --order n (denominator degree, >= 1)");
  const int m = GetInt(o, "numerator_degree", n - 1);
  const LoadedFrf loaded = Load(input, o);
  Eigen::VectorXd weights;
  std::string weight_used;
  const Frf frf = SisoElement(loaded.frf, o, &weights, &weight_used);
  MethodReport report;
  report.record_sample_time = loaded.sample_time;
  json& j = report.json;
  json d;
  d["weight"] = weight_used;
  TransferFunction model;
  Eigen::VectorXcd poles;
  std::ostringstream t;
  t.precision(6);
  if (!stable) {
    LevyOptions lo;
    lo.denominator_degree = n;
    lo.numerator_degree = m;
    lo.max_sk_iterations = GetInt(o, "sk_iterations", 30);
    lo.weights = weights;
    lo.refine_output_error = GetBool(o, "refine", true);  // ML with w = 1/σ (levy.h)
    lo.max_function_evaluations = GetInt(o, "max_function_evaluations", lo.max_function_evaluations);
    const LevyResult r = FitLevy(frf, lo);
    model = r.model;
    poles = r.poles;
    j["status"] = ToString(r.status);
    j["message"] = r.message;
    j["fit_percent"] = r.fit_percent;
    d["sk_iterations"] = r.sk_iterations;
    d["sk_converged"] = r.sk_converged;
    d["refined"] = r.refined;
    d["sk_cost"] = r.sk_cost;
    d["relative_change"] = r.relative_change;
    d["cost_history"] = r.cost_history;
    d["stable"] = r.stable;
    d["final_cost"] = r.final_cost;
    t << "Levy + Sanathanan-Koerner [Balda (4)-(8)]: " << r.message << "\n";
  } else {
    StableNlsOptions so;
    so.denominator_degree = n;
    so.numerator_degree = m;
    so.sk_iterations = GetInt(o, "sk_iterations", 30);
    so.square_numerator = GetBool(o, "square_numerator", true);
    so.max_function_evaluations = GetInt(o, "max_function_evaluations", 2000);
    so.weights = weights;
    const StableNlsResult r = FitStableNls(frf, so);
    model = r.model;
    poles = r.poles;
    j["status"] = ToString(r.status);
    j["message"] = r.message;
    j["fit_percent"] = r.fit_percent;
    d["iterations"] = r.iterations;
    d["function_evaluations"] = r.function_evaluations;
    d["stable"] = r.stable;
    d["final_cost"] = r.final_cost;
    d["start_cost"] = r.start_cost;
    d["start_stable"] = r.start.stable;
    t << "stable nonlinear regression [Balda (9)-(12)]: " << r.message << "\n";
  }
  j["model"] = ModelToJson(model);
  d["poles"] = Complexes(poles);
  d["frf_source"] = loaded.source;
  d["zoh_correction"] = loaded.zoh_corrected;
  d["lines"] = frf.NumLines();
  j["details"] = d;
  t << "  lines " << frf.NumLines() << " (" << loaded.source << "), fit " << j["fit_percent"].get<double>()
    << " %\n  num:";
  for (int i = 0; i < model.num.size(); ++i) t << " " << model.num(i);
  t << "\n  den:";
  for (int i = 0; i < model.den.size(); ++i) t << " " << model.den(i);
  t << "\n  poles:";
  for (int i = 0; i < poles.size(); ++i) t << " " << poles(i);
  t << "\n";
  report.text = t.str();
  return report;
}

MethodReport PoleResidue(const MethodInput& input, const json& o) {
  CheckOptionKeys(o, Keys({"peak_tolerance", "peaks_hz", "fictitious_poles", "origin_correction",
                           "max_residual_poles", "max_function_evaluations"}), "pole-residue");
  const LoadedFrf loaded = Load(input, o);
  Eigen::VectorXd weights;
  const Frf frf = SisoElement(loaded.frf, o, &weights, nullptr, "none");  // pole-residue: unweighted unless asked
  PoleResidueOptions po;
  po.peak_tolerance = GetDouble(o, "peak_tolerance", po.peak_tolerance);
  po.fictitious_poles = GetBool(o, "fictitious_poles", true);
  po.origin_correction = GetBool(o, "origin_correction", true);
  po.max_function_evaluations = GetInt(o, "max_function_evaluations", po.max_function_evaluations);
  po.max_residual_poles = GetInt(o, "max_residual_poles", po.max_residual_poles);
  if (po.max_residual_poles < 0) throw std::invalid_argument("option 'max_residual_poles' must be >= 0");
  po.weights = weights;
  if (o.contains("peaks_hz")) {
    const json& p = o["peaks_hz"];
    if (p.is_number()) po.peak_omegas.push_back(2 * kPi * p.get<double>());
    else if (p.is_array()) {
      for (const auto& x : p) {
        if (!x.is_number()) throw std::invalid_argument("option 'peaks_hz' must hold numbers");
        po.peak_omegas.push_back(2 * kPi * x.get<double>());
      }
    } else {
      throw std::invalid_argument("option 'peaks_hz' must be a number or a list of numbers");
    }
  }
  const PoleResidueResult r = FitPoleResidue(frf, po);
  MethodReport report;
  report.record_sample_time = loaded.sample_time;
  json& j = report.json;
  j["model"] = ModelToJson(PoleResidueTransferFunction(r));
  j["status"] = ToString(r.status);
  j["message"] = r.message;
  j["fit_percent"] = r.fit_percent;
  json modes = json::array();
  std::ostringstream t;
  t.precision(6);
  t << "pole-residue fit [Balda (24)-(35), ideSISO]: " << r.message << ", fit " << r.fit_percent << " %\n";
  t << "   k     Re s       Im s     f_n [Hz]   zeta       Q   std: Re s    Im s     zeta\n";
  int k = 0;
  for (const Mode& m : r.modes) {
    modes.push_back({{"eigenvalue", {m.eigenvalue.real(), m.eigenvalue.imag()}},
                     {"residue", {m.residue.real(), m.residue.imag()}},
                     {"natural_frequency_rad_s", m.natural_frequency},
                     {"natural_frequency_hz", m.natural_frequency / (2 * kPi)},
                     {"damping_ratio", m.damping_ratio}, {"q", m.q}, {"fictitious", m.fictitious},
                     {"from_residual", m.from_residual},
                     {"std", {{"real", NullIfNan(m.std_real)}, {"imag", NullIfNan(m.std_imag)},
                              {"natural_frequency_rad_s", NullIfNan(m.std_natural_frequency)},
                              {"damping_ratio", NullIfNan(m.std_damping_ratio)}}}});
    char line[240];
    std::snprintf(line, sizeof line, "  %2d %9.3f %10.3f %10.3f %8.4f %8.2f %11.3g %8.3g %8.3g%s\n", ++k,
                  m.eigenvalue.real(), m.eigenvalue.imag(), m.natural_frequency / (2 * kPi), m.damping_ratio, m.q,
                  m.std_real, m.std_imag, m.std_damping_ratio,
                  m.fictitious ? "  (fictitious)" : m.from_residual ? "  (from the residual)" : "");
    t << line;
  }
  json d;
  d["modes"] = modes;
  d["origin_correction"] = {r.origin_correction.real(), r.origin_correction.imag()};
  d["iterations"] = r.iterations;
  d["function_evaluations"] = r.function_evaluations;
  d["frf_source"] = loaded.source;
  d["lines"] = frf.NumLines();
  j["details"] = d;
  report.text = t.str();
  return report;
}

MethodReport Mbk(const MethodInput& input, const json& o) {
  CheckOptionKeys(o, Keys({"variant"}), "mbk");
  const LoadedFrf loaded = Load(input, o);
  const std::string variant = o.contains("variant") && o["variant"].is_string() ? o["variant"].get<std::string>()
                              : o.contains("variant") ? "?" : "product";
  if (variant != "product" && variant != "difference")
    throw std::invalid_argument("mbk: option 'variant' must be product or difference");
  const MbkResult r = IdentifyMbk(loaded.frf, variant == "product" ? MbkMethod::kProduct : MbkMethod::kDifference);
  const int n = static_cast<int>(r.mass.rows());
  // State space x = [q; q̇]: A = [0 I; −M⁻¹K −M⁻¹B], B = [0; M⁻¹], C = [I 0].
  StateSpace ss;
  const Eigen::MatrixXd minv = r.mass.inverse();
  ss.A = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  ss.A.topRightCorner(n, n).setIdentity();
  ss.A.bottomLeftCorner(n, n) = -minv * r.stiffness;
  ss.A.bottomRightCorner(n, n) = -minv * r.damping;
  ss.B = Eigen::MatrixXd::Zero(2 * n, n);
  ss.B.bottomRows(n) = minv;
  ss.C = Eigen::MatrixXd::Zero(n, 2 * n);
  ss.C.leftCols(n).setIdentity();
  ss.D = Eigen::MatrixXd::Zero(n, n);
  MethodReport report;
  json& j = report.json;
  j["model"] = ModelToJson(ss);
  j["status"] = ToString(r.status);
  j["message"] = r.message;
  j["fit_percent"] = nullptr;
  auto mat = [](const Eigen::MatrixXd& m) {
    json a = json::array();
    for (int i = 0; i < m.rows(); ++i) {
      std::vector<double> row(m.cols());
      for (int c = 0; c < m.cols(); ++c) row[c] = m(i, c);
      a.push_back(row);
    }
    return a;
  };
  json d;
  d["M"] = mat(r.mass);
  d["B"] = mat(r.damping);
  d["K"] = mat(r.stiffness);
  d["variant"] = variant;
  d["residual_norm"] = r.residual_norm;
  d["frf_source"] = loaded.source;
  d["lines"] = loaded.frf.NumLines();
  j["details"] = d;
  std::ostringstream t;
  t.precision(8);
  t << "M, B, K [Balda " << (variant == "product" ? "(16)-(19)" : "(20)-(22)") << "]: " << r.message << "\n";
  t << "M =\n" << r.mass << "\nB =\n" << r.damping << "\nK =\n" << r.stiffness << "\n";
  report.text = t.str();
  return report;
}

}  // namespace

std::vector<MethodInfo> FrequencyMethods() {
  return {
      {"levy-sk", "Levy regression + Sanathanan-Koerner reweighting on an FRF (seed 002 (4)-(8)): --order n, numerator_degree",
       false, [](const MethodInput& in, const json& o) { return Rational(in, o, false); }},
      {"stable-nls", "stable-by-construction nonlinear FRF regression (seed 002 (9)-(12)): --order n, numerator_degree",
       false, [](const MethodInput& in, const json& o) { return Rational(in, o, true); }},
      {"pole-residue", "modal pole-residue fit of an FRF from its peaks (seed 002 (24)-(35)): peak_tolerance, peaks_hz, max_residual_poles, weight",
       false, [](const MethodInput& in, const json& o) { return PoleResidue(in, o); }},
      {"mbk", "M, B, K from a receptance FRF matrix (seed 002 (16)-(22)): variant=product|difference",
       false, [](const MethodInput& in, const json& o) { return Mbk(in, o); }},
  };
}

}  // namespace idrig
