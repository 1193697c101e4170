// Even/odd detection lines of a periodic odd multisine (gap_noise.h, after Pintelon and
// Schoukens, System Identification: A Frequency Domain Approach, 2nd ed.: §3.5 the odd random
// phase multisine and its detection lines, §4.3 noise from periods and the BLA's variances).
#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

#include "core/numeric/gap/gap_diagnosis.h"
#include "core/numeric/gap/gap_noise.h"

namespace idrig {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// 99.9 % level of |Ȳ|²/σ̂² for a line with noise only: F(2, 2(M−1)), whose tail is
// (1 + x/(M−1))^−(M−1).
double LineThreshold(int periods) {
  const double m1 = periods - 1;
  return m1 * (std::pow(0.001, -1.0 / m1) - 1);
}

// Distortion is "present" on a class of lines when more of them exceed the 99.9 % level than
// chance allows (binomial, p = 0.001, mean + 3σ + 1).
bool MoreThanChance(int significant, int lines) {
  const double expected = 0.001 * lines;
  return significant > expected + 3 * std::sqrt(0.001 * 0.999 * lines) + 1;
}

double Db(double ratio) { return ratio > 0 ? 10 * std::log10(ratio) : -300.0; }

}  // namespace

DetectionLines AnalyseDetectionLines(const std::vector<GapRecord>& records, const TransferFunction* sim) {
  DetectionLines d;
  const GapRecord* record = nullptr;
  Periodicity p;
  for (const auto& r : records) {
    p = FindPeriod(r.u);
    if (p.period > 0) {
      record = &r;
      break;
    }
  }
  if (!record) {
    d.reason = "no record with a periodic input (two periods at least)";
    return d;
  }
  const int n = p.period;
  const int first = SteadyPeriodStart(record->y, p);
  const int m = p.periods - first;
  d.period_samples = n;
  d.periods = m;
  d.steady_from = first;
  d.f0_hz = 1.0 / (n * record->sample_time);
  const int half = (n - 1) / 2;  // lines 1 … half (below Nyquist)
  Eigen::FFT<double> fft;
  std::vector<double> su(n), sy(n);
  std::vector<std::complex<double>> fu, fy;
  std::vector<std::complex<double>> u_mean(half + 1, 0.0), y_mean(half + 1, 0.0);
  std::vector<std::vector<std::complex<double>>> y_periods;
  // A ramp (an integrating plant's integrated offset) leaks into every line as a sawtooth: it is
  // taken off as the line through the period means.
  const double drift = PeriodDrift(record->y, p, first);
  for (int j = first; j < p.periods; ++j) {
    for (int k = 0; k < n; ++k) {
      const long t = static_cast<long>(j) * n + k;
      su[k] = record->u(t);
      sy[k] = record->y(t) - drift * t;
    }
    fft.fwd(fu, su);
    fft.fwd(fy, sy);
    y_periods.emplace_back(fy.begin(), fy.begin() + half + 1);
    for (int k = 1; k <= half; ++k) {
      u_mean[k] += fu[k] / double(m);
      y_mean[k] += fy[k] / double(m);
    }
  }
  double u_peak = 0;
  for (int k = 1; k <= half; ++k) u_peak = std::max(u_peak, std::norm(u_mean[k]));
  std::vector<int> kind(half + 1, 0);  // 1 excited, 0 not
  int top = 0, even_excited = 0, excited = 0;
  for (int k = 1; k <= half; ++k)
    if (std::norm(u_mean[k]) > 1e-4 * u_peak) {  // −40 dB: a measured input's noise stays below
      kind[k] = 1;
      top = k;
      ++excited;
      if (k % 2 == 0) ++even_excited;
    }
  if (excited < 3) {
    d.reason = "the periodic input excites fewer than 3 lines";
    return d;
  }
  if (even_excited > 0) {
    d.reason = "the periodic input excites even lines (" + std::to_string(even_excited) + " of " +
               std::to_string(excited) + "): not an odd multisine, so no even detection lines";
    return d;
  }
  if (m < 2) {
    d.reason = "one steady period only: no noise estimate per line";
    return d;
  }
  d.available = true;
  d.excited = excited;
  const double threshold = LineThreshold(m);
  // G0 as the records see it: sampled with a zero-order hold (the half-sample lag and the sinc
  // of the hold are in the data, not in the continuous G0).
  StateSpace sim_zoh;
  if (sim) {
    TransferFunction undelayed = *sim;
    undelayed.delay_s = 0;
    sim_zoh = sim->IsDiscrete() ? ToStateSpace(undelayed) : DiscretizeZoh(ToStateSpace(undelayed), record->sample_time);
    sim_zoh.delay_s = sim->delay_s;
  }
  auto g0_at = [&](double f_hz) { return FrequencyResponse(sim_zoh, 2 * M_PI * f_hz)(0, 0); };
  std::vector<double> noise(half + 1, 0.0);
  for (int k = 1; k <= half; ++k) {
    double s = 0;
    for (const auto& yp : y_periods) s += std::norm(yp[k] - y_mean[k]);
    noise[k] = s / (double(m) * (m - 1));
  }
  int odd_in_band = 0;
  for (int k = 1; k <= top; ++k) odd_in_band += (k % 2 == 1 && kind[k] == 0);
  d.odd_out_of_band = odd_in_band == 0;
  const int last = std::min(half, 3 * top);
  double odd_y = 0, odd_n = 0, even_y = 0, even_n = 0, exc_y = 0;
  for (int k = 1; k <= last; ++k) {
    DetectionLine line;
    line.line = k;
    line.f_hz = k * d.f0_hz;
    line.y_power = std::norm(y_mean[k]);
    line.noise_power = noise[k];
    line.significant = noise[k] > 0 && line.y_power / noise[k] > threshold;
    const bool in_band = k <= top;
    if (kind[k] == 1) {
      line.kind = "excited";
      const std::complex<double> g = y_mean[k] / u_mean[k];
      line.bla_magnitude = std::abs(g);
      line.bla_phase = std::arg(g);
      line.bla_noise_std = std::sqrt(noise[k]) / std::abs(u_mean[k]);
      exc_y += line.y_power;
      if (sim) line.sim_magnitude = std::abs(g0_at(line.f_hz));
    } else if (k % 2 == 1) {
      line.kind = "odd";
      if (in_band || d.odd_out_of_band) {
        ++d.odd_lines;
        d.odd_significant += line.significant;
        odd_y += line.y_power;
        odd_n += noise[k];
      }
    } else {
      line.kind = "even";
      if (in_band) {
        ++d.even_lines;
        d.even_significant += line.significant;
        even_y += line.y_power;
        even_n += noise[k];
      }
    }
    d.lines.push_back(line);
  }
  // Nonlinear-distortion 1σ of the BLA at an excited line: the excess power of the nearest odd
  // detection lines (up to two on each side, in band) over their noise, divided by |U|².
  std::vector<double> relative;
  for (auto& line : d.lines) {
    if (line.kind != "excited") continue;
    const int k = line.line;
    double excess = 0;
    int used = 0;
    for (int side : {-1, 1}) {
      int found = 0;
      for (int j = k + side; j >= 1 && j <= top && found < 2; j += side)
        if (kind[j] == 0 && j % 2 == 1) {
          excess += std::norm(y_mean[j]) - noise[j];
          ++found;
          ++used;
        }
    }
    line.bla_distortion_std = used ? std::sqrt(std::max(0.0, excess / used)) / std::abs(u_mean[k]) : kNan;
    if (sim && line.sim_magnitude > 0) {
      const std::complex<double> g0 = g0_at(line.f_hz);
      relative.push_back(std::abs(std::polar(line.bla_magnitude, line.bla_phase) - g0) / std::abs(g0));
    }
  }
  if (!relative.empty()) {
    std::nth_element(relative.begin(), relative.begin() + relative.size() / 2, relative.end());
    d.bla_vs_sim = relative[relative.size() / 2];
  }
  const double exc_mean = exc_y / excited;
  if (d.odd_lines) {
    d.odd_to_noise_db = Db(odd_y / std::max(odd_n, 1e-300));
    d.odd_to_output_db = Db(odd_y / d.odd_lines / std::max(exc_mean, 1e-300));
    d.odd_distortion = MoreThanChance(d.odd_significant, d.odd_lines);
  }
  if (d.even_lines) {
    d.even_to_noise_db = Db(even_y / std::max(even_n, 1e-300));
    d.even_to_output_db = Db(even_y / d.even_lines / std::max(exc_mean, 1e-300));
    d.even_distortion = MoreThanChance(d.even_significant, d.even_lines);
  }
  return d;
}

}  // namespace idrig
