// Frequency-domain maximum likelihood against the Cramér–Rao bound (issue 15). Not run by ctest.
//   frequency_ml_benchmark [SEEDS] [DUMP_DIR]   (part 2, a time record, is described at TimeRecord)
// With DUMP_DIR, part 1's FRFs are written there (frf_<seed>.csv with a sigma column, poles.csv,
// crb.txt) for tests/benchmarks/frequency_ml_vs_octave.sh, and part 2 is skipped.
// Seed 001's plant W(p) = (0.5p + 1)/(p³ + 2.5p² + 4p + 1.5), 200 lines log-spaced over
// 0.05–20 rad/s, complex noise relative to |G|: e_k = 0.01·|G_k|·(n₁ + j n₂)/√2 (E|e_k|² = σ_k²,
// σ_k = 1 % of |G_k|). Fits: levy-sk and stable-nls unweighted, weighted by 1/|G̃_k| (the
// measured magnitude: weight=inverse_magnitude) and by 1/σ_k (the true σ: a `sigma` column).
// The bound: θ = (a₀, a₁, a₂, b₀, b₁) of G = B/A, J_kj = ∂G(jω_k)/∂θ_j (∂G/∂a_j = −G s^j/A,
// ∂G/∂b_j = s^j/A), FIM = 2 Re(Jᴴ Σ⁻¹ J) with Σ = diag(σ_k²) (σ_k² = E|e_k|², so 2Re(·) is the
// brief's Re(JᴴΣ⁻¹J) with σ² per real part); the poles' covariance D·FIM⁻¹·Dᴴ with
// ∂p_i/∂a_j = −p_i^j/A′(p_i); the bound on the RMS pole error is √trace. The RMS error over
// the seeds is √(mean_seeds Σ_i |p̂_i − p_i|²), each true pole matched to the nearest estimate.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include "core/io/csv.h"
#include "core/io/frf_csv.h"
#include "core/methods/registry.h"
#include "core/numeric/frequency_domain/stable_nls.h"
#include "tests/unit/numeric/frequency_domain/frf_crb.h"

namespace {

using namespace idrig;
using idrig::testing::PoleCrb;
using idrig::testing::SquaredPoleError;
using Complex = std::complex<double>;

Eigen::VectorXd LogLines(int n, double lo, double hi) {
  Eigen::VectorXd w(n);
  for (int k = 0; k < n; ++k) w(k) = lo * std::pow(hi / lo, k / (n - 1.0));
  return w;
}

// Part 2, a time record: seed 001's plant under a random binary ±1 input held 4 samples,
// N = 2000, Ts = 0.2 s, white output noise σ; the FRF by Welch up to Nyquist (the methods' own
// estimate), levy-sk and stable-nls at order 3/1 through the registry, unweighted (weight=none)
// and with the default (weight=auto: 1/σ_k from the Welch variance, i.e. the coherence).
void TimeRecord(int seeds, double noise) {
  TransferFunction plant;
  plant.num = Eigen::Vector2d(0.5, 1.0);
  plant.den = Eigen::Vector4d(1.0, 2.5, 4.0, 1.5);
  const Eigen::VectorXcd poles = Poles(plant);
  const double ts = 0.2, nyquist = 3.14159265358979323846 / ts;
  const char* methods[2] = {"levy-sk", "stable-nls"};
  const char* weights[2] = {"none", "auto"};
  double sq[2][2] = {};
  int at_nyquist[2][2] = {}, ok[2][2] = {}, ok_at_nyquist[2][2] = {};
  const std::string path = "/tmp/frequency_ml_benchmark_record.csv";
  for (int seed = 1; seed <= seeds; ++seed) {
    std::mt19937_64 rng(1000 + seed);
    std::bernoulli_distribution coin;
    std::normal_distribution<double> n01;
    const int n = 2000;
    Eigen::MatrixXd u(n, 1);
    for (int k = 0; k < n; k += 4) {
      const double level = coin(rng) ? 1.0 : -1.0;
      for (int i = k; i < std::min(n, k + 4); ++i) u(i, 0) = level;
    }
    Eigen::MatrixXd y = Simulate(LtiModel(plant), u, ts);
    for (int k = 0; k < n; ++k) y(k, 0) += noise * n01(rng);
    WriteIoRecordCsv(MakeIoRecord(u, y, ts), path);
    for (int m = 0; m < 2; ++m)
      for (int w = 0; w < 2; ++w) {
        const MethodReport r = RunMethod(methods[m], path, {{"order", 3}, {"numerator_degree", 1}, {"weight", weights[w]}});
        Eigen::VectorXcd est(r.json["details"]["poles"].size());
        bool nyq = false;
        for (int i = 0; i < est.size(); ++i) {
          est(i) = Complex(r.json["details"]["poles"][i][0].get<double>(), r.json["details"]["poles"][i][1].get<double>());
          nyq |= std::abs(est(i).imag()) >= 0.9 * nyquist;
        }
        sq[m][w] += SquaredPoleError(poles, est) / seeds;
        at_nyquist[m][w] += nyq;
        const bool is_ok = r.json["status"] == "ok";
        ok[m][w] += is_ok;
        ok_at_nyquist[m][w] += is_ok && nyq;
      }
  }
  std::remove(path.c_str());
  std::printf("\ntime record, sigma = %.3g, %d seeds (Welch FRF up to Nyquist):\n", noise, seeds);
  std::printf("| method | weight | RMS pole error | pole at >= 0.9 Nyquist | status ok | ok with a Nyquist pole |\n|---|---|---|---|---|---|\n");
  for (int m = 0; m < 2; ++m)
    for (int w = 0; w < 2; ++w)
      std::printf("| %s | %s | %.4g | %d | %d | %d |\n", methods[m], weights[w], std::sqrt(sq[m][w]), at_nyquist[m][w],
                  ok[m][w], ok_at_nyquist[m][w]);
}

}  // namespace

int main(int argc, char** argv) {
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 50;
  const std::string dump = argc > 2 ? argv[2] : "";
  TransferFunction plant;
  plant.num = Eigen::Vector2d(0.5, 1.0);
  plant.den = Eigen::Vector4d(1.0, 2.5, 4.0, 1.5);
  const Eigen::VectorXcd poles = Poles(plant);
  const Eigen::VectorXd omega = LogLines(200, 0.05, 20.0);
  const Eigen::VectorXcd g0 = FrequencyResponse(plant, omega);
  const Eigen::VectorXd sigma = 0.01 * g0.cwiseAbs();
  const double crb = PoleCrb(plant, omega, sigma);
  std::printf("seed 001 plant, 200 lines 0.05-20 rad/s, 1 %% relative complex noise, %d seeds\n", seeds);
  std::printf("Cramer-Rao bound on the RMS pole error: %.4g\n", crb);
  const char* fits[3] = {"levy-sk (SK only)", "levy-sk + ML refinement", "stable-nls"};
  const char* weightings[3] = {"no weights", "1/|G measured|", "1/sigma"};
  double sq[3][3] = {};
  int not_ok[3][3] = {};
  for (int seed = 1; seed <= seeds; ++seed) {
    const Eigen::VectorXcd g = idrig::testing::WithComplexNoise(g0, sigma, seed);
    const Frf frf = MakeSisoFrf(omega, g);
    if (!dump.empty()) {
      Frf with_sigma = frf;
      with_sigma.variance = sigma.array().square().matrix();
      WriteFrfCsv(with_sigma, dump + "/frf_" + std::to_string(seed) + ".csv");
    }
    const Eigen::VectorXd weights[3] = {Eigen::VectorXd(), g.cwiseAbs().cwiseInverse(), sigma.cwiseInverse()};
    for (int v = 0; v < 3; ++v) {
      for (int refine = 0; refine < 2; ++refine) {
        LevyOptions lo;
        lo.denominator_degree = 3;
        lo.numerator_degree = 1;
        lo.weights = weights[v];
        lo.refine_output_error = refine;
        const LevyResult l = FitLevy(frf, lo);
        sq[refine][v] += SquaredPoleError(poles, l.poles) / seeds;
        not_ok[refine][v] += !l.ok();
      }
      StableNlsOptions so;
      so.denominator_degree = 3;
      so.numerator_degree = 1;
      so.weights = weights[v];
      const StableNlsResult s = FitStableNls(frf, so);
      sq[2][v] += SquaredPoleError(poles, s.poles) / seeds;
      not_ok[2][v] += !s.ok();
    }
  }
  std::printf("| fit | weights | RMS pole error | / CRB | not ok |\n|---|---|---|---|---|\n");
  for (int f = 0; f < 3; ++f)
    for (int v = 0; v < 3; ++v)
      std::printf("| %s | %s | %.4g | %.2f | %d of %d |\n", fits[f], weightings[v], std::sqrt(sq[f][v]),
                  std::sqrt(sq[f][v]) / crb, not_ok[f][v], seeds);
  if (!dump.empty()) {
    std::FILE* p = std::fopen((dump + "/poles.csv").c_str(), "w");
    for (int i = 0; i < poles.size(); ++i) std::fprintf(p, "%.17g,%.17g\n", poles(i).real(), poles(i).imag());
    std::fclose(p);
    std::FILE* c = std::fopen((dump + "/crb.txt").c_str(), "w");
    std::fprintf(c, "%.17g\n", crb);
    std::fclose(c);
    return 0;
  }
  TimeRecord(seeds, 0.01);
  TimeRecord(seeds, 0.05);
  return 0;
}
