// Starting points of the candidate fits (see gap_internal.h): the effects' scaled starts, the
// grid starts of the piecewise effects, the quantisation step from the samples' lattice, and
// the linear-in-parameters starts (the restoring-force idea: what the refitted G0 leaves,
// regressed on the effect's basis).
#include <algorithm>
#include <cmath>
#include <complex>

#include "core/numeric/gap/gap_internal.h"

namespace idrig::gap_detail {

// Starting points (physical units) for each effect, from the data's scales.
std::vector<std::vector<double>> Starts(EffectKind kind, const Scales& s) {
  const double um = s.u_max, ts = s.ts, slow = s.slow;
  switch (kind) {
    case EffectKind::kTimeDelay:
      return {{1.0 * ts}, {3.0 * ts}, {std::max(ts, 0.1 * slow)}, {std::max(2 * ts, 0.4 * slow)},
              {std::max(ts, s.lag_of_best_match)}};
    case EffectKind::kActuatorLag:
      return {{std::max(ts, 0.05 * slow)}, {std::max(ts, 0.2 * slow)}, {std::max(ts, 0.8 * slow)}};
    case EffectKind::kUnmodelledResonance: {
      std::vector<std::vector<double>> starts;
      const double nyquist = M_PI / ts;
      for (double f : {0.01, 0.02, 0.04, 0.08, 0.15, 0.3, 0.5, 0.75})
        starts.push_back({f * nyquist, 0.1});
      return starts;
    }
    case EffectKind::kInputSaturation:
      // Both limits in the data, or one beyond it (a one-sided limit: from two-sided starts the
      // far limit stays caught inside the data, a worse local minimum).
      return {{s.u_quantile[0], s.u_quantile[4]}, {s.u_quantile[1], s.u_quantile[3]},
              {0.5 * (s.u_quantile[1] + s.u_quantile[2]), 0.5 * (s.u_quantile[2] + s.u_quantile[3])},
              {s.u_quantile[0] - 2 * um, s.u_quantile[3]}, {s.u_quantile[1], s.u_quantile[4] + 2 * um}};
    case EffectKind::kDeadZone:
    case EffectKind::kBacklash:
    case EffectKind::kCoulombFriction:
      return {{0.03 * um}, {0.1 * um}, {0.3 * um}, {0.6 * um}};
    case EffectKind::kCubicStiffness: {
      const double unit = um / std::pow(s.y_max, 3);
      return {{0.05 * unit}, {0.3 * unit}, {1.0 * unit}, {-0.05 * unit}};
    }
    case EffectKind::kOutputSaturation:
      return {{s.y_measured_quantile[0], s.y_measured_quantile[3]}, {s.y_measured_quantile[1], s.y_measured_quantile[2]}};
    case EffectKind::kOutputQuantization:
      return {{0.05}, {0.3}};  // noise before the rounding, as a share of q
    case EffectKind::kSensorNonlinearity:
      return {{1.0, 0.0, 0.0, 0.0}, {1.0, 0.1 / s.y_max, 0.0, 0.0}, {1.0, 0.0, -0.1 / (s.y_max * s.y_max), 0.0}};
    default:
      return {{}};
  }
}

std::vector<std::vector<double>> GridStarts(EffectKind kind, const Scales& s) {
  std::vector<std::vector<double>> grid;
  switch (kind) {
    case EffectKind::kInputSaturation:
    case EffectKind::kOutputSaturation: {
      const bool in = kind == EffectKind::kInputSaturation;
      const double* low = in ? s.u_low : s.y_measured_low;
      const double* high = in ? s.u_high : s.y_measured_high;
      const double span = in ? s.u_max : s.y_max;
      // Each side: one of the tails, or beyond the data (that side does not clip).
      std::vector<double> lo(low, low + 6), hi(high, high + 6);
      lo.push_back(low[0] - 2 * span);
      hi.push_back(high[0] + 2 * span);
      for (double l : lo)
        for (double h : hi)
          if (h > l) grid.push_back({l, h});
      break;
    }
    case EffectKind::kDeadZone:
    case EffectKind::kBacklash:
    case EffectKind::kCoulombFriction:
      for (double f : {0.01, 0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.45, 0.6}) grid.push_back({f * s.u_max});
      break;
    case EffectKind::kTimeDelay:
      // The cost is many-valued in τ (each period of the response a basin): a grid a factor √2
      // apart from one sample to 0.6 slow time constants.
      for (double tau = s.ts; tau <= std::max(4 * s.ts, 0.6 * s.slow); tau *= M_SQRT2) grid.push_back({tau});
      break;
    default:
      break;
  }
  return grid;
}

// Candidate quantisation steps: the mean resultant length R(q) = |mean exp(2πi y/q)| is near 1
// when the samples sit on multiples of q (and on multiples of q/2, q/3, …), near 1/√N when not.
// With noise σ before the rounding R(q) = exp(−2π²σ²/q²) and R(q/k) = R(q)^(k²): the step has the
// largest R, and a submultiple ties with it only when the noise is far below the step. On a
// lattice the step is the best q, or a multiple of it whose R is within 10 % of the best (q, not
// q/2). A q that is no multiple of the best is not taken however high its R: on an output held
// at a few levels a q a fifth off the step lines up half of the samples (R 0.53 against 1.00,
// `--pairs any --integrating --seed 972` case 50, which made the lattice fail its 95 % test).
double QuantisationStep(const std::vector<GapRecord>& records, double* strength, int threads) {
  std::vector<double> y;
  for (const auto& r : records)
    for (long k = r.score_from; k < r.y.size(); ++k) y.push_back(r.y(k));
  double span = *std::max_element(y.begin(), y.end()) - *std::min_element(y.begin(), y.end());
  if (!(span > 0)) span = 1;
  auto resultant = [&y](double q) {
    std::complex<double> sum = 0;
    for (double v : y) sum += std::polar(1.0, 2 * M_PI * v / q);
    return std::abs(sum) / y.size();
  };
  // Coarse logarithmic grid span/3000 … span/3 (0.35 % apart: a lattice of up to ~300 steps
  // stays in phase), then a fine search around the chosen step.
  // (2000 steps × N samples of exp(2πi y/q): on 10^4 samples 0.4 s, ahead of every candidate.)
  const int grid = 2000, chunks = 8;
  std::vector<std::pair<double, double>> table(grid);
  ParallelFor(chunks, threads, [&](size_t c) {
    for (int i = static_cast<int>(c) * grid / chunks; i < (static_cast<int>(c) + 1) * grid / chunks; ++i) {
      const double q = span * std::pow(10.0, -3.5 + 3.0 * i / (grid - 1));
      table[i] = {q, resultant(q)};
    }
  }, [](size_t) { return std::string("scoring quantisation steps"); });
  size_t at = 0;
  for (size_t i = 0; i < table.size(); ++i)
    if (table[i].second > table[at].second) at = i;
  const double best = table[at].second;
  // On a lattice (the best R at least kStrongLattice): the largest-q local maximum within 10 % of
  // the best at a whole multiple of the best's q (2 % apart, the grid's spacing over a multiple
  // of up to 5): q itself, not q/2, q/3, …. Where R is about the noise's 1/√N everywhere (no
  // lattice, or noise far above the step) the largest-q local maximum within half of the best: a
  // coarse staircase that fits nothing, as before.
  constexpr double kStrongLattice = 0.3;
  double step = best >= kStrongLattice ? table[at].first : table.front().first;
  for (size_t i = (best >= kStrongLattice ? at : 0) + 1; i + 1 < table.size(); ++i) {
    const double multiple = table[i].first / table[at].first;
    const bool local_max = table[i].second >= table[i - 1].second && table[i].second >= table[i + 1].second;
    if (best >= kStrongLattice ? local_max && table[i].second >= 0.9 * best &&
                                     std::abs(multiple - std::round(multiple)) < 0.02 * multiple
                               : local_max && table[i].second >= 0.5 * best)
      step = table[i].first;
  }
  double refined = step, refined_r = resultant(step);
  for (int i = -100; i <= 100; ++i) {
    const double q = step * (1 + 0.005 * i / 100);
    const double r = resultant(q);
    if (r > refined_r) refined = q, refined_r = r;
  }
  *strength = refined_r;
  return refined;
}

std::vector<std::vector<double>> LinearStarts(const FitContext& ctx, EffectKind kind,
                                              const Candidate& base, const Eigen::VectorXd& x) {
  if (kind != EffectKind::kCubicStiffness && kind != EffectKind::kCoulombFriction &&
      kind != EffectKind::kSensorNonlinearity)
    return {};
  // The force acts on the mechanics (effects.h), so its regressor goes through that part only.
  const TransferFunction plant = SplitAtForce(base.Plant(x)).mechanics;
  EffectSimulationOptions sim;
  sim.substeps = 1;
  std::vector<Eigen::VectorXd> columns_e, columns_a, columns_b;
  for (const GapRecord& r : *ctx.estimation) {
    Nuisance nu;
    const Eigen::VectorXd y_hat = base.Predict(x, r, &nu);
    const long first = r.score_from, n = r.y.size() - first;
    const Eigen::VectorXd e = (r.y - y_hat).tail(n);
    Eigen::VectorXd a, b;
    if (kind == EffectKind::kCubicStiffness) {
      // force −k3 y³ ⇒ y − G u ≈ −k3·G_mech(y³) (measured y, its offset removed).
      const Eigen::VectorXd yc = r.y - nu.output_level;
      a = SimulateWithEffect(plant, Effect{}, yc.array().cube().matrix(), r.sample_time, sim).tail(n);
      a = -a;
    } else if (kind == EffectKind::kCoulombFriction) {
      // force −F_c sign(ẏ) ⇒ y − G u ≈ −F_c·G_mech(sign(dŷ/dt)) (velocity of the base prediction).
      Eigen::VectorXd s(r.y.size());
      for (long k = 0; k < s.size(); ++k) {
        const double v = y_hat(std::min<long>(k + 1, s.size() - 1)) - y_hat(std::max<long>(k - 1, 0));
        s(k) = v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0);
      }
      a = -SimulateWithEffect(plant, Effect{}, s, r.sample_time, sim).tail(n);
    } else {
      // y_m = y + a2 y² + a3 y³ about the base prediction (its offset removed).
      const Eigen::VectorXd yc = (y_hat - nu.output_level).tail(n);
      a = yc.array().square();
      b = yc.array().cube();
    }
    columns_e.push_back(e);
    columns_a.push_back(a);
    if (b.size()) columns_b.push_back(b);
  }
  long total = 0;
  for (const auto& e : columns_e) total += e.size();
  const int cols = columns_b.empty() ? 1 : 2;
  Eigen::MatrixXd m(total, cols + 1);
  Eigen::VectorXd rhs(total);
  long off = 0;
  for (size_t i = 0; i < columns_e.size(); ++i) {
    const long n = columns_e[i].size();
    rhs.segment(off, n) = columns_e[i];
    m.block(off, 0, n, 1) = columns_a[i];
    if (cols == 2) m.block(off, 1, n, 1) = columns_b[i];
    m.block(off, cols, n, 1).setOnes();
    off += n;
  }
  const Eigen::VectorXd coef = m.colPivHouseholderQr().solve(rhs);
  if (!coef.allFinite()) return {};
  switch (kind) {
    case EffectKind::kCubicStiffness: return {{coef(0)}, {0.5 * coef(0)}};
    case EffectKind::kCoulombFriction:
      if (coef(0) > 0) return {{coef(0)}, {0.5 * coef(0)}};
      return {};
    default: return {{1.0, coef(0), coef(1), 0.0}};
  }
}

}  // namespace idrig::gap_detail
