// Subspace and prediction-error methods: speed, Monte Carlo against the Cramér–Rao bound, real
// data. Not run by ctest; driven by tests/benchmarks/subspace_pem_vs_octave.sh, which runs
// Octave's n4sid/moesp on the same files in the same run. Subcommands:
//   subspace_pem_benchmark speed OUT.csv              N = 10^5, 2x2, order 8 (writes the record)
//   subspace_pem_benchmark montecarlo DIR SIGMA SEEDS seed-001 plant, N = 2000: default method
//                                                     vs the bound (writes DIR/mc_<seed>.csv)
//   subspace_pem_benchmark real SHARED DIR            DaISy records, first half / second half
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "core/io/csv.h"
#include "core/io/model_json.h"
#include "core/methods/registry.h"
#include "core/numeric/time_domain/pem.h"
#include "core/numeric/time_domain/subspace.h"
#include "core/numeric/validation.h"

namespace {

using namespace idrig;
using Clock = std::chrono::steady_clock;

double CpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

Eigen::MatrixXd RandomBinary(int samples, int inputs, int hold, std::mt19937_64& rng) {
  std::bernoulli_distribution coin(0.5);
  Eigen::MatrixXd u(samples, inputs);
  for (int q = 0; q < inputs; ++q)
    for (int k = 0; k < samples; ++k) u(k, q) = (k % hold == 0) ? (coin(rng) ? 1.0 : -1.0) : u(k - 1, q);
  return u;
}

// ---------------------------------------------------------------- speed
int Speed(const std::string& out) {
  // 2x2, order 8: four damped pairs, B and C from a seeded generator, output noise 0.05.
  std::mt19937_64 rng(8);
  std::normal_distribution<double> normal(0.0, 1.0);
  StateSpace s;
  s.A = Eigen::MatrixXd::Zero(8, 8);
  const double radius[] = {0.95, 0.9, 0.85, 0.7}, angle[] = {0.2, 0.6, 1.2, 2.0};
  for (int k = 0; k < 4; ++k) {
    const double re = radius[k] * std::cos(angle[k]), im = radius[k] * std::sin(angle[k]);
    s.A.block(2 * k, 2 * k, 2, 2) << re, im, -im, re;
  }
  s.B = Eigen::MatrixXd::NullaryExpr(8, 2, [&] { return normal(rng); });
  s.C = Eigen::MatrixXd::NullaryExpr(2, 8, [&] { return normal(rng); });
  s.D = Eigen::MatrixXd::Zero(2, 2);
  s.sample_time = 1.0;
  const int n = 100000;
  const Eigen::MatrixXd u = RandomBinary(n, 2, 1, rng);
  Eigen::MatrixXd y = SimulateFrom(s, u, Eigen::VectorXd::Zero(8));
  for (int k = 0; k < n; ++k)
    for (int r = 0; r < 2; ++r) y(k, r) += 0.05 * normal(rng);
  const IoRecord record = MakeIoRecord(u, y, 1.0);
  WriteIoRecordCsv(record, out);
  for (auto w : {SubspaceWeighting::kMoesp, SubspaceWeighting::kN4sid, SubspaceWeighting::kCva}) {
    SubspaceOptions o;
    o.order = 8;
    o.block_rows = 16;  // Octave's default s = min(2n, n + 10) for n = 8
    o.weighting = w;
    std::vector<double> times, cpu;
    SubspaceResult r;
    for (int rep = 0; rep < 5; ++rep) {
      const auto t0 = Clock::now();
      const double c0 = CpuSeconds();
      r = IdentifySubspace(record, o);
      cpu.push_back(CpuSeconds() - c0);
      times.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    }
    std::sort(times.begin(), times.end());
    std::sort(cpu.begin(), cpu.end());
    std::printf("idrig n4sid weighting=%-5s N=%d 2x2 order 8 i=16: median %.4f s wall (min %.4f s), %.4f s CPU; "
                "fit y1 %.2f %% y2 %.2f %%\n",
                ToString(w), n, times[2], times[0], cpu[2], r.fit_per_output(0), r.fit_per_output(1));
  }
  return 0;
}

// ---------------------------------------------------------------- Monte Carlo
constexpr double kTs = 0.2;

TransferFunction Plant() {
  TransferFunction tf;
  tf.num = Eigen::Vector2d(0.5, 1.0);
  tf.den = Eigen::Vector4d(1.0, 2.5, 4.0, 1.5);
  return tf;
}

// Continuous poles s = ln(z)/Ts of a discrete model (or the poles of a continuous one),
// matched to the true poles (each true pole takes its nearest unused estimate).
Eigen::VectorXcd MatchedPoles(const LtiModel& model, const Eigen::VectorXcd& truth) {
  const StateSpace ss = ToStateSpace(model);
  Eigen::VectorXcd p = Poles(ss);
  if (ss.IsDiscrete())
    for (int i = 0; i < p.size(); ++i) p(i) = std::log(p(i)) / ss.sample_time;
  Eigen::VectorXcd out(truth.size());
  std::vector<bool> used(p.size(), false);
  for (int i = 0; i < truth.size(); ++i) {
    int best = -1;
    for (int j = 0; j < p.size(); ++j)
      if (!used[j] && (best < 0 || std::abs(p(j) - truth(i)) < std::abs(p(best) - truth(i)))) best = j;
    if (best < 0) { out(i) = std::complex<double>(1e3, 0); continue; }
    used[best] = true;
    out(i) = p(best);
  }
  return out;
}

// A complex pair is lost when the estimate's poles near the true pair are not a conjugate pair.
bool LostPair(const Eigen::VectorXcd& matched, const Eigen::VectorXcd& truth) {
  for (int i = 0; i < truth.size(); ++i)
    if (std::abs(truth(i).imag()) > 1e-9 && std::abs(matched(i).imag()) < 1e-9) return true;
  return false;
}

// Cramér–Rao bound of the continuous poles for the OE model y = B/F u + e under white noise
// σ²: FIM = Σ ψψᵀ/σ², ψ = ∂ŷ/∂θ at the true θ = (b, f) ([Ljung] Eq. (9.18)); poles z_i of F by
// ∂z_i/∂f_k = −z_i^{n−k}/F'(z_i), s_i = ln z_i / Ts. Returns E Σ_i |ŝ_i − s_i|² at the bound.
double PoleBound(const Eigen::MatrixXd& u, double sigma, const TransferFunction& g_discrete) {
  const int n = g_discrete.Order();
  const Eigen::VectorXd f = g_discrete.den / g_discrete.den(0);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  const Eigen::VectorXd num = g_discrete.num / g_discrete.den(0);
  b.tail(num.size()) = num;  // b_k of q^-k, k = 1..n (num in descending z, degree n−1)
  const long samples = u.rows();
  Eigen::VectorXd ushift = Eigen::VectorXd::Zero(samples);
  ushift.tail(samples - 1) = u.col(0).head(samples - 1);
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(1);
  const Eigen::VectorXd w = FilterPolynomial(b, f, ushift);
  const Eigen::VectorXd uf = FilterPolynomial(one, f, ushift), wf = FilterPolynomial(one, f, w);
  Eigen::MatrixXd psi(samples, 2 * n);
  auto shifted = [&](const Eigen::VectorXd& x, int k) {
    Eigen::VectorXd out = Eigen::VectorXd::Zero(samples);
    out.tail(samples - k) = x.head(samples - k);
    return out;
  };
  for (int k = 0; k < n; ++k) psi.col(k) = shifted(uf, k);          // ∂ŷ/∂b_{k+1}
  for (int k = 1; k <= n; ++k) psi.col(n + k - 1) = -shifted(wf, k);  // ∂ŷ/∂f_k
  const Eigen::MatrixXd cov = (psi.transpose() * psi / (sigma * sigma)).inverse();
  const Eigen::MatrixXd cov_f = cov.bottomRightCorner(n, n);
  const Eigen::VectorXcd z = PolynomialRoots(f);
  Eigen::MatrixXcd jac(n, n);
  for (int i = 0; i < n; ++i) {
    std::complex<double> dp = 0.0;  // F'(z) of z^n + f1 z^{n−1} + … + fn
    for (int k = 0; k < n; ++k) dp += static_cast<double>(n - k) * f(k) * std::pow(z(i), n - k - 1);
    for (int k = 1; k <= n; ++k) jac(i, k - 1) = -std::pow(z(i), n - k) / dp / (z(i) * kTs);
  }
  return (jac * cov_f * jac.adjoint()).trace().real();
}

int MonteCarlo(const std::string& dir, double sigma, int seeds) {
  const TransferFunction plant = Plant();
  const StateSpace discrete = DiscretizeZoh(ToStateSpace(plant), kTs);
  const TransferFunction g = ToTransferFunction(discrete);
  const Eigen::VectorXcd truth = Poles(plant);
  double bound_sum = 0.0;
  struct Stat { double sq = 0; int lost = 0, failed = 0, order_wrong = 0; };
  Stat stats[3];
  const char* names[3] = {"default (auto)", "oe order 3", "n4sid order 3"};
  std::ofstream truth_file(dir + "/mc_truth.txt");
  truth_file.precision(17);
  for (int i = 0; i < truth.size(); ++i) truth_file << truth(i).real() << " " << truth(i).imag() << "\n";
  int chosen_oe = 0;
  for (int s = 1; s <= seeds; ++s) {
    std::mt19937_64 rng(1000 + s);
    const Eigen::MatrixXd u = RandomBinary(2000, 1, 4, rng);
    Eigen::MatrixXd y = SimulateFrom(discrete, u, Eigen::VectorXd::Zero(3));
    std::normal_distribution<double> noise(0.0, sigma);
    for (int k = 0; k < y.rows(); ++k) y(k, 0) += noise(rng);
    const IoRecord record = MakeIoRecord(u, y, kTs);
    WriteIoRecordCsv(record, dir + "/mc_" + std::to_string(s) + ".csv");
    bound_sum += PoleBound(u, sigma, g);
    const MethodReport reports[3] = {RunMethod("auto", record, nlohmann::json::object()),
                                     RunMethod("oe", record, {{"order", 3}}),
                                     RunMethod("n4sid", record, {{"order", 3}})};
    chosen_oe += reports[0].json.value("chosen_method", "") == "oe";
    for (int m = 0; m < 3; ++m) {
      if (reports[m].json.value("status", "") != "ok") ++stats[m].failed;
      const LtiModel model = ModelFromJson(reports[m].json.at("model"));
      if (ToStateSpace(model).Order() != 3) ++stats[m].order_wrong;
      const Eigen::VectorXcd est = MatchedPoles(model, truth);
      stats[m].sq += (est - truth).squaredNorm();
      stats[m].lost += LostPair(est, truth);
    }
  }
  const double bound = std::sqrt(bound_sum / seeds);
  std::printf("sigma %.3g, %d seeds, N = 2000, Ts = 0.2 s, binary +-1 held 4 samples: Cramer-Rao bound on the RMS "
              "continuous-pole error %.5f\n", sigma, seeds, bound);
  for (int m = 0; m < 3; ++m) {
    const double rms = std::sqrt(stats[m].sq / seeds);
    std::printf("  %-15s RMS pole error %.5f = %.2f x bound; lost pair %d, status not ok %d, order != 3 %d\n", names[m], rms,
                rms / bound, stats[m].lost, stats[m].failed, stats[m].order_wrong);
  }
  std::printf("  (default chose oe on %d of %d seeds)\n", chosen_oe, seeds);
  std::ofstream(dir + "/mc_bound.txt") << bound << "\n";
  return 0;
}

// ---------------------------------------------------------------- real data
struct RealRecord {
  std::string name, file;
  std::vector<int> inputs, outputs;  // 0-based columns of the .dat file
  double ts;
};

Eigen::MatrixXd ReadDat(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<double>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<double> row;
    const char* p = line.c_str();
    char* end = nullptr;
    for (double v = std::strtod(p, &end); end != p; v = std::strtod(p, &end)) {
      row.push_back(v);
      p = end;
    }
    if (!row.empty()) rows.push_back(row);
  }
  Eigen::MatrixXd m(rows.size(), rows.empty() ? 0 : rows[0].size());
  for (size_t r = 0; r < rows.size(); ++r)
    for (size_t c = 0; c < rows[r].size(); ++c) m(r, c) = rows[r][c];
  return m;
}

double ValidationFit(const LtiModel& model, const IoRecord& full, int split, Eigen::VectorXd* per_output) {
  const Eigen::MatrixXd sim = Simulate(model, full.u, full.sample_time);
  *per_output = FitPercent(full.y.bottomRows(full.NumSamples() - split), sim.bottomRows(full.NumSamples() - split));
  return per_output->mean();
}

int Real(const std::string& shared, const std::string& dir) {
  const std::vector<RealRecord> records = {
      {"dryer", "dryer.dat", {0}, {1}, 0.08},       {"exchanger", "exchanger.dat", {1}, {2}, 1.0},
      {"robot_arm", "robot_arm.dat", {0}, {1}, 1.0}, {"flutter", "flutter.dat", {0}, {1}, 1.0},
      {"CD_player_arm", "CD_player_arm.dat", {0, 1}, {2, 3}, 1.0},
      {"winding", "winding.dat", {0, 1, 2, 3, 4}, {5, 6}, 0.1}};
  std::ofstream list(dir + "/real_list.txt");
  for (const auto& rec : records) {
    const std::string path = shared + "/data/daisy/" + rec.file;
    if (!std::ifstream(path)) { std::printf("%-14s skip: %s not found\n", rec.name.c_str(), path.c_str()); continue; }
    const Eigen::MatrixXd dat = ReadDat(path);
    const int samples = static_cast<int>(dat.rows()), split = samples / 2;
    Eigen::MatrixXd u(samples, rec.inputs.size()), y(samples, rec.outputs.size());
    for (size_t j = 0; j < rec.inputs.size(); ++j) u.col(j) = dat.col(rec.inputs[j]);
    for (size_t j = 0; j < rec.outputs.size(); ++j) y.col(j) = dat.col(rec.outputs[j]);
    // Means of the estimation half removed from both halves (the same for Octave).
    const Eigen::RowVectorXd um = u.topRows(split).colwise().mean(), ym = y.topRows(split).colwise().mean();
    u.rowwise() -= um;
    y.rowwise() -= ym;
    const IoRecord full = MakeIoRecord(u, y, rec.ts), est = Slice(full, 0, split);
    WriteIoRecordCsv(full, dir + "/real_" + rec.name + ".csv");
    const auto t0 = Clock::now();
    const MethodReport def = RunMethod("auto", est, nlohmann::json::object());
    const double t_auto = std::chrono::duration<double>(Clock::now() - t0).count();
    const int order = def.json.at("selection").at("chosen").at("order");
    Eigen::VectorXd per;
    const double fit_default = ValidationFit(ModelFromJson(def.json.at("model")), full, split, &per);
    std::string per_text;
    for (int k = 0; k < per.size(); ++k) per_text += (k ? "/" : "") + std::to_string(per(k)).substr(0, 5);
    std::printf("%-14s N=%d nu=%d ny=%d  default: %s n=%d fit %.1f %% (%s) [%.2f s]", rec.name.c_str(), samples,
                full.NumInputs(), full.NumOutputs(),
                def.json.at("selection").at("chosen").value("candidate", "?").c_str(), order, fit_default,
                per_text.c_str(), t_auto);
    std::ofstream results(dir + "/real_idrig_" + rec.name + ".txt");
    std::string label = def.json.at("selection").at("chosen").value("candidate", "?");
    std::replace(label.begin(), label.end(), ' ', '_');
    results << rec.name << " default " << order << " " << fit_default << " " << label << "\n";
    {  // the same folds split by sample count (option split=samples), for comparison
      const MethodReport by_samples = RunMethod("auto", est, {{"split", "samples"}});
      std::string l = by_samples.json.at("selection").at("chosen").value("candidate", "?");
      std::replace(l.begin(), l.end(), ' ', '_');
      const double f = ValidationFit(ModelFromJson(by_samples.json.at("model")), full, split, &per);
      results << rec.name << " bysamples " << by_samples.json.at("selection").at("chosen").at("order").get<int>() << " "
              << f << " " << l << "\n";
      std::printf(" | split=samples: %s n=%d fit %.1f %%", l.c_str(),
                  by_samples.json.at("selection").at("chosen").at("order").get<int>(), f);
    }
    for (int n = 1; n <= 8; ++n) {
      const std::pair<const char*, nlohmann::json> variants[] = {
          {"n4sid", {{"order", n}}}, {"n4sid_D", {{"order", n}, {"feedthrough", true}}},
          {"oe", {{"order", n}}}, {"oe_nk0", {{"order", n}, {"input_delay", 0}}}};
      for (const auto& [m, options] : variants) {
        double fit = NAN;
        try {
          const std::string method = std::string(m).substr(0, std::string(m).find('_'));
          const MethodReport r = RunMethod(method, est, options);
          if (!r.json.at("model").is_null()) fit = ValidationFit(ModelFromJson(r.json.at("model")), full, split, &per);
        } catch (const std::exception& e) {
          if (n == order) std::printf(" [%s: %s]", m, e.what());
        }
        if (n == order) std::printf("  %s %.1f %%", m, fit);
        results << rec.name << " " << m << " " << n << " " << fit << "\n";
      }
    }
    std::printf("\n");
    std::fflush(stdout);
    list << rec.name << " " << order << " " << fit_default << " " << rec.inputs.size() << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string cmd = argc > 1 ? argv[1] : "";
  if (cmd == "speed" && argc > 2) return Speed(argv[2]);
  if (cmd == "montecarlo" && argc > 4) return MonteCarlo(argv[2], std::atof(argv[3]), std::atoi(argv[4]));
  if (cmd == "real" && argc > 3) return Real(argv[2], argv[3]);
  std::fprintf(stderr, "usage: %s speed OUT.csv | montecarlo DIR SIGMA SEEDS | real SHARED DIR\n", argv[0]);
  return 2;
}
