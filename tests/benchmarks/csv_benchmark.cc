// Reading records (issue 15): core/io's one-pass parser (csv_scan.h: string_views, from_chars)
// against the parser it replaced (std::getline + a stringstream per line + strtod, a vector per
// row), copied here as `Reference` so that both run on the same text in the same run.
//   build/bin/csv_benchmark --benchmark_counters_tabular=true
// The text: seed 001's example record as `idrig example` writes it (t,u,y, 17 digits), 2·10^5
// samples (and 10^4, 10^6).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/csv.h"
#include "core/io/frf_csv.h"

namespace {

using namespace idrig;

std::string RecordText(int n) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  IoRecord r = MakeIoRecord(Eigen::MatrixXd::Zero(n, 1), Eigen::MatrixXd::Zero(n, 1), 0.2);
  double x = 0.0;
  for (int k = 0; k < n; ++k) {
    r.u(k, 0) = n01(rng) > 0 ? 1.0 : -1.0;
    x = 0.95 * x + 0.05 * r.u(k, 0);
    r.y(k, 0) = x + 0.01 * n01(rng);
  }
  return FormatIoRecordCsv(r);
}

// The parser before issue 15 (core/io/csv.cc at fe97319), data rows only.
std::vector<std::vector<double>> Reference(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);  // header
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) {
      const auto b = field.find_first_not_of(" \t\r\n\"");
      const auto e = field.find_last_not_of(" \t\r\n\"");
      fields.push_back(b == std::string::npos ? "" : field.substr(b, e - b + 1));
    }
    std::vector<double> row(fields.size());
    for (size_t c = 0; c < fields.size(); ++c) {
      char* end = nullptr;
      row[c] = std::strtod(fields[c].c_str(), &end);
      if (*end != '\0') std::abort();
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

void BM_ParseRecord(benchmark::State& state) {
  const std::string text = RecordText(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(ParseIoRecordCsv(text));
  state.counters["samples/s"] = benchmark::Counter(static_cast<double>(state.range(0)) * state.iterations(),
                                                   benchmark::Counter::kIsRate);
  state.counters["MB/s"] = benchmark::Counter(text.size() * 1e-6 * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ParseRecord)->ArgName("N")->Arg(10000)->Arg(200000)->Arg(1000000)->Unit(benchmark::kMillisecond);

void BM_ParseRecordReference(benchmark::State& state) {
  const std::string text = RecordText(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(Reference(text));
  state.counters["samples/s"] = benchmark::Counter(static_cast<double>(state.range(0)) * state.iterations(),
                                                   benchmark::Counter::kIsRate);
  state.counters["MB/s"] = benchmark::Counter(text.size() * 1e-6 * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ParseRecordReference)->ArgName("N")->Arg(10000)->Arg(200000)->Unit(benchmark::kMillisecond);

// An FRF table of 2·10^5 lines through the same scanner.
void BM_ParseFrf(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::ostringstream s;
  s.precision(17);
  s << "f_hz,re,im\n";
  for (int k = 0; k < n; ++k) s << 0.01 * (k + 1) << "," << std::cos(0.001 * k) << "," << std::sin(0.001 * k) << "\n";
  const std::string text = s.str();
  for (auto _ : state) benchmark::DoNotOptimize(ParseFrfCsv(text));
  state.counters["lines/s"] = benchmark::Counter(static_cast<double>(n) * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ParseFrf)->ArgName("lines")->Arg(200000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
