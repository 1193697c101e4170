// Candidate fitting of the gap diagnosis (see gap_diagnosis.h, gap_internal.h): one candidate's
// model (G0's coefficients as log multipliers, the effect's parameters φ), its output-error
// residuals, the Levenberg–Marquardt fit from the effect's starts, and the parameters' 1σ.
#include <unsupported/Eigen/NonLinearOptimization>
#include <unsupported/Eigen/NumericalDiff>

#include <algorithm>
#include <numeric>
#include <cmath>
#include <complex>
#include <stdexcept>

#include "core/numeric/gap/gap_internal.h"

namespace idrig::gap_detail {

// One discretisation per prediction, shared by the free response, the settled direction and the
// delay line's level before the record (gap_internal.h).
StateSpace SampledUndelayed(const TransferFunction& plant, double ts) {
  TransferFunction g = plant;
  g.delay_s = 0;
  if (g.Order() == 0) return StateSpace{};
  return DiscretizeZoh(ToStateSpace(g), ts);
}

Eigen::MatrixXd FreeResponse(const StateSpace& d, long n) {
  const long order = d.A.rows();
  if (order == 0 || n <= 0) return Eigen::MatrixXd(std::max<long>(n, 0), order);
  // Row k is C A^k, built as the columns of its transpose (A^T)^k C^T: one contiguous
  // matrix-vector product per row, without a temporary per row.
  Eigen::MatrixXd ft(order, n);
  ft.col(0) = d.C.row(0).transpose();
  double largest = 0;
  for (long k = 0; k < n; ++k) {
    const double norm = ft.col(k).norm();
    largest = std::max(largest, norm);
    // A stable plant's free response decays: below 1e-15 of its largest row it is zero for the
    // projection, so the rows end here (the caller treats the missing rows as zeros).
    if (!(norm > 1e-15 * largest) || k + 1 == n) return ft.leftCols(k + 1).transpose();
    ft.col(k + 1).noalias() = d.A.transpose() * ft.col(k);
    if (!ft.col(k + 1).allFinite()) return ft.leftCols(k + 1).transpose();
  }
  return ft.transpose();
}

std::vector<std::pair<long, long>> Segments(const GapRecord& record, long segment) {
  const long first = record.score_from, total = record.y.size() - first;
  const long count = segment > 0 ? std::max<long>(1, total / segment) : 1;
  std::vector<std::pair<long, long>> out;
  for (long j = 0; j < count; ++j) {
    const long start = first + j * total / count;
    out.emplace_back(start, first + (j + 1) * total / count - start);
  }
  return out;
}

namespace {

// Least squares through small normal equations, equilibrated (unit diagonal) and solved by a
// symmetric eigen-decomposition with a relative cut-off (a minimum-norm solution where the
// columns are nearly dependent: the fitted values, all that matters here, are then still the
// projection).
Eigen::VectorXd EquilibratedSolve(const Eigen::MatrixXd& gram, const Eigen::VectorXd& rhs, long* rank = nullptr) {
  const long k = gram.rows();
  Eigen::VectorXd scale = gram.diagonal().cwiseSqrt();
  for (long i = 0; i < k; ++i) scale(i) = scale(i) > 0 ? 1.0 / scale(i) : 0.0;
  const Eigen::MatrixXd g = scale.asDiagonal() * gram * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(g);
  const Eigen::VectorXd lambda = eig.eigenvalues();
  const double cut = 1e-13 * lambda.cwiseAbs().maxCoeff();
  const Eigen::VectorXd proj = eig.eigenvectors().transpose() * (scale.asDiagonal() * rhs);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(k);
  if (rank) *rank = 0;
  for (long i = 0; i < k; ++i)
    if (lambda(i) > cut) {
      z += eig.eigenvectors().col(i) * (proj(i) / lambda(i));
      if (rank) ++*rank;
    }
  return scale.asDiagonal() * z;
}

}  // namespace

Eigen::VectorXd OffsetAndStateFit(const Eigen::VectorXd& r, const Eigen::MatrixXd& free_rows, long* rank,
                                  const Eigen::MatrixXd* extra) {
  const long len = r.size(), rows = std::min<long>(len, free_rows.rows()), n = free_rows.cols();
  const long m = extra ? extra->cols() : 0, k = 1 + n + m;
  Eigen::MatrixXd gram(k, k);
  Eigen::VectorXd rhs(k);
  gram(0, 0) = double(len);
  rhs(0) = r.sum();
  if (n > 0) {
    const auto f = free_rows.topRows(rows);
    gram.block(1, 1, n, n) = f.transpose() * f;
    gram.block(0, 1, 1, n) = f.colwise().sum();
    gram.block(1, 0, n, 1) = gram.block(0, 1, 1, n).transpose();
    rhs.segment(1, n) = f.transpose() * r.head(rows);
  }
  if (m > 0) {
    const Eigen::MatrixXd& x = *extra;
    gram.block(1 + n, 1 + n, m, m) = x.transpose() * x;
    gram.block(0, 1 + n, 1, m) = x.colwise().sum();
    gram.block(1 + n, 0, m, 1) = gram.block(0, 1 + n, 1, m).transpose();
    if (n > 0) {
      gram.block(1, 1 + n, n, m) = free_rows.topRows(rows).transpose() * x.topRows(rows);
      gram.block(1 + n, 1, m, n) = gram.block(1, 1 + n, n, m).transpose();
    }
    rhs.tail(m) = x.transpose() * r;
  }
  return EquilibratedSolve(gram, rhs, rank);
}

namespace {

double Pos(double v) { return std::exp(std::clamp(v, -30.0, 30.0)); }

// The input a delayed plant's line holds at the start of a record. The rig ran before the
// record began, so over the first d samples (d = the whole-sample delay) the plant is driven by
// what it was given then, not by zero: an unknown level c per record (the rig settled at an
// operating point), entering the prediction linearly beside the initial state. Its column is
// the plant's zero-state response to an input of 1 over the first d samples and 0 after (the
// fractional part of the delay in the sampled plant, as in simulation); n rows at most, fewer
// where it has decayed (the caller treats missing rows as zeros). Empty without a whole-sample
// delay: the line is then empty and x0 alone is the state. `undelayed`: the plant's delay-free
// realisation (SampledUndelayed), for the size of its state.
Eigen::VectorXd PreRecordResponse(const TransferFunction& plant, const StateSpace& undelayed, double ts, long n) {
  if (n <= 0 || !HasDelayLine(plant.delay_s, ts)) return Eigen::VectorXd();
  const StateSpace d = DiscretizeZoh(ToStateSpace(plant), ts);
  const long whole = std::lround(d.delay_s / ts);
  if (whole <= 0) return Eigen::VectorXd();
  Eigen::VectorXd out(n), x = Eigen::VectorXd::Zero(d.A.rows());
  x.tail(d.A.rows() - undelayed.A.rows()).setOnes();  // a fractional delay's state: the previous input, c too
  double largest = 0;
  for (long k = 0; k < n; ++k) {
    const double u = k < whole ? 1.0 : 0.0;
    out(k) = (d.C.row(0) * x)(0, 0) + d.D(0, 0) * u;
    largest = std::max(largest, std::abs(out(k)));
    if (k >= whole && !(x.norm() > 1e-15 * std::max(largest, 1e-300))) return out.head(k + 1);
    x = d.A * x + d.B.col(0) * u;
    if (!x.allFinite()) return out.head(k + 1);
  }
  return out;
}

// The state columns of a record's first segment: the free response F, and beside it the input
// held in the delay line before the record (PreRecordResponse) where there is one.
Eigen::MatrixXd WithPreRecord(const Eigen::MatrixXd& free, const Eigen::VectorXd& pre) {
  if (pre.size() == 0 || free.cols() == 0) return free;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(std::max<long>(free.rows(), pre.size()), free.cols() + 1);
  out.topLeftCorner(free.rows(), free.cols()) = free;
  out.col(free.cols()).head(pre.size()) = pre;
  return out;
}

// The state columns of a record's first segment for a candidate of `spec` whose linear part is
// `linear`: F and the delay line's level.
Eigen::MatrixXd FirstSegmentState(const CandidateSpec& spec, const TransferFunction& linear,
                                  const StateSpace& undelayed, double ts, long n, const Eigen::MatrixXd& free) {
  if (!spec.free_state || free.cols() == 0) return free;
  return WithPreRecord(free, PreRecordResponse(linear, undelayed, ts, n));
}

// The nuisance coefficients of a rig settled at a constant input before the record, per unit of
// the level it then reads: x0 = (I − A)⁻¹B (the sampled plant's equilibrium, in FreeResponse's
// coordinates) and, with a delay line (PreRecordResponse), its level 1; divided by the output
// C x0 + D. Empty where the plant has no equilibrium (an integrator: I − A singular) or no
// static gain. `d`: the plant's delay-free sampled realisation (SampledUndelayed).
Eigen::VectorXd SettledDirection(const StateSpace& d, bool with_line) {
  const long n = d.A.rows();
  if (n == 0) return Eigen::VectorXd();
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(Eigen::MatrixXd::Identity(n, n) - d.A);
  if (!lu.isInvertible()) return Eigen::VectorXd();
  const Eigen::VectorXd x = lu.solve(d.B.col(0));
  const double level = (d.C.row(0) * x)(0, 0) + d.D(0, 0);
  if (!std::isfinite(level) || !(std::abs(level) > 1e-12 * (d.B.norm() + std::abs(d.D(0, 0)))) || !x.allFinite())
    return Eigen::VectorXd();
  Eigen::VectorXd out(n + (with_line ? 1 : 0));
  out.head(n) = x / level;
  if (with_line) out(n) = 1.0 / level;
  return out;
}

// The sensor's own columns on a segment [start, start + len) of a record: a drift's ramp
// (k − (len − 1)/2)·Ts, centred so that the offset b stays the segment's mean level (with
// `drift`), then for every sensor step inside the segment the level it adds (0 before, 1 from it).
// `from_record_start`: the ramp (start + k)·Ts, zero where the record starts — for clips, whose
// limits are in the measured output's coordinates (OffsetAndStateThroughMaps, `offset_inside`).
Eigen::MatrixXd SensorColumns(const GapRecord& record, long start, long len, bool drift,
                              bool from_record_start = false) {
  std::vector<long> steps;
  for (long s : record.sensor_steps)
    if (s > start && s < start + len) steps.push_back(s - start);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(len, (drift ? 1 : 0) + static_cast<long>(steps.size()));
  const double anchor = from_record_start ? -static_cast<double>(start) : 0.5 * (len - 1);
  if (drift)
    for (long k = 0; k < len; ++k) x(k, 0) = (k - anchor) * record.sample_time;
  for (size_t i = 0; i < steps.size(); ++i) x.col((drift ? 1 : 0) + static_cast<long>(i)).tail(len - steps[i]).setOnes();
  return x;
}

long Longest(const std::vector<std::pair<long, long>>& segments) {
  long longest = 0;
  for (const auto& s : segments) longest = std::max(longest, s.second);
  return longest;
}

}  // namespace

Candidate::Candidate(const TransferFunction& base, const CandidateSpec& spec, const Scales& scales,
                     int substeps)
    : base_(base), spec_(spec), scales_(scales), substeps_(substeps) {
  if (spec_.fixed.size() < spec_.kinds.size()) spec_.fixed.resize(spec_.kinds.size());
  if (spec_.fit_plant) {
    for (int i = 1; i < base.den.size(); ++i)
      if (base.den(i) != 0) free_den_.push_back(i);
    for (int i = 0; i < base.num.size(); ++i)
      if (base.num(i) != 0) free_num_.push_back(i);
  }
  int offset = PlantParams() + NuisanceParams();
  for (size_t i = 0; i < spec_.kinds.size(); ++i) {
    const int n = NumEffectParams(spec_.kinds[i], spec_.fixed[i]);
    block_start_.push_back(offset);
    block_size_.push_back(n);
    offset += n;
    effect_params_ += n;
  }
}

int Candidate::NumEffectParams(EffectKind kind, const std::vector<double>& fixed) {
  switch (kind) {
    case EffectKind::kTimeDelay:
    case EffectKind::kActuatorLag:
    case EffectKind::kDeadZone:
    case EffectKind::kBacklash:
    case EffectKind::kCoulombFriction:
    case EffectKind::kCubicStiffness:
      return 1;
    case EffectKind::kUnmodelledResonance:
    case EffectKind::kInputSaturation:
    case EffectKind::kOutputSaturation:
      return 2;
    case EffectKind::kSensorNonlinearity:
      return fixed.empty() ? 2 : 0;  // polynomial a2, a3; or |y| (fixed = {1})
    case EffectKind::kOutputQuantization:
      return 1;  // q fixed by the samples' lattice; fitted: the noise before the rounding
    default:
      return 0;  // none, parameter_mismatch
  }
}

TransferFunction Candidate::Plant(const Eigen::VectorXd& x) const {
  TransferFunction g = base_;
  int j = 0;
  for (int i : free_den_) g.den(i) *= std::exp(std::clamp(x(j++), -20.0, 20.0));
  for (int i : free_num_) g.num(i) *= std::exp(std::clamp(x(j++), -20.0, 20.0));
  if (gain_only_) g.num *= std::exp(std::clamp(x(j++), -20.0, 20.0));
  return g;
}

double Candidate::InputOffset(const Eigen::VectorXd& x) const {
  // Bounded to ±max|u| (an offset larger than the input's range is not an offset).
  return spec_.input_offset ? std::tanh(x(PlantParams())) * scales_.u_max : 0.0;
}

Effect Candidate::EffectAt(const Eigen::VectorXd& x, size_t i) const {
  const EffectKind kind = spec_.kinds[i];
  const std::vector<double>& fixed = spec_.fixed[i];
  const Eigen::VectorXd phi = x.segment(block_start_[i], block_size_[i]);
  const Scales& s = scales_;
  Effect e;
  e.kind = kind;
  switch (kind) {
    case EffectKind::kTimeDelay:
      // No longer than the longest record: a longer delay only delays the whole response out of
      // it, and its delay line (one slot a sample) would not fit in memory near Pos's bound.
      e.params = {std::min(Pos(phi(0)) * s.ts, s.duration)};
      break;
    case EffectKind::kActuatorLag: e.params = {Pos(phi(0)) * s.ts}; break;
    case EffectKind::kUnmodelledResonance:
      // ζ ≤ 1/√2: a resonance has a peak. Above it the "resonance" is a smooth low-pass; above
      // 1 two real poles, and where the faster is beyond the band a first-order lag with a spare
      // parameter (a fourth-order two-mass plant's actuator lag fitted ζ = 9.3 and won by 0.3 %
      // NRMSE; bounded at 1, an integrating plant's lag under coloured noise fitted ζ = 1.0 and
      // won by 0.3 % again).
      e.params = {Pos(phi(0)) / s.ts, std::clamp(Pos(phi(1)), 1e-4, M_SQRT1_2)};
      break;
    case EffectKind::kInputSaturation:
    case EffectKind::kOutputSaturation: {
      const double scale = kind == EffectKind::kInputSaturation ? s.u_max : s.y_max;
      double lo = phi(0) * scale, hi = phi(1) * scale;
      if (hi - lo < 1e-9 * scale) hi = lo + 1e-9 * scale;
      e.params = {lo, hi};
      break;
    }
    case EffectKind::kDeadZone:
    case EffectKind::kBacklash:
    case EffectKind::kCoulombFriction:
      e.params = {Pos(phi(0)) * s.u_max};
      break;
    case EffectKind::kCubicStiffness:
      e.params = {phi(0) * s.u_max / std::pow(s.y_max, 3)};
      break;
    case EffectKind::kSensorNonlinearity:
      if (fixed.empty()) e.params = {1.0, phi(0) / s.y_max, phi(1) / (s.y_max * s.y_max), 0.0};
      else e.params = {1.0, 0.0, 0.0, 1.0};
      break;
    case EffectKind::kOutputQuantization: e.params = {fixed.at(0)}; break;
    default: break;
  }
  return e;
}

Effect Candidate::EffectOf(const Eigen::VectorXd& x) const {
  if (spec_.kinds.empty()) return Effect{};
  return EffectAt(x, 0);
}

std::vector<Effect> Candidate::Effects(const Eigen::VectorXd& x) const {
  std::vector<Effect> out;
  for (size_t i = 0; i < spec_.kinds.size(); ++i)
    if (spec_.kinds[i] != EffectKind::kNone && spec_.kinds[i] != EffectKind::kParameterMismatch)
      out.push_back(EffectAt(x, i));
  return out;
}

Eigen::VectorXd Candidate::Phi(size_t i, const std::vector<double>& p) const {
  const Scales& s = scales_;
  Eigen::VectorXd phi(block_size_[i]);
  switch (spec_.kinds[i]) {
    case EffectKind::kTimeDelay:
    case EffectKind::kActuatorLag: phi(0) = std::log(p[0] / s.ts); break;
    case EffectKind::kUnmodelledResonance:
      phi(0) = std::log(p[0] * s.ts);
      phi(1) = std::log(p[1]);
      break;
    case EffectKind::kInputSaturation: phi << p[0] / s.u_max, p[1] / s.u_max; break;
    case EffectKind::kOutputSaturation: phi << p[0] / s.y_max, p[1] / s.y_max; break;
    case EffectKind::kDeadZone:
    case EffectKind::kBacklash:
    case EffectKind::kCoulombFriction: phi(0) = std::log(std::max(p[0], 1e-9 * s.u_max) / s.u_max); break;
    case EffectKind::kCubicStiffness: phi(0) = p[0] * std::pow(s.y_max, 3) / s.u_max; break;
    case EffectKind::kSensorNonlinearity:
      if (block_size_[i] == 2) phi << p[1] * s.y_max, p[2] * s.y_max * s.y_max;
      break;
    case EffectKind::kOutputQuantization: phi(0) = std::log(p[0]); break;  // s/q
    default: break;
  }
  return phi;
}

// The best predictor of q·round((y + n)/q) when noise n ~ N(0, s²) enters before the rounding is
// its conditional mean, a staircase smoothed by s (s → 0: the staircase). With r = y/q, σ = s/q:
//  - σ ≥ 0.1: the Fourier series of the sawtooth r − round(r) = Σ_m (−1)^(m+1) sin(2πmr)/(πm),
//    each harmonic damped by the Gaussian's characteristic function exp(−2π²m²σ²), so
//    E[round(r + ν)] = r − Σ_m (−1)^(m+1) e^(−2π²m²σ²) sin(2πmr)/(πm), truncated where the
//    factor is < 1e-13 (m ≤ 1.25/σ + 1): one sin/cos per sample, harmonics by recurrence;
//  - σ < 0.1: only the two boundaries next to r matter (a jump of two levels needs |ν| ≥ 0.5 =
//    5σ): E = m + P(r + ν ≥ m + ½) − P(r + ν < m − ½), m = round(r), and exactly m when r is
//    more than 8.5σ from both (tails < 1e-17).
void SmoothedStaircase(Eigen::VectorXd& y, double q, double s) {
  const double sigma = s / q;
  if (sigma >= 0.1) {
    const int harmonics = static_cast<int>(std::ceil(1.25 / sigma)) + 1;
    std::vector<double> weight(harmonics + 1);
    for (int m = 1; m <= harmonics; ++m)
      weight[m] = (m % 2 ? 1.0 : -1.0) * std::exp(-2 * M_PI * M_PI * m * m * sigma * sigma) / (M_PI * m);
    for (long k = 0; k < y.size(); ++k) {
      const double r = y(k) / q;
      const double c1 = std::cos(2 * M_PI * (r - std::round(r))), s1 = std::sin(2 * M_PI * (r - std::round(r)));
      double sm = s1, cm = c1, saw = weight[1] * s1;
      for (int m = 2; m <= harmonics; ++m) {
        const double sn = sm * c1 + cm * s1, cn = cm * c1 - sm * s1;
        sm = sn, cm = cn;
        saw += weight[m] * sm;
      }
      y(k) = q * (r - saw);
    }
    return;
  }
  const double scale = 1.0 / (sigma * M_SQRT2);
  for (long k = 0; k < y.size(); ++k) {
    const double r = y(k) / q, m = std::round(r), f = r - m;  // f in [−½, ½]
    double mean = m;
    if (0.5 - f < 8.5 * sigma) mean += 0.5 * std::erfc((m + 0.5 - r) * scale);  // up one level
    if (0.5 + f < 8.5 * sigma) mean -= 0.5 * std::erfc((r - m + 0.5) * scale);  // down one
    y(k) = q * mean;
  }
}

namespace {

bool IsOutputMap(EffectKind kind) {
  return kind == EffectKind::kOutputSaturation || kind == EffectKind::kSensorNonlinearity;
}

// The output maps (OutputMap: saturation, sensor map) in the order given, on z, and their
// derivative d map/dz (chain rule through several maps).
void ApplyOutputMaps(const std::vector<Effect>& maps, Eigen::VectorXd& z, Eigen::VectorXd* slope) {
  if (slope) slope->setOnes(z.size());
  for (const Effect& e : maps)
    for (long k = 0; k < z.size(); ++k) {
      double d = 1.0;
      z(k) = OutputMap(e, z(k), slope ? &d : nullptr);
      if (slope) (*slope)(k) *= d;
    }
}

}  // namespace

Eigen::VectorXd Candidate::Simulate(const Eigen::VectorXd& x, const GapRecord& record,
                                    std::vector<Effect>* output_maps, double play_state) const {
  EffectSimulationOptions options;
  options.substeps = substeps_;
  options.play_state = play_state;
  std::vector<Effect> effects = InRigOrder(Effects(x));
  // Quantisation is applied in Predict, after the nuisance (see there); so are the output maps
  // when the caller takes them (they then act on the free response as well).
  effects.erase(std::remove_if(effects.begin(), effects.end(),
                               [&](const Effect& e) {
                                 if (output_maps && IsOutputMap(e.kind)) output_maps->push_back(e);
                                 return e.kind == EffectKind::kOutputQuantization ||
                                        (output_maps && IsOutputMap(e.kind));
                               }),
                effects.end());
  const double du = InputOffset(x);
  const Eigen::VectorXd u = du != 0 ? Eigen::VectorXd(record.u.array() + du) : record.u;
  return SimulateWithEffects(Plant(x), effects, u, record.sample_time, options);
}

namespace {

// One segment's prediction through the output maps from its coefficients coef = [b, x0, c]:
// map(z + F·x0) + b + E·c, or with `offset_inside` map(z + F·x0 + b) + E·c (F = `free`, whose
// missing rows are zeros; E = `extra`, the sensor's columns, used where it has the segment's
// rows). The maps' slope into `slope` when given.
void ThroughMaps(const Eigen::VectorXd& z, const Eigen::MatrixXd& free, const std::vector<Effect>& maps,
                 const Eigen::VectorXd& coef, const Eigen::MatrixXd& extra, bool offset_inside, Eigen::VectorXd& m,
                 Eigen::VectorXd* slope) {
  const long len = z.size(), rows = std::min<long>(len, free.rows()), n = free.cols();
  const long m_extra = extra.rows() == len ? extra.cols() : 0;
  m = z;
  if (n > 0) m.head(rows) += free.topRows(rows) * coef.segment(1, n);
  if (offset_inside) m.array() += coef(0);
  ApplyOutputMaps(maps, m, slope);
  if (!offset_inside) m.array() += coef(0);
  if (m_extra > 0) m += extra * coef.tail(m_extra);
}

// The nuisance of one segment through the output maps, ŷ = map(z + F·x0) + b (a sensor offset
// after the map; the segment's state before it, where the plant's state is): Gauss–Newton on
// (b, x0) with the map linearised, J = [1, diag(map'(z + F·x0))·F], each step the same
// equilibrated least squares as without maps. Two starts, the better kept: x0 = 0 (the
// simulation from rest is right: a |y| sensor folds, and a start on the wrong side of the fold
// is the mirror basin), and the state the segment would need were the maps the identity (the
// right basin when the simulation from rest has drifted into a clip that the rig's own state
// never reaches: at x0 = 0 the clipped samples have no slope, and Gauss–Newton could not leave
// them). Exact for the maps' pieces the samples sit on. Behind a |y| sensor a third start from
// a grid over the level where the segment began (below: `settled`).
//
// `offset_inside` (the maps are clips only): ŷ = clip(z + F·x0 + b), J = diag(clip')·[1, F].
// The same model — clip(s, lo, hi) + b = clip(s + b, lo + b, hi + b) — with the limits where
// the samples are, in the measured output's coordinates. With b after the clip, the limits sit
// in coordinates that the segment's own offset sets, and on an integrating plant that offset and
// the integrator's level are one direction: a segment's fit could place the clip anywhere, the
// limits' start (the measured quantiles less one global offset) clipped nothing, and the fit of
// the limits had no slope to follow.
//
// `extra` (the sensor's own columns, SensorColumns; or none): added after the maps, where the
// sensor is (coef = [b, x0, c]); in the clip's coordinates a drifting reading would move the limits.
//
// `fixed_offset` (b after the maps only): b is given, not fitted — the record's one sensor
// offset, shared by its shooting segments (PredictFrom).
Eigen::VectorXd OffsetAndStateThroughMaps(const Eigen::VectorXd& y, const Eigen::VectorXd& z,
                                          const Eigen::MatrixXd& free, const std::vector<Effect>& maps,
                                          Eigen::VectorXd* fitted, bool offset_inside,
                                          const Eigen::MatrixXd& extra, const Eigen::VectorXd& settled,
                                          const double* fixed_offset = nullptr,
                                          const Eigen::VectorXd* from = nullptr) {
  const long len = y.size(), rows = std::min<long>(len, free.rows()), n = free.cols();
  const long m_extra = extra.rows() == len ? extra.cols() : 0;  // the sensor's columns after the maps
  const Eigen::MatrixXd* sensor = m_extra > 0 ? &extra : nullptr;
  auto evaluate = [&](const Eigen::VectorXd& coef, Eigen::VectorXd& m, Eigen::VectorXd* slope) {
    ThroughMaps(z, free, maps, coef, extra, offset_inside, m, slope);
    return (y - m).squaredNorm();
  };
  // One Gauss–Newton step: b after the maps has slope 1; inside them, the maps' slope; the
  // sensor's columns (after the maps) slope 1.
  const bool offset_given = fixed_offset && !offset_inside;
  auto step = [&](const Eigen::VectorXd& r, const Eigen::VectorXd& slope) {
    if (offset_given) {  // the state (and the sensor's columns) only: b stays where it was given
      Eigen::MatrixXd design = Eigen::MatrixXd::Zero(len, n + m_extra);
      design.topLeftCorner(rows, n) = slope.head(rows).asDiagonal() * free.topRows(rows);
      if (m_extra > 0) design.rightCols(m_extra) = extra;
      Eigen::VectorXd d = Eigen::VectorXd::Zero(1 + n + m_extra);
      if (n + m_extra > 0) d.tail(n + m_extra) = EquilibratedSolve(design.transpose() * design, design.transpose() * r);
      return d;
    }
    if (!offset_inside)
      return OffsetAndStateFit(r, slope.head(rows).asDiagonal() * free.topRows(rows), nullptr, sensor);
    Eigen::MatrixXd design = Eigen::MatrixXd::Zero(len, 1 + n + m_extra);
    design.col(0) = slope;
    design.block(0, 1, rows, n) = slope.head(rows).asDiagonal() * free.topRows(rows);
    if (m_extra > 0) design.rightCols(m_extra) = extra;
    return EquilibratedSolve(design.transpose() * design, design.transpose() * r);
  };
  // A fixed number of full steps, each kept only when it lowers the sum of squares: the result
  // is then a smooth function of the candidate's parameters wherever the clipped samples do
  // not change (an inexact inner solve with a tolerance would put noise into the outer fit's
  // finite-difference Jacobian).
  auto refine = [&](Eigen::VectorXd coef, double& best) {
    Eigen::VectorXd m, slope;
    best = evaluate(coef, m, &slope);
    for (int it = 0; it < 4 && std::isfinite(best); ++it) {
      const Eigen::VectorXd trial = coef + step(y - m, slope);
      Eigen::VectorXd m_trial, slope_trial;
      const double next = evaluate(trial, m_trial, &slope_trial);
      if (!(next < best)) break;
      coef = trial, m.swap(m_trial), slope.swap(slope_trial), best = next;
    }
    return coef;
  };
  const long k = 1 + n + m_extra;
  if (from && from->size() == k) {  // one start given: refined from there only
    double sse = INFINITY;
    const Eigen::VectorXd coef = refine(*from, sse);
    if (fitted) evaluate(coef, *fitted, nullptr);
    return coef;
  }
  Eigen::VectorXd mapped = z;
  if (!offset_inside) ApplyOutputMaps(maps, mapped, nullptr);
  Eigen::VectorXd at_rest = Eigen::VectorXd::Zero(k);
  at_rest(0) = offset_given ? *fixed_offset : (y - mapped).mean();
  double sse_rest = INFINITY, sse_identity = INFINITY;
  Eigen::VectorXd coef = refine(at_rest, sse_rest);
  if (n > 0 || m_extra > 0) {
    Eigen::VectorXd identity = OffsetAndStateFit(y - z, free, nullptr, sensor);
    if (offset_given) identity(0) = *fixed_offset;
    const Eigen::VectorXd other = refine(identity, sse_identity);
    if (sse_identity < sse_rest) coef = other;
  }
  // A |y| sensor: the level c the segment starts at decides where the pre-map signal folds,
  // and both starts above can leave it on the wrong side of zero (the mirror basin: a plant that
  // starts at −0.05 and rises through the fold, read as one that starts at +0.05 and never
  // folds), or on one side for the whole segment (the fold unused). A third start from the best
  // c of a grid over the levels that put the fold inside the segment, b by least squares for
  // each, along the direction that holds a level: on an integrator the free response's own
  // (F v ≈ 1, the level held for the whole segment); on a plant with an equilibrium, `settled`
  // (SettledDirection: the rig at rest at a constant input before the record, its delay line
  // included, whose level then decays as the record's input takes over; `--pairs any --seed 974
  // --excitation steps` case 8, a delay behind |y| that starts just below the fold).
  const bool fold = std::any_of(maps.begin(), maps.end(), IsAbsoluteSensor);
  if (fold && n > 0 && !offset_inside) {
    const Eigen::VectorXd ones = Eigen::VectorXd::Ones(len);
    Eigen::VectorXd v, shift;  // the coefficients per unit level, and the level they add over the segment
    if (rows == len) {
      v = free.topRows(rows).completeOrthogonalDecomposition().solve(ones);
      if ((free.topRows(rows) * v - ones).norm() < 1e-3 * std::sqrt(double(len))) shift = ones;
    }
    if (shift.size() == 0 && settled.size() == n) {
      v = settled;
      shift = Eigen::VectorXd::Zero(len);
      shift.head(rows) = free.topRows(rows) * v;
    }
    if (shift.size() == len) {
      const double lo = -z.maxCoeff(), hi = -z.minCoeff();
      double best_grid = INFINITY;
      Eigen::VectorXd grid_coef;
      for (int i = 0; i <= 40; ++i) {
        const double c = lo + (hi - lo) * i / 40.0;
        Eigen::VectorXd trial = Eigen::VectorXd::Zero(k);
        trial.segment(1, n) = c * v;
        Eigen::VectorXd m = z + c * shift;
        ApplyOutputMaps(maps, m, nullptr);
        trial(0) = offset_given ? *fixed_offset : (y - m).mean();
        const double sse = (y.array() - m.array() - trial(0)).square().sum();
        if (sse < best_grid) best_grid = sse, grid_coef = trial;
      }
      // No finite point on the grid (a simulation that has left the reals, a direction that
      // overflows): no third start.
      if (grid_coef.size() == k) {
        double sse_fold = INFINITY;
        const Eigen::VectorXd folded = refine(grid_coef, sse_fold);
        if (sse_fold < std::min(sse_rest, sse_identity)) coef = folded;
      }
    }
  }
  if (fitted) evaluate(coef, *fitted, nullptr);
  return coef;
}

}  // namespace

// A rig's backlash keeps its play where the last motion before the record left it: anywhere in
// the band around the command it then held, and after the first sample in the band
// [v0 − r, v0 + r] around the play's first input v0 (the command with its offset, through the
// input maps before the backlash). From rest at the origin (play_state 0) is right only for a rig
// started for the record; one held at its operating point has taken up the play on one side
// (`--pairs any --integrating --seed 980` case 4: the bench's rig warmed up at zero command, its
// play at du + r; from 0 the first level drove the integrator by 0.2 too little until the first
// reversal, and r fitted 0.04 for 0.16 with the record's start left above the floor). Five
// points across the band, a parabola's vertex about the best, and the origin's own play (clamped
// into the band); the best on the record's samples is kept, like the free initial state — a
// nuisance per record, counted in NuisanceColumns.
std::vector<double> Candidate::PlayStates(const Eigen::VectorXd& x, const GapRecord& record,
                                          long* taken_up) const {
  const std::vector<Effect> effects = InRigOrder(Effects(x));  // as Simulate takes them
  const auto it = std::find_if(effects.begin(), effects.end(), [](const Effect& e) { return e.kind == EffectKind::kBacklash; });
  if (it == effects.end() || record.u.size() == 0) return {};
  const double du = InputOffset(x), r = it->params[0];
  const auto play_input = [&](long k) {  // what the play sees at sample k
    double v = record.u(k) + du;
    for (auto e = effects.begin(); e != it; ++e) {
      if (e->kind == EffectKind::kInputSaturation) v = std::clamp(v, e->params[0], e->params[1]);
      if (e->kind == EffectKind::kDeadZone) v = DeadZone(v, e->params[0]);
    }
    return v;
  };
  // Once the input has spanned more than the play (2r) every start has been taken up the same
  // way: where it began matters before that sample only. By the second sample: not at all.
  // (Every start lies in [v0 − r, v0 + r], and the play moves up only to follow v − r, down only
  // to follow v + r: at the first v ≥ v0 + 2r, or ≤ v0 − 2r, all are at v ∓ r.)
  const double v0 = play_input(0);
  if (record.u.size() > 1 && std::abs(play_input(1) - v0) > 2 * r) return {};
  if (taken_up) {
    *taken_up = record.u.size();
    for (long k = 1; k < record.u.size(); ++k)
      if (std::abs(play_input(k) - v0) >= 2 * r) {
        *taken_up = k;
        break;
      }
  }
  return {std::clamp(0.0, v0 - r, v0 + r), v0 - r, v0 - 0.5 * r, v0, v0 + 0.5 * r, v0 + r};
}

GapRecord RecordHead(const GapRecord& record, long length) {
  GapRecord head;
  head.u = record.u.head(length);
  head.y = record.y.head(length);
  head.sample_time = record.sample_time;
  head.score_from = record.score_from;
  for (long k : record.sensor_steps)
    if (k < length) head.sensor_steps.push_back(k);
  return head;
}

Eigen::VectorXd Candidate::Predict(const Eigen::VectorXd& x, const GapRecord& record,
                                   Nuisance* nuisance) const {
  long taken_up = 0;
  const std::vector<double> plays = PlayStates(x, record, spec_.segment > 0 ? &taken_up : nullptr);
  if (plays.empty()) return PredictFrom(x, record, nuisance, 0.0);
  // Under multiple shooting every segment has a free state, so the play's start shows in the
  // segments up to the one where it is taken up (and beyond only through the nuisance they
  // share): the start is chosen on those segments when they are at most half the record (then
  // the chosen start is predicted on the whole record). 10^4 samples at 500 per segment under a
  // slow input: six short predictions and one whole instead of seven whole.
  const GapRecord* scored = &record;
  GapRecord head;
  if (spec_.segment > 0) {
    const long shows = std::max<long>(taken_up, record.score_from);  // its segment: the last it shows in
    long end = record.y.size();
    for (const auto& segment : Segments(record, spec_.segment))
      if (segment.first <= shows && shows < segment.first + segment.second) end = segment.first + segment.second;
    if (2 * end <= record.y.size()) {
      head = RecordHead(record, end);
      scored = &head;
    }
  }
  Eigen::VectorXd best;
  double best_sse = INFINITY, chosen = plays.front();
  std::vector<double> sse(plays.size());
  FreeRows rows;  // the same linear part for every play state
  const auto consider = [&](double play) {
    Eigen::VectorXd y = PredictFrom(x, *scored, nullptr, play, &rows);
    const long n = scored->y.size() - scored->score_from;
    const double e = (scored->y.tail(n) - y.tail(n)).squaredNorm();
    if (best.size() == 0 || e < best_sse || (std::isnan(best_sse) && !std::isnan(e)))
      best_sse = e, best = std::move(y), chosen = play;
    return e;
  };
  for (size_t i = 0; i < plays.size(); ++i) sse[i] = consider(plays[i]);
  // Between the band's points (plays 1..5, equally spaced) the sum of squares is piecewise
  // quadratic in the play: one parabola step through the best of them and its neighbours.
  size_t at = 1;
  for (size_t i = 2; i < plays.size(); ++i)
    if (sse[i] < sse[at]) at = i;
  const size_t mid = std::clamp<size_t>(at, 2, plays.size() - 2);
  const double h = plays[mid + 1] - plays[mid];
  const double curvature = sse[mid + 1] - 2 * sse[mid] + sse[mid - 1];
  if (h > 0 && curvature > 0) {
    const double vertex = plays[mid] - 0.5 * h * (sse[mid + 1] - sse[mid - 1]) / curvature;
    consider(std::clamp(vertex, plays[mid - 1], plays[mid + 1]));
  }
  if (nuisance || scored != &record) best = PredictFrom(x, record, nuisance, chosen, &rows);
  return best;
}

Candidate::FreeRows Candidate::Rows(const Eigen::VectorXd& x, double sample_time, long longest,
                                    bool absolute_sensor) const {
  FreeRows rows;
  rows.longest = longest;
  const TransferFunction linear = LinearPart(x);
  const StateSpace sampled = spec_.free_state ? SampledUndelayed(linear, sample_time) : StateSpace{};
  rows.free = FreeResponse(sampled, longest);
  rows.first = FirstSegmentState(spec_, linear, sampled, sample_time, longest, rows.free);
  // Behind a |y| sensor, the rig settled before the record: a direction for the fold's grid.
  if (absolute_sensor) rows.settled = SettledDirection(sampled, rows.first.cols() > rows.free.cols());
  return rows;
}

// Nuisance parameters by variable projection (Golub–Pereyra): the output offset and the free
// initial state enter the prediction linearly, ŷ = ŷ_sim + b·1 + F(θ)·x0 on each segment
// (F = the sampled plant's free response C A^k), so for given θ, φ they are the least-squares
// solution, eliminated from the nonlinear fit. With `segment` > 0 every segment of that many
// samples gets its own state (multiple shooting without continuity constraints). A candidate
// with an output map has ŷ = map(ŷ_sim + F(θ)·x0) + b instead, fitted by Gauss–Newton
// (OffsetAndStateThroughMaps): the segment's state is the plant's, before the sensor.
Eigen::VectorXd Candidate::PredictFrom(const Eigen::VectorXd& x, const GapRecord& record, Nuisance* nuisance,
                                       double play_state, FreeRows* rows) const {
  std::vector<Effect> maps;
  if (nuisance) nuisance->output_level = Eigen::VectorXd::Zero(record.y.size());
  Eigen::VectorXd y = Simulate(x, record, spec_.free_state ? &maps : nullptr, play_state);
  if (!y.allFinite()) return y;
  const auto segments = Segments(record, spec_.segment);
  const long longest = Longest(segments);
  FreeRows own;
  if (!rows) rows = &own;
  if (rows->longest != longest)
    *rows = Rows(x, record.sample_time, longest, std::any_of(maps.begin(), maps.end(), IsAbsoluteSensor));
  const Eigen::MatrixXd &free = rows->free, &first = rows->first;
  const Eigen::VectorXd& settled = rows->settled;
  if (!maps.empty() && !segments.empty()) {  // the unscored warm-up: the maps alone
    Eigen::VectorXd head = y.head(segments.front().first);
    ApplyOutputMaps(maps, head, nullptr);
    y.head(head.size()) = head;
  }
  // Clips alone take the offset inside them (OffsetAndStateThroughMaps): their limits are in the
  // measured output's coordinates. A sensor map keeps it after (its fold is at the plant's zero).
  const bool offset_inside =
      std::none_of(maps.begin(), maps.end(), [](const Effect& e) { return e.kind != EffectKind::kOutputSaturation; });
  // A sensor map with its offset after it, on shooting segments: the record's sensor has one
  // offset, so its segments share b. Free per segment, b and the level of the plant's state
  // before the map would let each segment sit on its own stretch of the map — its own slope, a
  // gain per segment, or behind |y| a fold of its own — and on an integrating plant, where the
  // state's level is free, a y², y³ map took up a load disturbance's walk that way (`gap bench
  // --integrating --process-noise 0.5 --only none --seed 2002 --offsets`: cases 117 and 234
  // named sensor_nonlinearity, LR 244 and 176). Each segment is fitted first with b free (its
  // basin: the starts of OffsetAndStateThroughMaps), then again with b held at the record's b
  // (below). A joint Gauss–Newton step on b and every segment's state together after that cost
  // ~1.9 s of the 12.7 s of `gap_benchmark --benchmark_filter=BM_DiagnosePair/1/10000/1` and
  // changed no verdict of the benches that motivated the sharing (docs/gap.md, stop 42).
  const bool share_offset = !maps.empty() && !offset_inside && segments.size() > 1;
  std::vector<Eigen::VectorXd> shared_coefs;
  Eigen::VectorXd shared_fitted;
  if (share_offset) {
    std::vector<const Eigen::MatrixXd*> states;
    std::vector<Eigen::MatrixXd> sensors;
    // Behind |y| a segment's own b is fixed only where the plant's output passes the fold: on a
    // segment that stays on one side, b and the state's level are one direction (`folding`: the
    // own b of the segments that pass it).
    const bool fold = std::any_of(maps.begin(), maps.end(), IsAbsoluteSensor);
    std::vector<double> own, folding;
    std::vector<Eigen::VectorXd> first_pass, level;  // each segment's own fit; its level direction
    std::vector<double> slope_mean;                  // the maps' mean slope on the segment
    // The direction of the state that holds a level over a whole segment (an integrator's: F v
    // = 1), for the first segment's state and the later ones'; empty where there is none.
    auto level_of = [](const Eigen::MatrixXd& f, long len) {
      Eigen::VectorXd v;
      if (f.cols() == 0 || f.rows() < len) return v;
      v = f.topRows(len).completeOrthogonalDecomposition().solve(Eigen::VectorXd::Ones(len));
      if (!(((f.topRows(len) * v).array() - 1.0).matrix().norm() < 1e-3 * std::sqrt(double(len))) || !v.allFinite())
        v.resize(0);
      return v;
    };
    // (A record scored from later on has no segment at sample 0, whose state `first` is.)
    const Eigen::VectorXd first_level =
        segments.front().first == 0 ? level_of(first, segments.front().second) : Eigen::VectorXd();
    const Eigen::VectorXd later_level = level_of(free, segments[1].second);  // share_offset: 2 or more
    for (const auto& [start, len] : segments) {
      states.push_back(start == 0 ? &first : &free);
      sensors.push_back(SensorColumns(record, start, len, spec_.drift));
      const Eigen::VectorXd coef =
          OffsetAndStateThroughMaps(record.y.segment(start, len), y.segment(start, len), *states.back(), maps, nullptr,
                                    false, sensors.back(), start == 0 ? settled : Eigen::VectorXd());
      first_pass.push_back(coef);
      const Eigen::MatrixXd& f = *states.back();
      const long rows = std::min<long>(len, f.rows()), n = f.cols();
      Eigen::VectorXd plant = y.segment(start, len), slope;
      if (n > 0 && coef.allFinite()) plant.head(rows) += f.topRows(rows) * coef.segment(1, n);
      Eigen::VectorXd mapped = plant;
      ApplyOutputMaps(maps, mapped, &slope);
      slope_mean.push_back(slope.size() > 0 ? slope.mean() : 1.0);
      level.push_back(start == 0 ? first_level : later_level);
      if (!std::isfinite(coef(0))) continue;
      own.push_back(coef(0));
      if (fold && plant.minCoeff() < 0 && plant.maxCoeff() > 0) folding.push_back(coef(0));
    }
    // The record's b: behind |y|, the median of the b of the segments that pass the fold, where
    // b is fixed, or the one of their b that scores best (below), whichever leaves the least
    // with b held; otherwise the mean of the segments' own (a smooth function of the candidate's
    // parameters, as the outer fit's finite differences need).
    std::vector<double> tried;
    // Each segment's own fit with b set to a candidate b and the level moved by the difference
    // through the maps' slope (the same fit where the segment keeps to one piece of |y|); its
    // own fit where the plant holds no level or its fit is not finite.
    auto shifted_start = [&](size_t j, double b) {
      Eigen::VectorXd shifted = first_pass[j];
      const bool from_own = shifted.allFinite() && level[j].size() > 0 && std::abs(slope_mean[j]) > 1e-3;
      if (from_own) {
        shifted.segment(1, level[j].size()) += level[j] * ((shifted(0) - b) / slope_mean[j]);
        shifted(0) = b;
      }
      return std::make_pair(from_own, shifted);
    };
    if (!folding.empty()) {
      std::sort(folding.begin(), folding.end());
      tried.push_back(folding[folding.size() / 2]);
      // Every folding segment's b scored by the record's fit from the shifted starts alone (no
      // refinement): the one that leaves the least is tried beside the median.
      double best_score = INFINITY, best_b = folding.front();
      for (double b : folding) {
        double score = 0.0;
        for (size_t j = 0; j < segments.size() && std::isfinite(score); ++j) {
          const auto [start, len] = segments[j];
          const auto [from_own, c] = shifted_start(j, b);
          if (!from_own) continue;
          Eigen::VectorXd m;
          ThroughMaps(y.segment(start, len), *states[j], maps, c, sensors[j], false, m, nullptr);
          score += (record.y.segment(start, len) - m).squaredNorm();
        }
        if (score < best_score) best_score = score, best_b = b;
      }
      if (best_b != tried.front()) tried.push_back(best_b);
    } else if (!own.empty()) {
      tried.push_back(std::accumulate(own.begin(), own.end(), 0.0) / own.size());
    }
    // Behind |y| the output never reads below b (|·| ≥ 0), and a segment that keeps to one side
    // of the fold takes any b under its own by moving its level away from the fold: the lowest
    // own b suits every such segment. The median and the mean above can lie above a segment's
    // readings, where no level fits it: a plant below the fold for the whole record (an actuator
    // offset driving an integrator down, `gap bench --cases 39 --seed 7303 --integrating
    // --offsets --excitation steps`, case 37), whose segments grazing the fold (by 0.008 on an
    // output of 8) counted as folding with own b up to 3.7 where the sensor offset was −1.63.
    if (fold && !own.empty()) {
      const double lowest = *std::min_element(own.begin(), own.end());
      if (std::find(tried.begin(), tried.end(), lowest) == tried.end()) tried.push_back(lowest);
    }
    if (tried.empty()) tried.push_back(0.0);
    double best_sse = INFINITY;
    for (double b : tried) {
      std::vector<Eigen::VectorXd> coefs;
      Eigen::VectorXd fitted_all = y;
      double sse = 0.0;
      for (size_t j = 0; j < segments.size(); ++j) {
        const auto [start, len] = segments[j];
        Eigen::VectorXd fitted;
        // From the segment's shifted own fit; every start again where the plant holds no level.
        const auto [from_own, shifted] = shifted_start(j, b);
        coefs.push_back(OffsetAndStateThroughMaps(record.y.segment(start, len), y.segment(start, len), *states[j],
                                                  maps, &fitted, false, sensors[j],
                                                  start == 0 ? settled : Eigen::VectorXd(), &b,
                                                  from_own ? &shifted : nullptr));
        fitted_all.segment(start, len) = fitted;
        sse += (record.y.segment(start, len) - fitted).squaredNorm();
      }
      if (sse < best_sse || shared_coefs.empty()) best_sse = sse, shared_coefs.swap(coefs), shared_fitted.swap(fitted_all);
    }
  }
  for (size_t j = 0; j < segments.size(); ++j) {
    const auto [start, len] = segments[j];
    // The delay line's level before the record on the segment that starts the record; a later
    // segment (or a record scored from later on) has the record's own input in the line.
    const Eigen::MatrixXd& state = start == 0 ? first : free;
    // The sensor's own columns beside the offset (after the output maps, where the sensor is): a
    // drift's ramp, the level each sensor step adds. Behind clips, whose limits are in the
    // measured output's coordinates and whose offset is inside them, the ramp starts at zero with
    // the record: a drift after the clip moves the clipped readings, and centred on each record
    // (or each shooting segment) it would put the limits where that record's (segment's) mean
    // drift puts them — the estimation record's drifting up, the validation record's down (`gap
    // bench --cases 39 --seed 7403 --offsets --add-drift 3 --excitation noise`, the
    // output_saturation cases 10, 23 and 36: the clip alone left 2× the noise variance on
    // validation, and a sensor map beside it, with its offset after the clip, was named).
    const bool anchored = !maps.empty() && offset_inside;
    const Eigen::MatrixXd sensor = SensorColumns(record, start, len, spec_.drift, anchored);
    const long n = state.cols(), m = sensor.cols();
    Eigen::VectorXd coef;
    if (!maps.empty()) {  // the state inside the maps, the offset (and the sensor's columns) after them
      if (share_offset) {
        coef = shared_coefs[j];
        y.segment(start, len) = shared_fitted.segment(start, len);
      } else {
        Eigen::VectorXd fitted;
        coef = OffsetAndStateThroughMaps(record.y.segment(start, len), y.segment(start, len), state, maps, &fitted,
                                         offset_inside, sensor, start == 0 ? settled : Eigen::VectorXd());
        y.segment(start, len) = fitted;
      }
    } else {
      coef = OffsetAndStateFit(record.y.segment(start, len) - y.segment(start, len), state, nullptr,
                               m > 0 ? &sensor : nullptr);
      if (coef.allFinite()) {
        y.segment(start, len).array() += coef(0);
        const long rows = std::min<long>(len, state.rows());
        if (n > 0) y.segment(start, rows) += state.topRows(rows) * coef.segment(1, n);
        if (m > 0) y.segment(start, len) += sensor * coef.tail(m);
      }
    }
    if (nuisance && j == 0) {
      nuisance->output_offset = coef(0);
      nuisance->output_drift = spec_.drift ? coef(1 + n) : 0.0;
      nuisance->initial_state_rms = n > 0 ? coef.segment(1, n).norm() / std::sqrt(double(n)) : 0.0;
      nuisance->output_level.resize(record.y.size());
      for (long k = 0; k < record.y.size(); ++k) {
        nuisance->output_level(k) =
            coef(0) + nuisance->output_drift * (anchored ? k : k - start - 0.5 * (len - 1)) * record.sample_time;
        if (m > (spec_.drift ? 1 : 0) && k >= start) {  // the sensor steps' levels, as of sample k
          const long row = std::min(k - start, len - 1);
          for (long i = spec_.drift ? 1 : 0; i < m; ++i) nuisance->output_level(k) += sensor(row, i) * coef(1 + n + i);
        }
      }
    }
  }
  // Quantisation last, as a smoothed staircase on the lattice the samples sit on (φ + k·q, φ
  // from the data: a sensor offset after the rounding puts it anywhere), so the output offset
  // and the initial state are fitted to the unrounded prediction, whose error is zero-mean.
  for (size_t i = 0; i < spec_.kinds.size(); ++i)
    if (spec_.kinds[i] == EffectKind::kOutputQuantization) {
      const double q = spec_.fixed[i].at(0), phase = spec_.fixed[i].size() > 1 ? spec_.fixed[i][1] : 0.0;
      y.array() -= phase;
      SmoothedStaircase(y, q, q * std::exp(std::clamp(x(block_start_[i]), -12.0, 3.0)));
      y.array() += phase;
    }
  if (nuisance) nuisance->input_offset = InputOffset(x);
  return y;
}

TransferFunction Candidate::LinearPart(const Eigen::VectorXd& x) const {
  TransferFunction linear = Plant(x);
  for (const Effect& e : Effects(x))
    if (IsLinearEffect(e.kind)) linear = ApplyLinearEffect(linear, e);
  return linear;
}

long Candidate::NuisanceColumns(const Eigen::VectorXd& x, const std::vector<GapRecord>& records) const {
  const TransferFunction linear = LinearPart(x);
  long columns = 0;
  for (const GapRecord& record : records) {
    const auto segments = Segments(record, spec_.segment);
    const long longest = Longest(segments);
    const StateSpace sampled = spec_.free_state ? SampledUndelayed(linear, record.sample_time) : StateSpace{};
    const Eigen::MatrixXd free = FreeResponse(sampled, longest);
    const Eigen::MatrixXd first = FirstSegmentState(spec_, linear, sampled, record.sample_time, longest, free);
    for (const auto& segment : segments) {
      long rank = 0;
      const Eigen::MatrixXd sensor = SensorColumns(record, segment.first, segment.second, spec_.drift);
      OffsetAndStateFit(Eigen::VectorXd::Zero(segment.second), segment.first == 0 ? first : free, &rank,
                        sensor.cols() > 0 ? &sensor : nullptr);
      columns += rank;
    }
    if (!PlayStates(x, record).empty()) ++columns;  // where the play was before the record
  }
  return columns;
}

void Residuals::operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
  long offset = 0;
  for (const GapRecord& rec : *records) {
    const long n = rec.u.size() - rec.score_from;
    Eigen::VectorXd y_hat;
    bool ok = true;
    try {
      y_hat = candidate->Predict(x, rec);
    } catch (const std::exception&) {
      ok = false;  // an invalid parameter set (e.g. a non-finite pole): a large residual
    }
    if (ok) r.segment(offset, n) = rec.y.tail(n) - y_hat.tail(n);
    for (long k = 0; k < n; ++k)
      if (!ok || !std::isfinite(r(offset + k))) r(offset + k) = 1e6 * (1 + std::abs(rec.y(k)));
    offset += n;
  }
}

double Mse(const Residuals& residuals, const Eigen::VectorXd& x) {
  Eigen::VectorXd r(residuals.count);
  residuals(x, r);
  return r.squaredNorm() / std::max<long>(1, residuals.count);
}

FitOutcome Minimise(const Residuals& residuals, Eigen::VectorXd x, int max_evaluations) {
  FitOutcome out;
  int calls = 0;
  if (x.size() > 0) {
    LmFunctor functor{residuals, static_cast<int>(x.size()), &calls};
    Eigen::NumericalDiff<LmFunctor> numeric(functor);
    Eigen::LevenbergMarquardt<Eigen::NumericalDiff<LmFunctor>> lm(numeric);
    lm.parameters.maxfev = max_evaluations;
    lm.parameters.xtol = 1e-7;
    lm.parameters.ftol = 1e-9;
    const auto status = lm.minimize(x);
    out.converged = status == Eigen::LevenbergMarquardtSpace::RelativeReductionTooSmall ||
                    status == Eigen::LevenbergMarquardtSpace::RelativeErrorTooSmall ||
                    status == Eigen::LevenbergMarquardtSpace::RelativeErrorAndReductionTooSmall ||
                    status == Eigen::LevenbergMarquardtSpace::CosinusTooSmall;
  } else {
    out.converged = true;
  }
  out.x = x;
  out.mse = Mse(residuals, x);
  out.evaluations = calls + 1;
  return out;
}

// Which mode is the added one. The refitted plant times ω²/(s² + 2ζωs + ω²) is the same model
// whichever of the two underdamped modes sits in the resonance block, and the fit may leave G0's
// own mode there with the new one in the plant (`gap bench --samples 1500 --seed 802 --offsets`,
// case 4: a 13 rad/s mode, ζ 0.084, reported as 3.14 rad/s, ζ 0.455, G0's mode, with the plant's
// pair at 12.9 rad/s). The added mode is the one farther from G0's poles: when a pair of the
// refitted plant lies more than twice as far from them (relative distance) as the block's mode,
// the two are exchanged — the plant keeps its DC gain and the product does not change — and the
// block's 1σ, which belonged to the other mode, is dropped.
static void ReportAddedModeAsResonance(const TransferFunction& g0, CandidateFit& c) {
  if (c.plant.sample_time != 0 || g0.sample_time != 0) return;
  const Eigen::VectorXcd g0_poles = PolynomialRoots(g0.den);
  if (g0_poles.size() == 0) return;
  auto distance = [&](std::complex<double> z) {
    double d = INFINITY;
    for (long i = 0; i < g0_poles.size(); ++i)
      d = std::min(d, std::abs(z - g0_poles(i)) / std::max({std::abs(z), std::abs(g0_poles(i)), 1e-12}));
    return d;
  };
  for (size_t b = 0; b < c.effects.size(); ++b) {
    Effect& e = c.effects[b];
    if (e.kind != EffectKind::kUnmodelledResonance || e.params.size() < 2 || !(e.params[1] < 1)) continue;
    const double wr = e.params[0], zr = e.params[1];
    const std::complex<double> r(-zr * wr, wr * std::sqrt(1 - zr * zr));
    Eigen::VectorXcd poles = PolynomialRoots(c.plant.den);
    long far = -1;
    for (long i = 0; i < poles.size(); ++i)
      if (poles(i).imag() > 1e-9 * std::abs(poles(i)) && (far < 0 || distance(poles(i)) > distance(poles(far)))) far = i;
    if (far < 0 || !(distance(poles(far)) > 2 * distance(r))) continue;
    const std::complex<double> q = poles(far);
    long twin = -1;  // its conjugate
    for (long i = 0; i < poles.size(); ++i)
      if (i != far && (twin < 0 || std::abs(poles(i) - std::conj(q)) < std::abs(poles(twin) - std::conj(q)))) twin = i;
    if (twin < 0) continue;
    poles(far) = r;
    poles(twin) = std::conj(r);
    const double wq = std::abs(q);
    c.plant.num *= (wr * wr) / (wq * wq);
    c.plant.den = c.plant.den(0) * PolynomialFromRoots(poles);
    e.params = {wq, -q.real() / wq};
    c.effects_std[b] = {kNan, kNan};  // FitSpec gives every effect its row
    if (b == 0) c.effect = e, c.param_std = c.effects_std[0];
  }
}

// A starting point: the prefix (plant, du, the earlier effects' φ) and the last effect's start.
static Eigen::VectorXd StartPoint(const Candidate& cand, const Eigen::VectorXd& prefix, const std::vector<double>& start) {
  const size_t last = cand.Blocks() - 1;
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(cand.Size());
  const long head = std::min<long>(prefix.size(), cand.BlockStart(last));
  x0.head(head) = prefix.head(head);
  if (cand.BlockSize(last) > 0) x0.segment(cand.BlockStart(last), cand.BlockSize(last)) = cand.Phi(last, start);
  return x0;
}

// Every prefix times every start of the last block, as full starting points.
static std::vector<Eigen::VectorXd> StartPoints(const Candidate& cand, const std::vector<Eigen::VectorXd>& prefixes,
                                                const std::vector<std::vector<double>>& starts) {
  std::vector<Eigen::VectorXd> points;
  for (const Eigen::VectorXd& prefix : prefixes)
    for (const auto& start : starts) points.push_back(StartPoint(cand, prefix, start));
  return points;
}

std::vector<Eigen::VectorXd> BestStartPoints(const FitContext& ctx, const CandidateSpec& spec,
                                             const std::vector<Eigen::VectorXd>& prefixes,
                                             const std::vector<std::vector<double>>& starts, size_t keep) {
  const Candidate cand(*ctx.g0, spec, ctx.scales, ctx.options->substeps);
  const std::vector<Eigen::VectorXd> points = StartPoints(cand, prefixes, starts);
  if (points.size() <= keep) return points;
  const Residuals residuals{&cand, ctx.estimation, ctx.n_est};
  std::vector<std::pair<double, size_t>> scored;
  for (size_t i = 0; i < points.size(); ++i) {
    const double mse = Mse(residuals, points[i]);
    scored.push_back({std::isfinite(mse) ? mse : INFINITY, i});
  }
  std::stable_sort(scored.begin(), scored.end());
  // Points with the same cost are taken once: a limit or a width that no sample reaches leaves
  // the prediction as the prefix had it, whatever its value, and gives the fit no slope to
  // follow; three such starts would be one fit three times (effect_pairs.cc: an input limit
  // after friction, `gap bench --cases 52 --seed 7704 --offsets --combos 0.3 --ts 0.002
  // --samples 6000` case 26).
  std::vector<Eigen::VectorXd> best;
  double last = NAN;
  for (size_t i = 0; i < scored.size() && best.size() < keep; ++i) {
    if (std::abs(scored[i].first - last) <= 1e-12 * last) continue;
    last = scored[i].first;
    best.push_back(points[scored[i].second]);
  }
  return best;
}

CandidateSpec SpecFor(const FitContext& ctx, std::vector<EffectKind> kinds,
                      std::vector<std::vector<double>> fixed) {
  CandidateSpec spec = ctx.nuisance;
  spec.kinds = std::move(kinds);
  spec.fixed = std::move(fixed);
  spec.fixed.resize(spec.kinds.size());
  // An actuator offset is a separate parameter only where it is not an output offset in
  // disguise: with a nonlinear effect (it moves the operating point on the nonlinearity), or on
  // an integrating plant (it makes a ramp). Before a linear stable plant, du ≡ b/G0(0).
  // Coulomb friction sees it: where the record starts stuck, du decides how far the drive
  // must move before the axis breaks away. Quantisation does not: its lattice is placed in
  // the measured coordinates (Predict).
  // Nor does a backlash: the play operator commutes with a shift (B(u + c) = B(u) + c, its
  // play shifted too), and where its play was before the record is a nuisance of its own
  // (PlayStates), so beside a backlash alone du is an output offset again (fitted, it wandered
  // off on `--pairs any --plants two-mass --seed 971` case 28 — the play's first input at 1.4
  // for −0.05 — and the input limit searched as the second effect had its limits against that).
  bool nonlinear = false;
  for (EffectKind k : spec.kinds)
    if (k != EffectKind::kNone && k != EffectKind::kParameterMismatch && !IsLinearEffect(k) &&
        k != EffectKind::kOutputQuantization && k != EffectKind::kBacklash)
      nonlinear = true;
  spec.input_offset = ctx.integrating || nonlinear;
  return spec;
}

void FitSpec(const FitContext& ctx, const CandidateSpec& spec,
             const std::vector<Eigen::VectorXd>& prefixes,
             const std::vector<std::vector<double>>& starts, CandidateWork& w) {
  const Candidate cand(*ctx.g0, spec, ctx.scales, ctx.options->substeps);
  FitSpecFrom(ctx, spec, StartPoints(cand, prefixes, starts), w);
}

void FitSpecFrom(const FitContext& ctx, const CandidateSpec& spec, const std::vector<Eigen::VectorXd>& points,
                 CandidateWork& w) {
  const GapOptions& options = *ctx.options;
  Candidate cand(*ctx.g0, spec, ctx.scales, options.substeps);
  Residuals residuals{&cand, ctx.estimation, ctx.n_est};
  FitOutcome best;
  int evaluations = 0;
  for (const Eigen::VectorXd& x0 : points) {
    FitOutcome f = Minimise(residuals, x0, options.evaluations_per_start * (cand.Size() + 1));
    evaluations += f.evaluations;
    if (!(f.mse >= best.mse)) best = f;  // also takes the first (best.mse is NaN)
  }
  FitOutcome polished = Minimise(residuals, best.x, options.evaluations_polish * (cand.Size() + 1));
  evaluations += polished.evaluations;
  if (polished.mse < best.mse) best = polished;
  CandidateFit& c = w.fit;
  c.effect = cand.EffectOf(best.x);
  c.effects = cand.Effects(best.x);
  c.plant = cand.Plant(best.x);
  c.parameters = cand.Size();
  c.estimation_mse = best.mse;
  Nuisance nuisance;
  cand.Predict(best.x, ctx.estimation->front(), &nuisance);
  c.input_offset = nuisance.input_offset;
  c.input_offset_fitted = spec.input_offset;
  for (const GapRecord& r : *ctx.estimation) {
    cand.Predict(best.x, r, &nuisance);
    c.output_offsets.push_back(nuisance.output_offset);
    if (spec.drift) c.output_drifts.push_back(nuisance.output_drift);
  }
  w.x = best.x;
  w.spec = spec;
  w.y_val = Stack(*ctx.validation, [&](const GapRecord& r) { return cand.Predict(best.x, r); });
  // Linearised 1σ of the effect parameters: σ̂²(JᵀJ)⁻¹ in φ, mapped through dp/dφ.
  c.effects_std.clear();
  if (cand.EffectParams() > 0 || cand.NuisanceParams() > 0) {
    int calls = 0;
    LmFunctor functor{residuals, cand.Size(), &calls};
    Eigen::NumericalDiff<LmFunctor> numeric(functor);
    Eigen::MatrixXd jac(ctx.n_est, cand.Size());
    numeric.df(best.x, jac);
    evaluations += calls;
    const Eigen::MatrixXd cov =
        best.mse * (jac.transpose() * jac).completeOrthogonalDecomposition().pseudoInverse();
    if (cand.NuisanceParams() > 0) {
      const int col = cand.PlantParams();
      const double t = std::tanh(best.x(col));
      c.input_offset_std = std::sqrt(std::max(0.0, cov(col, col))) * (1 - t * t) * ctx.scales.u_max;
    }
    for (int b = 0; b < cand.Blocks(); ++b) {
      const EffectKind kind = spec.kinds[b];
      if (kind == EffectKind::kNone || kind == EffectKind::kParameterMismatch) continue;
      std::vector<double> sd_out(EffectParameterNames(kind).size(), kNan);
      for (int j = 0; j < cand.BlockSize(b); ++j) {
        const int col = cand.BlockStart(b) + j;
        Eigen::VectorXd bumped = best.x;
        const double h = 1e-6 * std::max(1.0, std::abs(bumped(col)));
        bumped(col) += h;
        const Effect lo = cand.EffectAt(best.x, b), hi = cand.EffectAt(bumped, b);
        const double sd = std::sqrt(std::max(0.0, cov(col, col)));
        for (size_t p = 0; p < lo.params.size(); ++p) {
          const double dp = (hi.params[p] - lo.params[p]) / h;
          if (dp != 0) sd_out[p] = std::abs(dp) * sd;
        }
      }
      c.effects_std.push_back(sd_out);
    }
  }
  while (c.effects_std.size() < c.effects.size())
    c.effects_std.push_back(std::vector<double>(EffectParameterNames(c.effects[c.effects_std.size()].kind).size(), kNan));
  c.param_std = c.effects_std.empty() ? std::vector<double>{} : c.effects_std.front();
  ReportAddedModeAsResonance(*ctx.g0, c);
  c.evaluations += evaluations;
}

// An input limit that few estimation samples reach (under 2 %: a multilevel record's lowest
// level, clipped a little, which the plant's gain and offset make up for) is barely seen by the
// fit, which leaves it wherever it ended — often at the edge of the estimation records, where
// it clips validation samples that reach further. A limit the data do not show is no limit: it is moved
// beyond all records (estimation and validation) and the fit polished from there, kept when
// the estimation MSE stays within two standard deviations of a χ² sample variance.
static void ReleaseUnreachedLimits(const FitContext& ctx, CandidateWork& w) {
  const double lo = w.fit.effect.params[0], hi = w.fit.effect.params[1], du = w.fit.input_offset;
  long below = 0, above = 0, n = 0;
  double v_min = INFINITY, v_max = -INFINITY;
  for (const auto* records : {ctx.estimation, ctx.validation})
    for (const GapRecord& r : *records)
      for (long k = r.score_from; k < r.u.size(); ++k) {
        const double v = r.u(k) + du;
        v_min = std::min(v_min, v);
        v_max = std::max(v_max, v);
        if (records == ctx.estimation) ++n, below += v < lo, above += v > hi;
      }
  const long few = std::max<long>(3, static_cast<long>(0.02 * n));  // the lowest of ~50 levels
  const double span = v_max - v_min;
  bool free_lo = below < few && lo > v_min - span, free_hi = above < few && hi < v_max + span;
  // Both few: the one fewer samples reach is tried (a real limit that 0.6 % of the samples
  // reach, and one at the edge of the data that none does: `--seed 52 --ts 0.05`, case 18).
  if (free_lo && free_hi) {
    if (below == above) return;
    free_lo = below < above;
    free_hi = !free_lo;
  }
  if (!(span > 0) || (!free_lo && !free_hi)) return;
  CandidateWork trial;
  FitSpec(ctx, w.spec, {w.x}, {{free_lo ? v_min - 2 * span : lo, free_hi ? v_max + 2 * span : hi}}, trial);
  if (!(trial.fit.estimation_mse <= w.fit.estimation_mse * SampleVarianceTolerance(n))) return;
  // One-sided or two-sided is a variant that extrapolates differently, so the validation
  // records decide as well: a limit that few estimation samples reach but the validation
  // records show stays (`--plants zeros --combos 1 --seed 204`, case 18: 0.8 % of either record
  // below it, with an unmodelled lag beside it the estimation MSE hardly moved, and releasing it
  // took the validation NRMSE from 0.031 to 0.045).
  if (!(ValidationMse(ctx, trial.y_val) <= ValidationMse(ctx, w.y_val) * SampleVarianceTolerance(ctx.n_val))) return;
  trial.fit.evaluations += w.fit.evaluations;
  trial.fit.note = std::string(free_lo ? "lower" : "upper") + " limit not reached by the estimation records: none assumed";
  w = std::move(trial);
}

double VariantCriterion(const FitContext& ctx, const CandidateWork& trial, size_t variants) {
  // Variants that extrapolate differently (the sensor map as a polynomial or as |y|) are chosen
  // on the validation records, where the difference shows (a record whose output never changes
  // sign cannot tell them apart; the polynomial's extra bend fitted there can fold the wrong way
  // on another): the validation BIC. One variant: the estimation BIC, as for any fit.
  if (variants > 1)
    return ValidationBic(ctx.n_val, ctx.n_est, ValidationMse(ctx, trial.y_val), trial.fit.parameters, 0);
  return ctx.n_est * std::log(trial.fit.estimation_mse) + trial.fit.parameters * std::log(double(ctx.n_est));
}

void FitEffect(const FitContext& ctx, EffectKind kind, CandidateWork& w) {
  const std::vector<GapRecord>& estimation = *ctx.estimation;
  (void)estimation;
  // Sub-variants fixed before the fit: |y| for the sensor, the step for quantisation.
  std::vector<std::vector<double>> variants = {{}};
  if (kind == EffectKind::kSensorNonlinearity) variants = {{}, {1.0}};
  if (kind == EffectKind::kOutputQuantization) variants = {{ctx.q_step, ctx.q_phase}};
  // The refit as a base for the linear-in-parameters starts.
  const CandidateSpec refit_spec = SpecFor(ctx, {EffectKind::kParameterMismatch});
  const Candidate refit(*ctx.g0, refit_spec, ctx.scales, ctx.options->substeps);
  double best_criterion = std::numeric_limits<double>::infinity();
  int evaluations = 0;
  for (const auto& fixed : variants) {
    const CandidateSpec spec = SpecFor(ctx, {kind}, {fixed});
    // Starts: the plant as given (right when the effect is the whole gap) and as refitted
    // (which has already absorbed what a linear refit can), times the effect's starts.
    Eigen::VectorXd from_refit = Eigen::VectorXd::Zero(ctx.refit_size + (spec.input_offset ? 1 : 0));
    from_refit.head(ctx.refit_fit.x.size()) = ctx.refit_fit.x;
    const Eigen::VectorXd from_g0 = Eigen::VectorXd::Zero(from_refit.size());
    std::vector<std::vector<double>> starts = Starts(kind, ctx.scales);
    if (fixed.empty()) {
      const auto linear = LinearStarts(ctx, kind, refit, ctx.refit_fit.x);
      starts.insert(starts.begin(), linear.begin(), linear.end());
    }
    std::vector<Eigen::VectorXd> prefixes = {from_refit, from_g0};
    if (spec.input_offset && ctx.integrating) {
      // On an integrating plant the actuator offset sets the drift the per-segment states
      // cannot take: G0 as given with the refit's du (the refit's θ has also bent to the effect).
      Eigen::VectorXd g0_du = from_g0;
      g0_du(ctx.refit_size - 1) = from_refit(ctx.refit_size - 1);  // x = [θ | du]
      prefixes.push_back(g0_du);
      // Behind |y| a plant whose output stays below the fold is read mirrored (|y| = −y): the
      // readings drift the other way from the plant, and the du that drives the plant is the one
      // that fits G0 to −y (ctx.mirrored_du, fitted beside G0 itself), which neither the refit
      // nor G0 reaches (a refit keeps the sign of G0's gain). `gap bench --cases 260 --seed 7310
      // --integrating --offsets --only sensor_nonlinearity`, case 219: an actuator offset of
      // −0.78 drove the integrator from −3 to −55; from the refit's du the |y| fit ran to
      // du = −2.69, its bound, and left the estimation records where the refit did (0.367 for a
      // noise variance of 0.215).
      if (kind == EffectKind::kSensorNonlinearity && !fixed.empty()) {
        Eigen::VectorXd mirrored = from_g0;
        mirrored(ctx.refit_size - 1) = ctx.mirrored_du;
        prefixes.push_back(mirrored);
      }
    }
    CandidateWork trial;
    FitSpec(ctx, spec, prefixes, starts, trial);
    evaluations += trial.fit.evaluations;
    const double criterion = VariantCriterion(ctx, trial, variants.size());
    if (criterion < best_criterion) {
      best_criterion = criterion;
      w = trial;
    }
  }
  w.fit.evaluations = evaluations;
  if (kind == EffectKind::kInputSaturation) ReleaseUnreachedLimits(ctx, w);
  if (kind == EffectKind::kOutputQuantization)
    w.fit.note = "step from the samples' lattice, strength R = " + std::to_string(ctx.q_strength);
}

}  // namespace idrig::gap_detail
