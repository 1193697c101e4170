// idrig excite --signal SPEC --fs HZ --duration S --out FILE.csv [--max-abs A] [--max-rate R]
// Writes an excitation signal offline as CSV with header `t,u`: samples t_k = k/fs for
// 0 <= t_k < duration, generated sample by sample exactly as the real-time excitation service
// does. The SPEC grammar is in docs/excitation.md.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include "core/numeric/signal/excitation.h"
#include "tools/idrig/commands.h"

namespace idrig {

namespace {

// Streams `t,u` rows with round-trip precision (17 significant digits).
void WriteExcitationCsv(ExcitationGenerator& generator, int64_t samples, std::ostream& out) {
  out << "t,u\n";
  char line[64];
  for (int64_t k = 0; k < samples; ++k) {
    const double t = generator.time();
    const double u = generator.Next();
    std::snprintf(line, sizeof line, "%.17g,%.17g\n", t, u);
    out << line;
  }
}

}  // namespace

void RegisterExciteCommand(CLI::App& app) {
  struct Args {
    std::string signal, out;
    double sample_rate_hz = 0.0, duration_s = 0.0, max_abs = 0.0, max_rate = 0.0;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "excite", "write an excitation signal as CSV (t,u); SPEC grammar: docs/excitation.md, "
                "e.g. prbs:bits=10,amp=1  multisine:f0=0.1,lines=1-20,set=odd,phase=schroeder");
  cmd->add_option("--signal", args->signal, "signal SPEC, kind:key=value,...")->required();
  cmd->add_option("--fs", args->sample_rate_hz, "sample rate [Hz]")
      ->required()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--duration", args->duration_s, "duration [s]: samples k/fs < duration")
      ->required()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", args->out, "CSV file to write; '-' for stdout")->required();
  cmd->add_option("--max-abs", args->max_abs, "reject the signal if |u| exceeds this (0: off)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--max-rate", args->max_rate,
                  "reject the signal if |u_k - u_k-1|*fs exceeds this [1/s] (0: off)")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([args] {
    const ExcitationSpec spec = ParseExcitationSpec(args->signal);
    const double exact_samples = args->duration_s * args->sample_rate_hz;
    const int64_t samples = static_cast<int64_t>(std::ceil(exact_samples - 1e-9));
    if (samples < 1 || exact_samples > 1e9)
      throw std::invalid_argument("--duration * --fs gives " + std::to_string(exact_samples) +
                                  " samples; it must be between 1 and 1e9");
    ExcitationLimits limits;
    limits.max_abs = args->max_abs;
    limits.max_rate = args->max_rate;
    limits.horizon_s = args->duration_s;
    AcceptExcitation(spec, args->sample_rate_hz, limits);  // throws on a violated bound
    ExcitationGenerator generator(spec, args->sample_rate_hz);
    if (args->out == "-") {
      WriteExcitationCsv(generator, samples, std::cout);
      return;
    }
    std::ofstream file(args->out);
    if (!file) throw std::runtime_error("cannot write '" + args->out + "'");
    WriteExcitationCsv(generator, samples, file);
    file.close();
    if (!file) throw std::runtime_error("write to '" + args->out + "' failed");
    const double period = ExcitationPeriod(spec, args->sample_rate_hz);
    std::cerr << "wrote " << args->out << ": " << FormatExcitationSpec(spec) << ", " << samples
              << " samples at " << args->sample_rate_hz << " Hz"
              << (period > 0 ? ", period " + std::to_string(period) + " s" : std::string())
              << "\n";
  });
}

}  // namespace idrig
