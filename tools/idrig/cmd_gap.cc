// idrig gap diagnose --sim MODEL.json --data EST.csv [--data …] [--validate VAL.csv …] [--glitches bridge|keep]
//                    [--drift fit|none] [--sensor-steps find|ignore] [--json]
// idrig gap bench --cases N --seed S [--snr DB] [--samples N] [--ts S] [--jobs J] [--offsets] [--combos F]
//                 [--pairs rig|any] [--excitation K] [--integrating] [--plants zeros|two-mass] [--damping LO,HI] [--noise-pole A] [--process-noise F]
//                 [--add-glitches N] [--glitches bridge|keep] [--add-drift S] [--drift fit|none]
//                 [--sensor-steps find|ignore] [--dump DIR] [--json]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/catalog/catalog.h"
#include "core/io/csv.h"
#include "core/io/gap_json.h"
#include "core/io/gap_svg.h"
#include "core/io/model_json.h"
#include "core/numeric/gap/gap_bench.h"
#include "core/numeric/gap/gap_diagnosis.h"
#include "tools/idrig/commands.h"

namespace idrig {
namespace {

void WriteCase(const GapCase& c, const std::string& dir, int index) {
  const std::string base = dir + "/case" + std::to_string(index);
  WriteModelFile(LtiModel(c.sim), base + "-sim.json");
  WriteIoRecordCsv(MakeIoRecord(c.estimation.u, c.estimation.y, c.estimation.sample_time), base + "-est.csv");
  WriteIoRecordCsv(MakeIoRecord(c.validation.u, c.validation.y, c.validation.sample_time), base + "-val.csv");
  nlohmann::json truth = EffectToJson(c.effect);
  truth["effect"] = EffectName(c.truth);
  truth["effects"] = nlohmann::json::array();
  for (size_t i = 0; i < c.truths.size(); ++i) {
    nlohmann::json e = EffectToJson(c.effects[i]);
    e["effect"] = EffectName(c.truths[i]);
    truth["effects"].push_back(e);
  }
  truth["input_offset"] = c.input_offset;
  truth["output_offset"] = c.output_offset;
  truth["real"] = ModelToJson(c.real);
  truth["noise_sigma"] = c.noise_sigma;
  truth["excitation"] = c.excitation;
  // GapCase::visibility and visibility_refit; +inf (none) as null.
  const auto finite_or_null = [](const std::vector<double>& values) {
    nlohmann::json out = nlohmann::json::array();
    for (double v : values) out.push_back(std::isfinite(v) ? nlohmann::json(v) : nlohmann::json());
    return out;
  };
  truth["visibility"] = finite_or_null(c.visibility);
  truth["visibility_refit"] = finite_or_null(c.visibility_refit);
  std::ofstream(base + "-truth.json") << truth.dump(2) << "\n";
}

// The names in verdict.effects (one or two), or verdict.effect alone.
std::vector<std::string> NamedEffects(const GapReport& report) {
  const GapVerdict& v = report.verdict;
  if (v.effect == "none" || v.effect == "ambiguous" || v.effect == "unexplained") return {v.effect};
  std::vector<std::string> names;
  for (const Effect& e : v.effects)
    if (e.kind != EffectKind::kNone) names.push_back(EffectName(e.kind));
  if (names.empty() || names.front() != v.effect) names.insert(names.begin(), v.effect);
  names.erase(std::unique(names.begin(), names.end()), names.end());
  return names;
}

struct BenchSettings {
  int cases = 26, samples = 4000, jobs = 2;
  double sample_time = 0.01;
  uint64_t seed = 1;
  double snr = 30, combos = 0, noise_pole = 0, process_noise = 0;
  std::vector<double> damping = {0.15, 0.8};
  bool json = false, offsets = false, integrating = false;
  int add_glitches = 0;
  double add_drift = 0;
  std::string dump, excitation, plants, glitches = "bridge", drift = "fit", sensor_steps = "find";
  std::string pairs = "rig";      // rig: the pairs that occur together on rigs; any: every pair
  std::vector<std::string> only;  // keep the cases that withhold one of these effects
};

std::string Rate(int num, int den) {
  std::ostringstream s;
  s << std::setprecision(3) << (den ? double(num) / den : 0.0) << " (" << num << "/" << den << ")";
  return s.str();
}

GapCaseOptions CaseOptions(const BenchSettings& b) {
  GapCaseOptions options;
  options.snr_db = b.snr;
  options.samples = b.samples;
  options.sample_time = b.sample_time;
  options.excitation = b.excitation;
  options.offsets = b.offsets;
  options.integrating = b.integrating;
  options.zeta_min = b.damping.at(0);
  options.zeta_max = b.damping.at(1);
  options.noise_pole = b.noise_pole;
  options.process_noise = b.process_noise;
  options.plants = b.plants;
  options.glitches = b.add_glitches;
  options.drift = b.add_drift;
  return options;
}

void RunBench(const BenchSettings& b) {
  BenchCaseTruth(0, b.combos);  // throws std::invalid_argument for a share outside [0, 1]
  const GapCaseOptions case_options = CaseOptions(b);
  ValidateGapCaseOptions(case_options);  // thrown here, not from the worker threads
  // The case indices: 0..cases−1, or with --only the first `cases` indices whose truth withholds
  // a listed effect (each kept case is the same case as at its index in the full sequence).
  std::vector<int> indices;
  for (const std::string& name : b.only)
    EffectFromName(name);  // throws std::invalid_argument naming an unknown effect
  for (int i = 0; static_cast<int>(indices.size()) < b.cases; ++i) {
    if (b.only.empty()) {
      indices.push_back(i);
      continue;
    }
    if (i > 1000 * b.cases)
      throw std::invalid_argument("gap bench: --only keeps no case of this sequence (with --combos 1 there is no single case)");
    const std::vector<EffectKind> truth = BenchCaseTruth(i, b.combos, b.pairs == "any");
    const bool kept = std::any_of(b.only.begin(), b.only.end(), [&](const std::string& name) {
      return std::any_of(truth.begin(), truth.end(), [&](EffectKind k) { return name == EffectName(k); });
    });
    if (kept) indices.push_back(i);
  }
  if (!b.dump.empty()) std::filesystem::create_directories(b.dump);
  std::vector<GapBenchOutcome> outcomes(b.cases);
  std::atomic<int> next{0};
  std::mutex print;
  auto worker = [&] {
    for (int slot = next++; slot < b.cases; slot = next++) {
      const int i = indices[slot];
      std::mt19937_64 rng(BenchCaseSeed(b.seed, i));
      const std::vector<EffectKind> truth = BenchCaseTruth(i, b.combos, b.pairs == "any");
      const GapCase c = MakeGapCase(truth, rng, case_options);
      if (!b.dump.empty()) WriteCase(c, b.dump, i);
      const auto start = std::chrono::steady_clock::now();
      GapOptions diagnosis;
      diagnosis.threads = 1;  // the cases run in parallel instead
      diagnosis.bridge_glitches = b.glitches == "bridge";
      diagnosis.fit_drift = b.drift == "fit";
      diagnosis.find_sensor_steps = b.sensor_steps == "find";
      const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation}, diagnosis);
      GapBenchOutcome& o = outcomes[slot];
      o.truth = truth;
      o.verdict = report.verdict.effect;
      o.effects = NamedEffects(report);
      o.shrink = report.verdict.shrink;
      o.confidence = report.verdict.confidence;
      o.excitation = c.excitation;
      o.visibility = c.visibility;
      o.visibility_refit = c.visibility_refit;
      o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::string truth_label, named_label;
      for (EffectKind k : truth) truth_label += (truth_label.empty() ? "" : "+") + std::string(EffectName(k));
      for (const auto& n : o.effects) named_label += (named_label.empty() ? "" : "+") + n;
      // The withheld effects within the noise (GapCase::visibility), and those the refit takes up
      // (GapCase::visibility_refit, where the first is above the threshold).
      std::string hidden, absorbed;
      for (size_t k = 0; k < truth.size() && k < c.visibility.size(); ++k) {
        const bool under = c.visibility[k] < BenchVisibilityThreshold();
        const bool refit_under = k < c.visibility_refit.size() && c.visibility_refit[k] < BenchVisibilityThreshold();
        if (!under && !refit_under) continue;
        std::string& list = under ? hidden : absorbed;
        char v[120];
        std::snprintf(v, sizeof v, "%s%s %.3g", list.empty() ? "" : ", ", EffectName(truth[k]),
                      under ? c.visibility[k] : c.visibility_refit[k]);
        list += v;
      }
      std::lock_guard<std::mutex> lock(print);
      std::cerr << "case " << i << ": truth " << truth_label << " (" << c.excitation
                << "), verdict " << o.verdict << " [" << named_label << "], confidence "
                << std::setprecision(3) << o.confidence << ", shrink " << o.shrink << ", "
                << o.seconds << " s"
                << (report.sensor_steps.empty() ? "" : ", " + std::to_string(report.sensor_steps.size()) + " sensor steps marked")
                << (hidden.empty() ? "" : ", within the noise (visibility): " + hidden)
                << (absorbed.empty() ? "" : ", within the noise after the refit (visibility_refit): " + absorbed)
                << "\n";
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < std::max(1, b.jobs); ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();

  const GapBenchScore s = ScoreGapBench(outcomes);
  if (b.json) {
    nlohmann::json out = {{"cases", b.cases}, {"seed", b.seed}, {"snr_db", b.snr}, {"samples", b.samples}, {"sample_time", b.sample_time},
                          {"offsets", b.offsets}, {"combos", b.combos}, {"pairs", b.pairs},
                          {"integrating", b.integrating}, {"excitation", b.excitation},
                          {"damping", b.damping}, {"noise_pole", b.noise_pole}, {"process_noise", b.process_noise}, {"plants", b.plants}, {"only", b.only},
                          {"add_glitches", b.add_glitches}, {"glitches", b.glitches},
                          {"add_drift", b.add_drift}, {"drift", b.drift}, {"sensor_steps", b.sensor_steps},
                          {"single_cases", s.single_cases},
                          {"top1_accuracy", s.top1_accuracy}, {"false_alarm_rate", s.false_alarm_rate},
                          {"single_extra_effect", s.single_extra},
                          {"combo_cases", s.combo_cases}, {"combo_both_named", s.combo_both_rate},
                          {"combo_top1_either", s.combo_top1_rate},
                          {"median_shrink_correct", s.median_shrink_correct},
                          {"mean_seconds", s.mean_seconds},
                          {"decidable_single_cases", s.decidable_single_cases},
                          {"top1_decidable", s.top1_decidable},
                          {"decidable_combo_cases", s.decidable_combo_cases},
                          {"combo_both_decidable", s.combo_both_decidable},
                          {"visibility_threshold", BenchVisibilityThreshold()},
                          {"detectable_single_cases", s.detectable_single_cases},
                          {"top1_detectable", s.top1_detectable},
                          {"detectable_combo_cases", s.detectable_combo_cases},
                          {"combo_both_detectable", s.combo_both_detectable},
                          {"refit_single_cases", s.refit_single_cases},
                          {"top1_refit", s.top1_refit},
                          {"refit_combo_cases", s.refit_combo_cases},
                          {"combo_both_refit", s.combo_both_refit},
                          {"confusion", s.confusion}};
    for (const auto& [kind, counts] : s.by_excitation)
      out["top1_by_excitation"][kind] = double(counts.first) / counts.second;
    for (const auto& [pair, counts] : s.by_pair)
      out["combo_both_by_pair"][pair] = double(counts.first) / counts.second;
    std::cout << out.dump(2) << "\n";
    return;
  }
  std::cout << std::setprecision(3) << "cases " << b.cases << ", seed " << b.seed << ", SNR " << b.snr
            << " dB, " << b.samples << " samples per record at Ts " << b.sample_time << " s"
            << (b.offsets ? ", actuator and sensor offsets" : "")
            << (b.add_glitches ? ", " + std::to_string(b.add_glitches) + " glitches per record (" + b.glitches + ")" : "")
            << (b.process_noise > 0 ? ", process noise " + std::to_string(b.process_noise) + " of the noise variance" : "")
            << (b.add_drift > 0 ? ", a sensor drift of " + std::to_string(b.add_drift) + " noise sigmas per record" : "")
            << (b.drift == "none" ? ", drift not fitted" : "")
            << ", two-effect share " << b.combos << (b.pairs == "any" ? " (any pair)" : "")
            << "\n"
            << "top-1 accuracy on single effects " << Rate(s.single_correct, s.single_cases) << "\n"
            << "false alarms on none " << Rate(s.false_alarms, s.none_cases) << "\n";
  if (s.combo_cases)
    std::cout << "two-effect cases: both named " << Rate(s.combo_both, s.combo_cases)
              << ", top-1 one of the two " << Rate(s.combo_either, s.combo_cases) << "\n";
  std::cout << "without the undecidable cases (an input saturation, dead zone or backlash under a "
               "two-valued input): top-1 "
            << Rate(s.decidable_single_correct, s.decidable_single_cases) << ", both named "
            << Rate(s.decidable_combo_both, s.decidable_combo_cases) << "\n";
  std::cout << "and without the effects within the noise (visibility under " << BenchVisibilityThreshold()
            << "): top-1 " << Rate(s.detectable_single_correct, s.detectable_single_cases) << ", both named "
            << Rate(s.detectable_combo_both, s.detectable_combo_cases) << "\n";
  std::cout << "and without those the refit takes up (visibility_refit under " << BenchVisibilityThreshold()
            << "): top-1 " << Rate(s.refit_single_correct, s.refit_single_cases) << ", both named "
            << Rate(s.refit_combo_both, s.refit_combo_cases) << "\n";
  std::cout << "median validated shrink (right effect) ";
  if (std::isnan(s.median_shrink_correct))
    std::cout << "n/a (no single-effect case named right)";
  else
    std::cout << s.median_shrink_correct;
  std::cout << "\n"
            << "mean time per diagnosis " << s.mean_seconds << " s\n";
  for (const auto& [kind, counts] : s.by_excitation)
    std::cout << "top-1 on " << kind << " excitation " << Rate(counts.first, counts.second) << "\n";
  for (const auto& [pair, counts] : s.by_pair)
    std::cout << "both named on " << pair << " " << Rate(counts.first, counts.second) << "\n";
  std::cout << "confusion (rows: truth; columns: named effects with counts)\n";
  for (const auto& [truth, row] : s.confusion) {
    std::cout << "  " << std::left << std::setw(22) << truth;
    for (const auto& [verdict, count] : row) std::cout << " " << verdict << ":" << count;
    std::cout << "\n";
  }
}

}  // namespace

void RegisterGapCommand(CLI::App& app) {
  auto* gap = app.add_subcommand("gap", "sim-to-real gap diagnosis");
  gap->require_subcommand(1);

  struct DiagnoseArgs {
    std::string sim;
    std::vector<std::string> data, validate;
    std::string plots, u_name, y_name, time_name, glitches = "bridge", drift = "fit", sensor_steps = "find";
    bool json = false;
  };
  auto d = std::make_shared<DiagnoseArgs>();
  auto* diagnose = gap->add_subcommand(
      "diagnose", "where the sim model departs from the records, which effect causes it, and how far adding it closes the gap on validation data");
  diagnose->add_option("--sim", d->sim, "sim model (idrig.model/1 JSON, SISO)")->required();
  diagnose->add_option("--data", d->data, "estimation record CSV t,u,y (repeatable)")->required();
  diagnose->add_option("--validate", d->validate, "held-out validation record CSV (repeatable); "
                                                  "absent: one record is split in time");
  diagnose->add_option("--u", d->u_name, "the input column of records with their own column names (default: u)");
  diagnose->add_option("--y", d->y_name, "the output column (default: y)");
  diagnose->add_option("--time", d->time_name, "the time column (default: t or time)");
  diagnose->add_option("--glitches", d->glitches,
                       "bridge (default: output samples far out of the signal, a sensor or acquisition glitch, are "
                       "bridged from their neighbours before fitting and listed under \"glitches\") or keep")
      ->check(CLI::IsMember({"bridge", "keep"}));
  diagnose->add_option("--drift", d->drift,
                       "fit (default: a slow sensor drift, a ramp per record, is a nuisance parameter beside the "
                       "output offset where G0 neither integrates nor is fitted by multiple shooting; reported under "
                       "verdict.nuisance.output_drift) or none")
      ->check(CLI::IsMember({"fit", "none"}));
  diagnose->add_option("--sensor-steps", d->sensor_steps,
                       "find (default: where a record's output jumps to a new level and stays there while the model's "
                       "output does not move, a sensor re-zeroed, the sensor gets a level of its own from there on; listed "
                       "under \"sensor_steps\") or ignore")
      ->check(CLI::IsMember({"find", "ignore"}));
  diagnose->add_flag("--json", d->json, "print the report as JSON (idrig.gap/1)");
  diagnose->add_option("--plots", d->plots, "also write SVG plots of the gap (frequency, amplitude, state, time, ranking) into this directory");
  diagnose->callback([d] {
    const TransferFunction sim = SimModelTransferFunction(ReadModelFile(d->sim));
    std::vector<GapRecord> estimation, validation;
    const bool named = !d->u_name.empty() || !d->y_name.empty() || !d->time_name.empty();
    if (named && (d->u_name.empty() || d->y_name.empty()))
      throw std::invalid_argument("records with their own column names need both --u and --y (and --time when "
                                  "the time column is not t or time)");
    const CsvColumns columns{{d->u_name}, {d->y_name}, d->time_name};
    auto read = [&](const std::string& path) { return named ? ReadIoRecordCsv(path, columns) : ReadIoRecordCsv(path); };
    for (const auto& p : d->data) estimation.push_back(ToGapRecord(read(p)));
    for (const auto& p : d->validate) validation.push_back(ToGapRecord(read(p)));
    GapOptions options;
    options.bridge_glitches = d->glitches == "bridge";
    options.fit_drift = d->drift == "fit";
    options.find_sensor_steps = d->sensor_steps == "find";
    const GapReport report = DiagnoseGap(sim, estimation, validation, options);
    nlohmann::json out = GapReportToJson(report);
    out["sim"] = d->sim;
    out["data"] = d->data;
    out["validate"] = d->validate;
    if (d->json) std::cout << out.dump(2) << "\n";
    else std::cout << GapReportText(out);
    if (!d->plots.empty())
      for (const auto& path : WriteGapReportSvgs(out, d->plots)) std::cerr << "wrote " << path << "\n";
  });

  struct ReportArgs {
    std::string source, plots, db = "idrig-demo/catalog.db";
  };
  auto r = std::make_shared<ReportArgs>();
  auto* report_cmd = gap->add_subcommand(
      "report", "render a stored diagnosis report as text, with SVG plots: a report id in the "
                "catalogue (workers' gap-diagnose jobs), or an idrig.gap/1 JSON file");
  report_cmd->add_option("report", r->source, "report id in the catalogue, or a file written by `gap diagnose --json`")
      ->required();
  report_cmd->add_option("--db", r->db, "catalogue file (idrig-catalog's db_path) for report ids");
  report_cmd->add_option("--plots", r->plots, "write SVG plots into this directory");
  report_cmd->callback([r] {
    nlohmann::json report;
    const bool is_id = !r->source.empty() &&
                       r->source.find_first_not_of("0123456789") == std::string::npos &&
                       !std::filesystem::exists(r->source);
    if (is_id) {
      if (!std::filesystem::exists(r->db))
        throw std::invalid_argument("no catalogue at '" + r->db + "' (give --db)");
      Catalog catalog(r->db, true);
      const auto stored = catalog.Diagnosis(std::stoll(r->source));
      if (!stored) throw std::invalid_argument("no diagnosis report " + r->source + " in " + r->db);
      report = nlohmann::json::parse(stored->report_json);
      std::cout << "report " << stored->report_id << ": rig " << stored->rig_id << ", experiment "
                << stored->experiment_id << ", request " << stored->request_id << ", model "
                << stored->model_id << "\n";
    } else {
      std::ifstream file(r->source);
      if (!file) throw std::invalid_argument("cannot open report '" + r->source + "'");
      try {
        report = nlohmann::json::parse(file);
      } catch (const nlohmann::json::parse_error& e) {
        throw std::invalid_argument(r->source + ": not valid JSON: " + e.what());
      }
    }
    if (report.value("format", "") != "idrig.gap/1")
      throw std::invalid_argument(r->source + ": not a gap report (format is not idrig.gap/1)");
    std::cout << GapReportText(report);
    if (!r->plots.empty())
      for (const auto& path : WriteGapReportSvgs(report, r->plots)) std::cout << "plot: " << path << "\n";
  });

  auto b = std::make_shared<BenchSettings>();
  auto* bench = gap->add_subcommand(
      "bench", "blind check: generate cases with withheld effects, diagnose them, score the verdicts");
  bench->add_option("--cases", b->cases, "number of cases (the 13 effects in turn)")->check(CLI::PositiveNumber);
  bench->add_option("--only", b->only,
                    "keep only the cases that withhold one of these effects (comma-separated; none for the "
                    "none cases); each kept case is the one at its index in the full sequence")
      ->delimiter(',');
  bench->add_option("--seed", b->seed, "seed of the case generator");
  bench->add_option("--snr", b->snr, "output SNR in dB");
  bench->add_option("--samples", b->samples, "samples per record")->check(CLI::Range(200, 10000000));
  bench->add_option("--ts", b->sample_time, "sample time [s] (the plants' corners are 0.7-15 rad/s)")
      ->check(CLI::Range(1e-5, 1.0));
  bench->add_option("--jobs", b->jobs, "parallel diagnoses")->check(CLI::Range(1, 64));
  bench->add_flag("--json", b->json, "print the summary as JSON");
  bench->add_option("--dump", b->dump, "also write each case (sim model, records, truth) to this directory");
  bench->add_option("--excitation", b->excitation, "levels, prbs, rbs, noise (band-limited Gaussian), steps (random staircase), chirp or multisine (periodic random-phase odd multisine, five periods) for every case (default: one of the first three drawn per case)")
      ->check(CLI::IsMember(BenchExcitations()));
  bench->add_flag("--integrating", b->integrating,
                  "integrating plants only (K/(s(Ts + 1)): position from force, a level from a flow)");
  bench->add_option("--plants", b->plants,
                    "plant family instead of the default (first order, mass-spring-damper, the two in series): "
                    "zeros (the series plant with a lead or non-minimum-phase zero) or two-mass (fourth order, "
                    "force on one mass, position of the other)")
      ->check(CLI::IsMember({"zeros", "two-mass"}));
  bench->add_option("--damping", b->damping,
                    "range LO,HI of the plants' damping ratio (default 0.15,0.8; e.g. 0.02,0.1 for lightly damped rigs)")
      ->expected(2)
      ->delimiter(',')
      ->check(CLI::Range(0.001, 5.0));
  bench->add_option("--noise-pole", b->noise_pole,
                    "colour the output noise: first-order pole A in [0, 0.99] (0: white; same variance)")
      ->check(CLI::Range(0.0, 0.99));
  bench->add_option("--process-noise", b->process_noise,
                    "share F in [0, 0.99] of the noise variance that enters at the plant's input as a load "
                    "disturbance (coloured by the plant; a random walk on an integrator); the rest is output noise")
      ->check(CLI::Range(0.0, 0.99));
  bench->add_flag("--offsets", b->offsets,
                  "random actuator offset (up to ±30 % of the command's peak) and sensor offset "
                  "(10–100 % of the output range) on every case");
  bench->add_option("--combos", b->combos,
                    "share F in [0, 1] of the cases with two effects that occur together on rigs");
  bench->add_option("--pairs", b->pairs,
                    "which pairs the two-effect cases draw: rig (default: pairs that occur together on rigs) "
                    "or any (every pair the rig can simulate together, 54)")
      ->check(CLI::IsMember({"rig", "any"}));
  bench->add_option("--add-glitches", b->add_glitches,
                    "sensor or acquisition glitches per record: runs of 1-3 samples, a spike 2-20 output spans off, "
                    "a dropout to zero or a reading stuck beyond the range")
      ->check(CLI::Range(0, 1000));
  bench->add_option("--glitches", b->glitches,
                    "bridge (default: output glitches bridged before fitting, as gap diagnose does) or keep")
      ->check(CLI::IsMember({"bridge", "keep"}));
  bench->add_option("--add-drift", b->add_drift,
                    "a slow sensor drift: a ramp to +S noise sigmas over the estimation record and to -S over the validation record, before the ADC")
      ->check(CLI::Range(0.0, 1e6));
  bench->add_option("--drift", b->drift, "fit (default, as gap diagnose does) or none: the sensor drift nuisance")
      ->check(CLI::IsMember({"fit", "none"}));
  bench->add_option("--sensor-steps", b->sensor_steps, "find (default, as gap diagnose does) or ignore")
      ->check(CLI::IsMember({"find", "ignore"}));
  bench->callback([b] { RunBench(*b); });
}

}  // namespace idrig
