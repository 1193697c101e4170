// The lattice of a quantised output (gap_noise.h): its offset and how many samples sit on it.
#include <algorithm>
#include <cmath>
#include <complex>
#include <set>
#include <sstream>

#include "core/numeric/gap/gap_internal.h"
#include "core/numeric/gap/gap_noise.h"

namespace idrig {

OutputLattice DetectOutputLattice(const std::vector<GapRecord>& records, double step, double noise_sigma) {
  OutputLattice l;
  l.step = step;
  if (!(step > 0)) {
    l.reason = "no candidate step";
    return l;
  }
  std::complex<double> sum = 0;
  long n = 0;
  for (const auto& r : records)
    for (long k = r.score_from; k < r.y.size(); ++k, ++n) sum += std::polar(1.0, 2 * M_PI * r.y(k) / step);
  if (n == 0) return l;
  l.resultant = std::abs(sum) / n;
  // Offset: the mean phase of the samples on the circle of circumference `step`.
  l.offset = step * std::arg(sum) / (2 * M_PI);
  if (l.offset < 0) l.offset += step;
  if (l.offset > step * (1 - 1e-6)) l.offset = 0;
  long on = 0;
  std::set<long> levels;
  for (const auto& r : records)
    for (long k = r.score_from; k < r.y.size(); ++k) {
      const double level = (r.y(k) - l.offset) / step;
      const double nearest = std::round(level);
      if (std::abs(level - nearest) < 0.05) {
        ++on;
        if (levels.size() < 100000) levels.insert(static_cast<long>(nearest));
      }
    }
  l.on_lattice = double(on) / n;
  l.levels = static_cast<int>(levels.size());
  l.lattice = l.on_lattice >= 0.95 && l.levels >= 4;
  l.noise_share = noise_sigma > 0 ? step * step / 12 / (noise_sigma * noise_sigma) : 0.0;
  std::ostringstream why;
  why.precision(3);
  if (!l.lattice) {
    why << l.on_lattice * 100 << " % of the samples within 5 % of a step of the best lattice (step "
        << step << "): not a lattice";
  } else if (l.noise_share < 0.05) {
    why << "the samples sit on a lattice of step " << step << " (" << l.levels
        << " levels), but its rounding noise q²/12 is only " << l.noise_share * 100
        << " % of the noise floor's variance: the resolution of the numbers, not a quantiser "
           "that matters";
  } else {
    l.detected = true;
    why << "the samples sit on a lattice of step " << step << " and offset " << l.offset << " ("
        << l.on_lattice * 100 << " % of them, " << l.levels << " levels); its rounding noise q²/12 is "
        << l.noise_share * 100 << " % of the noise floor's variance";
  }
  l.reason = why.str();
  return l;
}

void NameLatticeQuantisation(const OutputLattice& l, double noise_nrmse, GapReport& report) {
  if (!l.detected) return;
  GapVerdict& v = report.verdict;
  if (v.effect == "output_quantization" || v.effect == "ambiguous") return;
  for (const Effect& e : v.effects)
    if (e.kind == EffectKind::kOutputQuantization) return;
  const Effect quantiser{EffectKind::kOutputQuantization, {l.step}};
  if (v.effect == "none") {
    const CandidateFit* q = nullptr;
    for (const auto& c : report.ranking)
      if (c.effect.kind == EffectKind::kOutputQuantization && c.effects.size() <= 1) q = &c;
    v.effect = "output_quantization";
    if (q) {
      gap_detail::AdoptCandidate(*q, v);
      if (v.effects.empty()) v.effects = {q->effect};
    } else {
      v.params = quantiser;
      v.param_std = {std::nan("")};
      v.effects = {quantiser};
      v.effects_std = {{std::nan("")}};
    }
    v.confidence = l.on_lattice;
    report.notes.push_back("output_quantization named from the lattice (no candidate beat G0 "
                           "beyond the noise, which the rounding is part of): " + l.reason);
    return;
  }
  if (v.effects.size() != 1) return;
  const double left = v.nrmse_after > 0 ? noise_nrmse / v.nrmse_after : 0.0;
  if (l.noise_share * left * left < 0.05) return;
  v.effects.push_back(quantiser);
  v.effects_std.push_back({std::nan("")});
  report.notes.push_back("output_quantization added as a second effect from the lattice (not "
                         "refitted; nrmse_after is the first effect's): " + l.reason);
}

}  // namespace idrig
