#include "core/io/gap_json.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <iomanip>
#include <sstream>

#include "core/io/model_json.h"

namespace idrig {
namespace {

nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::json Params(const Effect& effect, const std::vector<double>* stds = nullptr) {
  nlohmann::json p = nlohmann::json::object();
  const auto& names = EffectParameterNames(effect.kind);
  for (size_t i = 0; i < names.size() && i < effect.params.size(); ++i) {
    if (stds && i < stds->size()) {
      p[names[i]] = {{"value", Number(effect.params[i])}, {"std", Number((*stds)[i])}};
    } else {
      p[names[i]] = Number(effect.params[i]);
    }
  }
  return p;
}

}  // namespace

nlohmann::json EffectToJson(const Effect& effect) {
  return {{"effect", EffectName(effect.kind)}, {"params", Params(effect)}};
}

Effect EffectFromJson(const nlohmann::json& json) {
  if (!json.is_object() || !json.contains("effect") || !json["effect"].is_string())
    throw std::invalid_argument("effect: expected {\"effect\": name, \"params\": {…}}");
  Effect effect;
  effect.kind = EffectFromName(json["effect"].get<std::string>());
  const auto& names = EffectParameterNames(effect.kind);
  const nlohmann::json params = json.value("params", nlohmann::json::object());
  if (!params.is_object()) throw std::invalid_argument("effect: params must be an object");
  for (auto it = params.begin(); it != params.end(); ++it)
    if (std::find(names.begin(), names.end(), it.key()) == names.end())
      throw std::invalid_argument("effect " + json["effect"].get<std::string>() + ": unknown parameter '" +
                                  it.key() + "'");
  for (const auto& name : names) {
    if (!params.contains(name)) {
      if (effect.kind == EffectKind::kSensorNonlinearity && name != "a1") {
        effect.params.push_back(0.0);  // a2, a3, absolute default to 0
        continue;
      }
      if (effect.kind == EffectKind::kSensorNonlinearity) {
        effect.params.push_back(1.0);  // a1 defaults to 1
        continue;
      }
      throw std::invalid_argument("effect " + json["effect"].get<std::string>() + ": missing parameter '" +
                                  name + "'");
    }
    if (!params[name].is_number())
      throw std::invalid_argument("effect: parameter '" + name + "' must be a number");
    effect.params.push_back(params[name].get<double>());
  }
  ValidateEffect(effect);
  return effect;
}

static nlohmann::json NoiseFloorJson(const NoiseFloor& f, double nrmse) {
  nlohmann::json j = {{"method", f.method}, {"sigma", f.sigma}, {"nrmse", nrmse}, {"samples", f.samples}};
  if (f.method == "periods") {
    j["period_samples"] = f.period;
    j["periods"] = f.periods;
  } else if (f.method == "arx_prediction") {
    j["order"] = f.order;
    j["ar_gain"] = f.ar_gain;
  }
  if (f.drifting_records > 0) j["drifting_records"] = f.drifting_records;
  return j;
}

static nlohmann::json DetectionLinesJson(const DetectionLines& d) {
  if (!d.available) return {{"available", false}, {"reason", d.reason}};
  auto db = [](double p) { return p > 0 ? 10 * std::log10(p) : -300.0; };
  nlohmann::json lines = nlohmann::json::array();
  for (const auto& l : d.lines) {
    if (lines.size() >= 2048) break;
    nlohmann::json j = {{"f_hz", l.f_hz}, {"line", l.line}, {"kind", l.kind}, {"y_db", db(l.y_power)},
                        {"noise_db", db(l.noise_power)}, {"significant", l.significant}};
    if (l.kind == "excited") {
      j["bla_magnitude"] = l.bla_magnitude;
      j["bla_phase"] = l.bla_phase;
      j["bla_noise_std"] = l.bla_noise_std;
      j["bla_distortion_std"] = std::isfinite(l.bla_distortion_std) ? nlohmann::json(l.bla_distortion_std) : nlohmann::json();
      j["sim_magnitude"] = l.sim_magnitude;
    }
    lines.push_back(j);
  }
  return {{"available", true}, {"period_samples", d.period_samples}, {"periods", d.periods},
          {"steady_from", d.steady_from}, {"f0_hz", d.f0_hz}, {"excited", d.excited},
          {"odd_lines", d.odd_lines}, {"even_lines", d.even_lines}, {"odd_out_of_band", d.odd_out_of_band},
          {"odd_significant", d.odd_significant}, {"even_significant", d.even_significant},
          {"odd_to_noise_db", d.odd_to_noise_db}, {"even_to_noise_db", d.even_to_noise_db},
          {"odd_to_output_db", d.odd_to_output_db}, {"even_to_output_db", d.even_to_output_db},
          {"odd_distortion", d.odd_distortion}, {"even_distortion", d.even_distortion},
          {"bla_vs_sim", d.bla_vs_sim}, {"lines", lines}};
}

nlohmann::json GapReportToJson(const GapReport& report) {
  const GapVerdict& v = report.verdict;
  nlohmann::json verdict = {
      {"effect", v.effect},
      {"confidence", v.confidence},
      {"nrmse_before", v.nrmse_before},
      {"nrmse_after", v.nrmse_after},
      {"shrink", v.shrink},
      {"noise_nrmse", v.noise_nrmse},
      {"remaining_gap_to_noise", v.remaining_gap_to_noise},
      {"below_noise_floor", v.below_noise_floor},
      {"estimation_only", v.estimation_only},
      {"effect_fitted", EffectName(v.params.kind)},
      {"params", Params(v.params)},
      {"params_std", Params(Effect{v.params.kind, v.param_std})},
      {"plant", ModelToJson(v.plant)},
      {"explanation", v.explanation},
  };
  if (!v.tied.empty()) verdict["tied"] = v.tied;
  nlohmann::json effects = nlohmann::json::array();
  for (size_t i = 0; i < v.effects.size(); ++i)
    effects.push_back({{"effect", EffectName(v.effects[i].kind)},
                       {"params", Params(v.effects[i], i < v.effects_std.size() ? &v.effects_std[i] : nullptr)}});
  // A verdict that names an effect of the library lists it under `effects` too when its
  // candidate carries no effect of its own: a parameter mismatch is the refitted plant
  // (`verdict.plant`), with no parameters here. Scripts that read `effects` then see what
  // `effect` says.
  if (effects.empty() && v.params.kind != EffectKind::kNone && v.effect == EffectName(v.params.kind))
    effects.push_back({{"effect", v.effect}, {"params", Params(v.params, &v.param_std)}});
  verdict["effects"] = effects;
  nlohmann::json output_offset = nlohmann::json::array();
  for (double b : v.nuisance.output_offset) output_offset.push_back(Number(b));
  verdict["nuisance"] = {
      {"input_offset", v.nuisance.input_offset_fitted ? Number(v.nuisance.input_offset) : nlohmann::json()},
      {"input_offset_std", v.nuisance.input_offset_fitted ? Number(v.nuisance.input_offset_std) : nlohmann::json()},
      {"output_offset", output_offset},
      {"initial_state", v.nuisance.initial_state},
  };
  if (!v.nuisance.output_drift.empty()) {
    nlohmann::json drift = nlohmann::json::array();
    for (double d : v.nuisance.output_drift) drift.push_back(Number(d));
    verdict["nuisance"]["output_drift"] = drift;
  }
  verdict["fit_scheme"] = v.fit_scheme;
  if (!v.g0_gap.empty()) verdict["g0_gap"] = v.g0_gap;
  if (v.linear_order > 0) {
    verdict["linear_order"] = v.linear_order;
    verdict["linear_nrmse_after"] = v.linear_nrmse_after;
  }
  if (v.shooting_segment > 0) verdict["shooting_segment"] = v.shooting_segment;

  nlohmann::json ranking = nlohmann::json::array();
  for (const auto& c : report.ranking) {
    ranking.push_back({
        {"effect", EffectName(c.effect.kind)},
        {"nrmse_after", c.nrmse_after},
        {"score", c.score},
        {"bic", c.bic},
        {"eligible", c.eligible},
        {"likelihood_ratio", c.likelihood_ratio},
        {"lr_threshold", c.lr_threshold},
        {"significant", c.significant},
        {"signature", c.signature},
        {"validation_gain_z", c.validation_gain_z},
        {"nuisance_columns", {{"estimation", c.nuisance_estimation}, {"validation", c.nuisance_validation}}},
        {"estimation_mse", c.estimation_mse},
        {"validation_mse", c.validation_mse},
        {"parameters", c.parameters},
        {"params", Params(c.effect, &c.param_std)},
        {"plant", ModelToJson(c.plant)},
        {"evaluations", c.evaluations},
        {"note", c.note},
    });
  }

  const GapWhere& w = report.where;
  nlohmann::json bands = nlohmann::json::array();
  for (const auto& b : w.bands)
    bands.push_back({{"f_lo_hz", b.f_lo_hz}, {"f_hi_hz", b.f_hi_hz}, {"gap_power", b.gap_power},
                     {"coherence", b.coherence}, {"coherence_threshold", b.coherence_threshold},
                     {"relative_error", b.relative_error},
                     {"significant", b.significant}});
  nlohmann::json factors = nlohmann::json::object();
  for (const auto& f : w.factors) {
    nlohmann::json bins = nlohmann::json::array();
    for (const auto& b : f.bins)
      bins.push_back({{"label", b.label}, {"samples", b.samples}, {"mean", b.mean}, {"rms", b.rms},
                      {"relative_rms", b.relative_rms}});
    factors[f.name] = {{"eta_squared", f.eta_squared}, {"rms_ratio", f.rms_ratio},
                       {"relative_ratio", f.relative_ratio}, {"bins", bins}};
  }
  nlohmann::json where = {
      {"nrmse_before", w.nrmse_before},
      {"noise_nrmse", w.noise_nrmse},
      {"noise_floor", NoiseFloorJson(w.noise_floor, w.noise_nrmse)},
      {"detection_lines", DetectionLinesJson(w.detection_lines)},
      {"lattice", {{"lattice", w.lattice.lattice}, {"detected", w.lattice.detected}, {"step", w.lattice.step},
                   {"offset", w.lattice.offset}, {"on_lattice", w.lattice.on_lattice},
                   {"resultant", w.lattice.resultant}, {"levels", w.lattice.levels},
                   {"noise_share", w.lattice.noise_share}, {"reason", w.lattice.reason}}},
      {"gap_to_noise", w.gap_to_noise},
      {"gap_significant", w.gap_significant},
      {"residual_white", w.residual_white},
      {"residual_independent", w.residual_independent},
      {"bands", bands},
      {"factors", factors},
      {"summary", w.summary},
  };
  nlohmann::json glitches = nlohmann::json::array();
  for (const auto& g : report.glitches)
    glitches.push_back({{"records", g.records}, {"record", g.record}, {"sample", g.sample},
                        {"value", g.value}, {"replaced_by", g.replaced_by}});
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& g : report.sensor_steps)
    steps.push_back({{"records", g.records}, {"record", g.record}, {"sample", g.sample}, {"size", g.size}});
  return {{"format", "idrig.gap/1"},
          {"verdict", verdict},
          {"ranking", ranking},
          {"where", where},
          {"notes", report.notes},
          {"glitches", glitches},
          {"sensor_steps", steps},
          {"estimation_samples", report.estimation_samples},
          {"validation_samples", report.validation_samples}};
}

std::string GapReportText(const nlohmann::json& report) {
  std::ostringstream s;
  const auto& v = report.at("verdict");
  s << std::setprecision(4);
  s << "verdict: " << v.at("effect").get<std::string>();
  if (v.contains("tied")) {
    std::string tied;
    for (const auto& t : v["tied"]) tied += (tied.empty() ? "" : " or ") + t.get<std::string>();
    s << " (" << tied << ")";
  }
  s << "  confidence " << v.at("confidence").get<double>() << "\n";
  s << "  " << v.at("explanation").get<std::string>() << "\n";
  s << "  validation NRMSE before " << v.at("nrmse_before").get<double>() << ", after "
    << v.at("nrmse_after").get<double>() << ", noise floor "
    << report.at("where").at("noise_nrmse").get<double>();
  if (report.at("where").contains("noise_floor"))
    s << " (" << report["where"]["noise_floor"].value("method", "") << ")";
  if (v.value("below_noise_floor", false)) s << ", below the floor";
  if (v.value("estimation_only", false)) s << ", on the estimation records only (not confirmed on validation)";
  s << "\n";
  for (const auto& [name, value] : v.at("params").items()) {
    s << "  " << name << " = " << value;
    const auto& sd = v.at("params_std")[name];
    if (sd.is_number()) s << " ± " << sd.get<double>();
    s << "\n";
  }
  if (v.contains("effects") && v["effects"].size() > 1) {
    const auto& second = v["effects"][1];
    s << "  second effect: " << second.at("effect").get<std::string>() << "\n";
    for (const auto& [name, value] : second.at("params").items())
      s << "    " << name << " = " << value.at("value") << " ± " << value.at("std") << "\n";
  }
  if (v.contains("nuisance")) {
    const auto& n = v["nuisance"];
    s << "  nuisance: input offset " << n.at("input_offset") << ", output offset "
      << (n.at("output_offset").empty() ? nlohmann::json() : n.at("output_offset")[0]);
    if (n.contains("output_drift") && !n["output_drift"].empty()) s << ", output drift " << n["output_drift"][0] << "/s";
    s << ", initial state " << n.at("initial_state").get<std::string>() << "; fit "
      << v.value("fit_scheme", "") << "\n";
  }
  s << "where: " << report.at("where").at("summary").get<std::string>() << "\n";
  if (report.at("where").contains("detection_lines") && report["where"]["detection_lines"].value("available", false)) {
    const auto& d = report["where"]["detection_lines"];
    s << "detection lines (" << d.at("periods").get<int>() << " periods): odd "
      << d.at("odd_to_noise_db").get<double>() << " dB over noise ("
      << (d.at("odd_distortion").get<bool>() ? "odd nonlinearity" : "noise only") << "), even "
      << d.at("even_to_noise_db").get<double>() << " dB ("
      << (d.at("even_distortion").get<bool>() ? "even nonlinearity" : "noise only") << ")\n";
  }
  s << "ranking (validation BIC; eligible = significant on estimation data and matching the gap):\n";
  s << "  " << std::left << std::setw(22) << "effect" << std::setw(12) << "NRMSE" << std::setw(12)
    << "score" << std::setw(10) << "LR/thr" << "signature\n";
  for (const auto& c : report.at("ranking")) {
    std::ostringstream lr, score, nrmse, signature;
    lr << std::setprecision(3)
       << c.at("likelihood_ratio").get<double>() / std::max(c.at("lr_threshold").get<double>(), 1e-12);
    score << std::setprecision(3) << c.at("score").get<double>();
    nrmse << std::setprecision(4) << c.at("nrmse_after").get<double>();
    signature << std::setprecision(3) << c.at("signature").get<double>();
    const std::string name = c.at("effect").get<std::string>();
    s << "  " << std::left << std::setw(22) << name << std::setw(12) << nrmse.str() << std::setw(12)
      << score.str() << std::setw(10) << (name == "none" ? "-" : lr.str()) << signature.str()
      << (c.at("eligible").get<bool>() ? "" : "  (not eligible)") << "\n";
  }
  for (const auto& n : report.at("notes")) s << "note: " << n.get<std::string>() << "\n";
  return s.str();
}

std::string GapReportText(const GapReport& report) { return GapReportText(GapReportToJson(report)); }

}  // namespace idrig
