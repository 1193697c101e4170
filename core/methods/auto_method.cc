// `auto`: the default of `idrig identify`. Every applicable method (SISO: oe, n4sid, arx-oe;
// MIMO: n4sid, oe per output), each also with a direct input term (oe with input_delay 0,
// n4sid with D), at every order 1..max_order is scored by forward (rolling-origin)
// cross-validation in two folds: estimated on the samples before the point where the
// cumulative input energy reaches 2/3, resp. 3/4, of its total (auto_method.h: the information
// about the parameters accrues with the input energy), each model simulates the whole record
// from rest and is scored on the samples after that point (mean simulation fit over the
// outputs). A candidate's score is the root mean square of its NRMSEs over the folds
// (P. Stoica, P. Eykhoff, P. Janssen, T. Söderström, "Model-structure selection by
// cross-validation", Int. J. Control 43(6), 1986; [Ljung] §16.5). The choice is the smallest
// order whose score is within 2 % of the best; among candidates at that order, the first in the
// list (oe first: under white output noise it is the maximum-likelihood estimate). The winner
// is refitted on the whole record and its report returned, with the table of candidates; a refit
// that fails there (an unstable model) is set aside and the rule applied to the candidates left.
// A record run about an operating point (its means stand out: auto_method.h) has every candidate
// also fitted about the means of its estimation part ("oe mean", …: y = y0 + G(u − u0)), scored
// the same way; at equal order the plain fit comes first.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "core/io/model_json.h"
#include "core/methods/auto_method.h"
#include "core/methods/subspace_pem_method.h"
#include "core/numeric/validation.h"

namespace idrig {
namespace {

using nlohmann::json;

// A method with fixed options: e.g. "oe nk=0" is oe with input_delay 0 (a direct term b0).
struct Variant {
  std::string label, method;
  json options;
};

struct Candidate {
  std::string label, method;
  json options;
  int order = 0;
  double fit = -std::numeric_limits<double>::infinity();  // 100·(1 − RMS of the fold NRMSEs) [%]
  std::vector<double> fold_fits;                         // mean validation fit per fold [%]
  std::string note;                                      // why it was not scored
};

}  // namespace

bool OffsetsStandOut(const IoRecord& record) {
  auto stands_out = [](const Eigen::MatrixXd& m) {
    for (int j = 0; j < m.cols(); ++j) {
      const double range = m.col(j).maxCoeff() - m.col(j).minCoeff();
      if (std::abs(m.col(j).mean()) > kOffsetShare * range) return true;
    }
    return false;
  };
  return stands_out(record.u) || stands_out(record.y);
}

int InputEnergySplit(const Eigen::MatrixXd& u, double fraction, int min_head, int min_tail) {
  const int samples = static_cast<int>(u.rows());
  if (!(fraction > 0.0 && fraction < 1.0))
    throw std::invalid_argument("input energy split: the fraction must lie in (0, 1)");
  if (min_head < 0 || min_tail < 0 || min_head + min_tail > samples)
    throw std::invalid_argument("input energy split: " + std::to_string(samples) + " samples cannot keep " +
                                std::to_string(min_head) + " before and " + std::to_string(min_tail) + " after the split");
  Eigen::VectorXd share = Eigen::VectorXd::Zero(samples);  // Σ_j (u_j − ū_j)²/(nu E_j) per sample
  int inputs_with_energy = 0;
  for (int j = 0; j < u.cols(); ++j) {
    const Eigen::ArrayXd e = (u.col(j).array() - u.col(j).mean()).square();
    const double total = e.sum();
    if (!(total > 0.0) || !std::isfinite(total)) continue;
    share += (e / total).matrix();
    ++inputs_with_energy;
  }
  int split = static_cast<int>(std::ceil(fraction * samples));
  if (inputs_with_energy > 0) {
    const double target = fraction * inputs_with_energy * (1.0 - 1e-12);  // a sum of N roundings
    double cumulative = 0.0;
    split = samples;
    for (int k = 0; k < samples; ++k) {
      cumulative += share(k);
      if (cumulative >= target) { split = k + 1; break; }
    }
  }
  return std::clamp(split, min_head, samples - min_tail);
}

std::vector<int> AutoFoldSplits(const Eigen::MatrixXd& u, bool by_energy) {
  const int samples = static_cast<int>(u.rows());
  std::vector<int> splits;
  for (double fraction : {2.0 / 3.0, 0.75}) {
    const int s = by_energy ? InputEnergySplit(u, fraction, samples / 2, std::max(10, samples / 10))
                            : samples - static_cast<int>(std::floor((1.0 - fraction) * samples + 1e-9));
    if (splits.empty() || s > splits.back()) splits.push_back(s);
  }
  return splits;
}

namespace {

MethodReport RunAuto(const MethodInput& input, const json& o) {
  CheckOptionKeys(o, {"order", "max_order", "candidates", "tolerance", "screen_samples", "split", "offsets"}, "auto");
  const IoRecord& full_record = *input.record;
  // Long records are screened on their first `screen_samples` samples (the same folds in that
  // window); the winner is refitted on the whole record.
  int screen = 15000;
  if (o.contains("screen_samples")) {
    if (!o["screen_samples"].is_number_integer() || o["screen_samples"].get<int>() < 30)
      throw std::invalid_argument("auto: option 'screen_samples' must be an integer >= 30");
    screen = o["screen_samples"].get<int>();
  }
  const IoRecord record = full_record.NumSamples() > screen ? Slice(full_record, 0, screen) : full_record;
  const bool siso = record.NumInputs() == 1 && record.NumOutputs() == 1;
  // Each method with and without a direct (same-sample) input term: real records often have
  // one (a fast sensor, a sampling skew), a sampled plant under a zero-order hold has none.
  const json direct_oe = {{"input_delay", 0}}, direct_n4sid = {{"feedthrough", true}};
  std::vector<Variant> variants =
      siso ? std::vector<Variant>{{"oe", "oe", json::object()}, {"n4sid", "n4sid", json::object()},
                                  {"arx-oe", "arx-oe", json::object()}, {"oe nk=0", "oe", direct_oe},
                                  {"n4sid D", "n4sid", direct_n4sid}}
           : std::vector<Variant>{{"n4sid", "n4sid", json::object()}, {"oe", "oe", json::object()},
                                  {"n4sid D", "n4sid", direct_n4sid}, {"oe nk=0", "oe", direct_oe}};
  if (o.contains("candidates")) {
    if (!o["candidates"].is_array() || o["candidates"].empty())
      throw std::invalid_argument("auto: option 'candidates' must be a non-empty list of method names");
    variants.clear();
    for (const auto& m : o["candidates"]) {
      if (!m.is_string()) throw std::invalid_argument("auto: option 'candidates' must list method names");
      FindMethod(m.get<std::string>());
      variants.push_back({m.get<std::string>(), m.get<std::string>(), json::object()});
    }
  }
  // Operating-point offsets: with offsets=auto (the default) a record whose means stand out
  // (OffsetsStandOut) is also fitted about its means (registry.h, option offsets=mean), every
  // candidate both ways, and the folds choose; a record about zero is taken as it is.
  const std::string offsets = o.value("offsets", std::string("auto"));
  const bool both = offsets == "auto" && OffsetsStandOut(record);
  if (offsets == "mean" || offsets == "initial" || both) {
    const std::string treatment = both ? "mean" : offsets;
    const size_t plain = variants.size();
    for (size_t k = 0; k < plain; ++k) {
      Variant v = variants[k];
      v.label += " " + treatment;
      v.options["offsets"] = treatment;
      if (!both) variants[k] = v;
      else variants.push_back(v);
    }
  }
  // A variant without a treatment is fitted as recorded (not the explicit methods' own choice
  // among the treatments, registry.h): the folds compare the treatments here.
  for (Variant& v : variants)
    if (!v.options.contains("offsets")) v.options["offsets"] = "none";
  bool by_energy = true;
  if (o.contains("split")) {
    if (o["split"] != "energy" && o["split"] != "samples")
      throw std::invalid_argument("auto: option 'split' must be 'energy' (the default) or 'samples'");
    by_energy = o["split"] == "energy";
  }
  int max_order = 6, only_order = 0;
  if (o.contains("max_order")) {
    if (!o["max_order"].is_number_integer() || o["max_order"].get<int>() < 1)
      throw std::invalid_argument("auto: option 'max_order' must be an integer >= 1");
    max_order = o["max_order"].get<int>();
  }
  if (o.contains("order")) {
    if (!o["order"].is_number_integer() || o["order"].get<int>() < 0)
      throw std::invalid_argument("auto: option 'order' must be an integer >= 1");
    only_order = o["order"].get<int>();
  }
  double tolerance = 0.02;
  if (o.contains("tolerance")) {
    if (!o["tolerance"].is_number() || o["tolerance"].get<double>() < 0)
      throw std::invalid_argument("auto: option 'tolerance' must be a number >= 0 (relative NRMSE)");
    tolerance = o["tolerance"].get<double>();
  }
  const int samples = record.NumSamples();
  if (samples < 30)
    throw std::invalid_argument("auto: the record has " + std::to_string(samples) +
                                " samples; choosing a model on held-out data needs at least 30");
  const std::vector<int> splits = AutoFoldSplits(record.u, by_energy);
  std::vector<IoRecord> heads;
  for (int s : splits) heads.push_back(Slice(record, 0, s));
  std::vector<Candidate> table;
  for (int n = only_order > 0 ? only_order : 1; n <= (only_order > 0 ? only_order : max_order); ++n) {
    for (const auto& v : variants) {
      Candidate c;
      c.label = v.label;
      c.method = v.method;
      c.options = v.options;
      c.options["order"] = n;
      c.order = n;
      double mean_square = 0.0;
      bool scored = true;
      for (size_t f = 0; f < splits.size() && scored; ++f) {
        const int split = splits[f];
        const std::string fold = splits.size() > 1 ? "fold " + std::to_string(f + 1) + ": " : "";
        try {
          const MethodReport r = RunMethod(v.method, heads[f], c.options);
          const std::string status = r.json.value("status", "failed");
          if (status == "failed") {
            c.note = fold + "status failed: " + r.json.value("message", "");
            scored = false;
            break;
          }
          if (status != "ok" && c.note.empty()) c.note = fold + "status " + status;
          const Eigen::MatrixXd sim = SimulateModelJson(r.json.at("model"), record.u, record.sample_time);
          const Eigen::VectorXd fit = FitPercent(record.y.bottomRows(samples - split), sim.bottomRows(samples - split));
          if (!fit.allFinite()) {
            c.note = fold + "the simulation diverges";
            scored = false;
            break;
          }
          c.fold_fits.push_back(fit.mean());
          const double nrmse = 1.0 - fit.mean() / 100.0;
          mean_square += nrmse * nrmse / static_cast<double>(splits.size());
        } catch (const std::exception& e) {
          c.note = fold + e.what();
          scored = false;
        }
      }
      if (scored) c.fit = 100.0 * (1.0 - std::sqrt(mean_square));
      table.push_back(c);
    }
  }
  // The winner is refitted on the whole record; a refit that fails (an unstable model: its
  // simulation diverges) is set aside and the rule is applied again to the candidates left, so
  // `auto` never returns a failed model while another candidate gives a usable one.
  std::vector<bool> excluded(table.size(), false);
  json rejected = json::array();
  double best = -std::numeric_limits<double>::infinity();
  const Candidate* chosen = nullptr;
  MethodReport report;
  for (int attempt = 0; attempt < 6; ++attempt) {
    best = -std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < table.size(); ++i)
      if (!excluded[i]) best = std::max(best, table[i].fit);
    if (!std::isfinite(best)) break;
    const double best_nrmse = 1.0 - best / 100.0;
    size_t pick = 0;
    for (size_t i = 0; i < table.size(); ++i)  // ordered by order, then by preference
      if (!excluded[i] && std::isfinite(table[i].fit) &&
          1.0 - table[i].fit / 100.0 <= (1.0 + tolerance) * best_nrmse + 1e-12) { pick = i; break; }
    std::string why;
    try {
      MethodReport refit = RunMethod(table[pick].method, full_record, table[pick].options);
      if (refit.json.value("status", std::string("failed")) != "failed") {
        chosen = &table[pick];
        report = std::move(refit);
        break;
      }
      why = refit.json.value("message", std::string("status failed"));
    } catch (const std::exception& e) {
      why = e.what();
    }
    excluded[pick] = true;
    json row = json::object();
    row["candidate"] = table[pick].label;
    row["order"] = table[pick].order;
    row["reason"] = "refit on the whole record failed: " + why;
    rejected.push_back(std::move(row));
  }
  if (chosen == nullptr) {
    std::string why;
    for (const auto& c : table) why += "\n  " + c.label + " n=" + std::to_string(c.order) + ": " + c.note;
    for (const auto& r : rejected) why += "\n  " + r["candidate"].get<std::string>() + " n=" +
                                          std::to_string(r["order"].get<int>()) + ": " + r["reason"].get<std::string>();
    throw std::invalid_argument("auto: no candidate method gave a usable model on the record:" + why);
  }
  json selection;
  json rows = json::array();
  for (const auto& c : table)
    rows.push_back({{"candidate", c.label}, {"method", c.method}, {"options", c.options}, {"order", c.order},
                    {"validation_fit_percent", std::isfinite(c.fit) ? json(c.fit) : json(nullptr)},
                    {"fold_fit_percent", c.fold_fits}, {"note", c.note}});
  std::ostringstream rule;
  if (record.NumSamples() < full_record.NumSamples())
    rule << "screened on the first " << record.NumSamples() << " of " << full_record.NumSamples() << " samples: ";
  json folds = json::array();
  rule << splits.size() << (splits.size() > 1 ? " folds" : " fold") << " at 2/3 and 3/4 of the "
       << (by_energy ? "input energy" : "samples") << ":";
  for (size_t f = 0; f < splits.size(); ++f) {
    rule << (f ? ";" : "") << " estimated on samples 0.." << splits[f] - 1 << ", scored on " << splits[f] << ".."
         << samples - 1;
    json fold = json::object();
    fold["estimation"] = json::array({0, splits[f] - 1});
    fold["validation"] = json::array({splits[f], samples - 1});
    folds.push_back(fold);
  }
  rule << " (simulation from rest); score 100(1 - RMS of the fold NRMSEs); the smallest order within "
       << 100 * tolerance << " % of the best score, then the first method in the list (";
  for (size_t k = 0; k < variants.size(); ++k) rule << (k ? ", " : "") << variants[k].label;
  rule << ")";
  if (both)
    rule << "; the record's means stand out (more than " << kOffsetShare
         << " of a channel's range), so every candidate is also fitted about them (\"mean\": y = y0 + G(u - u0))";
  selection["candidates"] = rows;
  selection["offsets"] = offsets == "auto" ? (both ? "chosen on the folds" : "none (the record is about zero)") : offsets;
  selection["rule"] = rule.str();
  selection["folds"] = folds;
  selection["chosen"] = {{"candidate", chosen->label}, {"method", chosen->method}, {"options", chosen->options},
                         {"order", chosen->order}, {"validation_fit_percent", chosen->fit}};
  selection["best_validation_fit_percent"] = best;
  if (!rejected.empty()) selection["rejected"] = rejected;
  report.json["chosen_method"] = chosen->method;
  report.json["selection"] = selection;
  std::ostringstream t;
  t << std::setprecision(4) << std::fixed;
  const int width = both ? 14 : 12;
  t << "Method and order chosen on held-out data: " << rule.str() << "\n\n  order";
  for (const auto& v : variants) t << std::setw(width) << v.label;
  t << "   (score %: 100(1 - RMS NRMSE) over the folds)\n";
  for (size_t k = 0; k < table.size(); k += variants.size()) {
    t << "  " << std::setw(5) << table[k].order;
    for (size_t i = 0; i < variants.size(); ++i) {
      const Candidate& c = table[k + i];
      std::ostringstream cell;
      cell << std::setprecision(2) << std::fixed;
      if (!std::isfinite(c.fit)) cell << "-";
      else if (c.fit < -999.0) cell << "< -999";  // a diverging fit; the JSON has the value
      else cell << c.fit;
      t << std::setw(width - 1) << cell.str() << (&c == chosen ? "*" : " ");
    }
    t << "\n";
  }
  for (const auto& r : rejected)
    t << "set aside: " << r["candidate"].get<std::string>() << " order " << r["order"].get<int>() << " ("
      << r["reason"].get<std::string>() << ")\n";
  if (!rejected.empty()) t << "\n";
  t << "\nchosen: " << chosen->label << " order " << chosen->order << " (validation fit " << chosen->fit
    << " %, best " << best << " %); refitted on the whole record:\n\n";
  report.text = t.str() + report.text;
  return report;
}

}  // namespace

MethodInfo AutoMethod() {
  return {"auto",
          "default: every applicable method and order, chosen by simulation fit on held-out data (two folds "
          "split at 2/3 and 3/4 of the input energy), refitted on the whole record",
          true, [](const MethodInput& in, const json& o) { return RunAuto(in, o); }};
}

}  // namespace idrig
