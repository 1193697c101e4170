// ARX throughput and memory: N = 10^3 … 10^6 samples, orders 3 and 10.
//   build/bin/arx_benchmark --benchmark_counters_tabular=true
// validate = 0: estimate, ε by GCV and all five forms (comparable to Octave's arx);
// validate = 1: plus simulation fit and residual tests on the record.
// Counters: samples/s, and peak resident memory growth over the record itself (the equations
// are reduced by QR in blocks, so it must not grow with N).
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <random>

#include "core/numeric/time_domain/arx.h"

namespace {

long PeakRssKb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

idrig::IoRecord Record(long samples) {
  idrig::TransferFunction plant;
  plant.num = Eigen::Vector2d(0.5, 1.0);
  plant.den = Eigen::Vector4d(1.0, 2.5, 4.0, 1.5);
  std::mt19937_64 rng(7);
  std::bernoulli_distribution coin(0.5);
  std::normal_distribution<double> noise(0.0, 0.01);
  Eigen::MatrixXd u(samples, 1);
  for (long k = 0; k < samples; ++k) u(k, 0) = coin(rng) ? 1.0 : -1.0;
  Eigen::MatrixXd y = idrig::Simulate(plant, u, 0.2);
  for (long k = 0; k < samples; ++k) y(k, 0) += noise(rng);
  return idrig::MakeIoRecord(u, y, 0.2);
}

void BM_Arx(benchmark::State& state) {
  const long samples = state.range(0);
  const int order = static_cast<int>(state.range(1));
  const idrig::IoRecord record = Record(samples);
  idrig::ArxOptions options;
  options.order = order;
  options.recover_continuous = order <= 3;
  options.validate = state.range(2) != 0;  // 0: estimate + all forms only (what Octave's arx does)
  const long rss_before = PeakRssKb();
  for (auto _ : state) {
    idrig::ArxResult result = idrig::IdentifyArx(record, options);
    benchmark::DoNotOptimize(result.g);
  }
  state.counters["samples/s"] = benchmark::Counter(static_cast<double>(samples) * state.iterations(),
                                                   benchmark::Counter::kIsRate);
  state.counters["peak_rss_growth_kB"] = static_cast<double>(PeakRssKb() - rss_before);
  state.counters["record_kB"] = samples * 3 * 8 / 1024.0;
}

BENCHMARK(BM_Arx)
    ->ArgNames({"N", "order", "validate"})
    ->ArgsProduct({{1000, 10000, 100000, 200000, 1000000}, {3, 10}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
