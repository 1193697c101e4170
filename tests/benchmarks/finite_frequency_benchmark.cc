// Scatter of the natural-frequency range experiments 4.1/5.1 of [Aleksandrov] under the
// disturbance (39), single runs at the paper's settings (docs/finite_frequency.md, section 7):
//   build/bin/finite_frequency_benchmark --seeds 100
// prints, for each experiment and each reading of (39) (SquareWavePhase), the mean, sd and
// share within ±10 % of T(ω_1, τ)/T_exact − 1 over seeds 1..N, and the rms of the
// filterability functions ℓ^α, ℓ^β (7) of the disturbance's own output. The disturbance acts
// 100 s before t0 (as in finite_frequency_test). Without --seeds: Google Benchmark timings of
// one experiment.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "core/numeric/finite_frequency/finite_frequency.h"
#include "core/numeric/finite_frequency/sine_experiment.h"

namespace {

using namespace idrig;
constexpr double kTwoPi = 6.283185307179586476925286766559;

TransferFunction Plant40() {
  TransferFunction w;
  w.num = Eigen::Vector2d(-0.4, 1.0);
  w.den = Eigen::Vector4d(0.2, 1.24, 5.24, 1.0);
  return w;
}

struct Run {
  double error, ell_alpha, ell_beta;
};

// One experiment at the paper's settings as RunRangeExperiment does it (h <= 0.01 s, >= 400
// samples per period, τ rounded to whole periods), returning T/T_exact − 1 and ℓ^α, ℓ^β.
Run Experiment(double omega, double rho, double tau, bool upper, uint64_t seed,
               SquareWavePhase phase) {
  const double period = kTwoPi / omega;
  const int per = std::max(400, static_cast<int>(std::ceil(period / 0.01)));
  const double h = period / per;
  const int periods = std::max(1, static_cast<int>(std::lround(tau / period)));
  const long n = static_cast<long>(periods) * per + 1;
  SineExperimentSetup setup;
  setup.plant = Plant40();
  setup.lines = {{omega, rho, 0.0}};
  setup.disturbance = RandomSquareWaveDisturbance(5.0, 3.0, 5.0, n * h + 1.0, seed, phase, -100.0);
  const auto record = SimulateSineExperiment(setup, h, n);
  FiniteFrequencySignal signal;
  signal.base_omega = omega;
  signal.multiples = {1};
  signal.amplitudes = {rho};
  const auto total = FourierFilterPerBasePeriod(record.y, h, signal, 0.0, periods).back();
  const auto natural = FourierFilterPerBasePeriod(record.natural_output, h, signal, 0.0, periods).back();
  const auto g = FrequencyResponse(Plant40(), omega);
  const double exact = upper ? UpperTimeConstant(g.real(), g.imag(), omega, 2)
                             : LowerTimeConstant(g.real(), g.imag(), omega);
  const double t = upper ? UpperTimeConstant(total.alpha[0], total.beta[0], omega, 2)
                         : LowerTimeConstant(total.alpha[0], total.beta[0], omega);
  return {t / exact - 1.0, natural.alpha[0], natural.beta[0]};
}

void Scatter(int seeds) {
  struct Setting {
    const char* name;
    double omega, rho, tau;
    bool upper;
  };
  const Setting settings[] = {{"4.1 w1=0.05 tau=3750", 0.05, 0.03, 3750, false},
                              {"4.1 w1=0.0135 tau=4800", 0.0135, 0.03, 4800, false},
                              {"5.1 w1=20 tau=6.28", 20, 1.0, 6.28, true},
                              {"5.1 w1=74 tau=3.14", 74, 1.0, 3.14, true},
                              {"5.1 w1=20 tau=400", 20, 1.0, 400, true}};
  std::printf("| experiment | reading of (39) | mean | sd | within ±10 %% | rms l_alpha | rms l_beta |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const Setting& s : settings) {
    for (const SquareWavePhase phase : {SquareWavePhase::kPeriodStart, SquareWavePhase::kExperimentTime}) {
      double sum = 0, sum2 = 0, la = 0, lb = 0;
      int within = 0;
      for (int seed = 1; seed <= seeds; ++seed) {
        const Run r = Experiment(s.omega, s.rho, s.tau, s.upper, seed, phase);
        sum += r.error;
        sum2 += r.error * r.error;
        la += r.ell_alpha * r.ell_alpha;
        lb += r.ell_beta * r.ell_beta;
        within += std::abs(r.error) <= 0.10;
      }
      const double mean = sum / seeds;
      std::printf("| %s | %s | %+.1f %% | %.1f %% | %d/%d | %.4f | %.4f |\n", s.name,
                  phase == SquareWavePhase::kPeriodStart ? "kPeriodStart" : "kExperimentTime",
                  100 * mean, 100 * std::sqrt(std::max(0.0, sum2 / seeds - mean * mean)), within,
                  seeds, std::sqrt(la / seeds), std::sqrt(lb / seeds));
      std::fflush(stdout);
    }
  }
}

void BM_LowerBoundExperiment(benchmark::State& state) {
  uint64_t seed = 1;
  for (auto _ : state)
    benchmark::DoNotOptimize(Experiment(0.05, 0.03, 3750, false, seed++, SquareWavePhase::kPeriodStart));
}
BENCHMARK(BM_LowerBoundExperiment)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--seeds") == 0) {
      Scatter(std::stoi(argv[i + 1]));
      return 0;
    }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
