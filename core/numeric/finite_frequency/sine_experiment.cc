#include "core/numeric/finite_frequency/sine_experiment.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace idrig {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

void Require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument("sine experiment: " + message);
}

double UnitUniform(std::mt19937_64& engine) {
  return static_cast<double>(engine() >> 11) * 0x1.0p-53;
}

// The augmented autonomous-plus-disturbance model
//   state X = [x_w; x_f; z_1; …; z_L],  X' = F X + G f,  y = H X (+ D ũ),  ũ = Σ ρ_l z_l,1
// with x_w the plant driven by ũ, x_f the disturbance channel 1/d(s), and
// z_l = e^(λt)[sin(ω_l t + φ_l), cos(ω_l t + φ_l)] the oscillators of the test signal.
struct Augmented {
  Eigen::MatrixXd F, G, H_total, H_natural, U;  // U: row giving ũ from X
  Eigen::VectorXd x0;
};

Augmented Build(const SineExperimentSetup& setup) {
  const StateSpace plant = ToStateSpace(setup.plant);
  TransferFunction channel;  // 1/d(s): the disturbance f enters (1) like k(p)u does
  channel.num = Eigen::VectorXd::Ones(1);
  channel.den = setup.plant.den;
  const StateSpace dist = ToStateSpace(channel);
  const int n = plant.Order(), m = dist.Order(), lines = static_cast<int>(setup.lines.size());
  const int size = n + m + 2 * lines;
  Augmented a;
  a.F = Eigen::MatrixXd::Zero(size, size);
  a.G = Eigen::MatrixXd::Zero(size, 1);
  a.U = Eigen::MatrixXd::Zero(1, size);
  a.x0 = Eigen::VectorXd::Zero(size);
  a.F.topLeftCorner(n, n) = plant.A;
  a.F.block(n, n, m, m) = dist.A;
  a.G.block(n, 0, m, 1) = dist.B;
  for (int l = 0; l < lines; ++l) {
    const SineLine& line = setup.lines[l];
    const int z = n + m + 2 * l;
    a.F(z, z) = setup.lambda;
    a.F(z, z + 1) = line.omega;
    a.F(z + 1, z) = -line.omega;
    a.F(z + 1, z + 1) = setup.lambda;
    a.x0(z) = std::sin(line.phase);
    a.x0(z + 1) = std::cos(line.phase);
    a.U(0, z) = line.amplitude;
  }
  a.F.topRows(n) += plant.B * a.U;  // x_w' = A x_w + b ũ
  a.H_natural = Eigen::MatrixXd::Zero(1, size);
  a.H_natural.block(0, n, 1, m) = dist.C;
  a.H_total = a.H_natural;
  a.H_total.leftCols(n) += plant.C;
  a.H_total += plant.D(0, 0) * a.U;
  return a;
}

struct Step {
  Eigen::MatrixXd phi, gamma;
};

Step Discretize(const Augmented& a, double h) {
  StateSpace model;
  model.A = a.F;
  model.B = a.G;
  model.C = a.H_total;
  model.D = Eigen::MatrixXd::Zero(1, 1);
  const StateSpace d = DiscretizeZoh(model, h);
  return {d.A, d.B};
}

}  // namespace

double PiecewiseConstantSignal::ValueAt(double t) const {
  const auto it = std::upper_bound(start_times.begin(), start_times.end(), t);
  if (it == start_times.begin()) return 0.0;
  return values[static_cast<size_t>(it - start_times.begin()) - 1];
}

PiecewiseConstantSignal RandomSquareWaveDisturbance(double amplitude, double omega_min,
                                                    double omega_max, double duration,
                                                    uint64_t seed, SquareWavePhase phase,
                                                    double start_time) {
  Require(std::isfinite(amplitude), "disturbance amplitude must be finite");
  Require(omega_min > 0.0 && omega_max >= omega_min && std::isfinite(omega_max),
          "disturbance frequencies need 0 < omega_min <= omega_max");
  Require(duration >= 0.0 && std::isfinite(duration), "duration must be >= 0");
  Require(start_time <= 0.0 && std::isfinite(start_time), "start_time must be <= 0");
  std::mt19937_64 engine(seed);
  PiecewiseConstantSignal f;
  double t = start_time;
  while (t <= duration) {
    // Eq. (39): f = a·sign(sin ω_f ·) on one period [t_c, t_c + 2π/ω_f), ω_f redrawn for the
    // next period.
    const double omega = omega_min + (omega_max - omega_min) * UnitUniform(engine);
    const double end = t + kTwoPi / omega;
    if (phase == SquareWavePhase::kPeriodStart) {
      // sin ω_f(t − t_c): the positive half-wave, then the negative one.
      f.start_times.push_back(t);
      f.values.push_back(amplitude);
      f.start_times.push_back(t + 0.5 * (end - t));
      f.values.push_back(-amplitude);
      t = end;
      continue;
    }
    // sin ω_f t with the experiment time t: one full period at a random phase.
    double piece = t;
    long zero = static_cast<long>(std::floor(t * omega / (kTwoPi / 2))) + 1;  // next zero of sin
    while (piece < end) {
      const double next = std::min(end, zero * (kTwoPi / 2) / omega);
      if (next > piece) {
        f.start_times.push_back(piece);
        f.values.push_back(std::sin(omega * 0.5 * (piece + next)) >= 0.0 ? amplitude : -amplitude);
      }
      piece = next;
      ++zero;
    }
    t = end;
  }
  return f;
}

SineExperimentRecord SimulateSineExperiment(const SineExperimentSetup& setup, double sample_time,
                                            int64_t num_samples) {
  Validate(setup.plant);
  Require(!setup.plant.IsDiscrete(), "the plant must be continuous (sample_time 0)");
  Require(setup.plant.num.size() <= setup.plant.den.size(), "the plant must be proper");
  Require(sample_time > 0.0 && std::isfinite(sample_time), "sample time must be positive");
  Require(num_samples >= 1, "need at least one sample");
  Require(std::isfinite(setup.lambda) && setup.lambda >= 0.0, "lambda must be >= 0");
  Require(setup.noise_bound >= 0.0, "noise bound must be >= 0");
  Require(setup.disturbance.start_times.size() == setup.disturbance.values.size(),
          "disturbance start_times and values differ in length");
  for (const SineLine& line : setup.lines)
    Require(std::isfinite(line.omega) && std::isfinite(line.amplitude) &&
                std::isfinite(line.phase),
            "test-signal lines must be finite");

  const Augmented a = Build(setup);
  const Step full = Discretize(a, sample_time);
  SineExperimentRecord record;
  record.sample_time = sample_time;
  record.t.resize(num_samples);
  record.u.resize(num_samples);
  record.y.resize(num_samples);
  record.natural_output.resize(num_samples);
  std::mt19937_64 noise(setup.noise_seed);
  const auto& switches = setup.disturbance.start_times;
  size_t next_switch = 0;
  // Advances x from `from` to `to` (to − from <= h), splitting the step at every switch of the
  // disturbance inside it, so that f is exact.
  auto advance = [&](Eigen::VectorXd& x, double from, double to, const Step& whole) {
    while (next_switch < switches.size() && switches[next_switch] <= from) ++next_switch;
    if (next_switch >= switches.size() || switches[next_switch] >= to) {
      x = whole.phi * x + whole.gamma * setup.disturbance.ValueAt(from);
      return;
    }
    double now = from;
    while (now < to) {
      const double end = (next_switch < switches.size() && switches[next_switch] < to)
                             ? switches[next_switch]
                             : to;
      if (end > now) {
        const Step part = Discretize(a, end - now);
        x = part.phi * x + part.gamma * setup.disturbance.ValueAt(now);
      }
      now = end;
      if (next_switch < switches.size() && switches[next_switch] <= now) ++next_switch;
    }
  };
  Eigen::VectorXd x = a.x0;
  if (!switches.empty() && switches.front() < 0.0) {
    // The disturbance acts before t0 on the plant at rest with u = 0: the oscillators are held
    // at zero (so ũ = 0) and started at t0.
    x.setZero();
    const int64_t steps = static_cast<int64_t>(std::ceil(-switches.front() / sample_time));
    double now = -static_cast<double>(steps) * sample_time;
    for (int64_t k = 0; k < steps; ++k) {
      const double to = -static_cast<double>(steps - k - 1) * sample_time;
      advance(x, now, to, full);
      now = to;
    }
    const int plant_and_channel = static_cast<int>(a.x0.size()) - 2 * static_cast<int>(setup.lines.size());
    x.tail(x.size() - plant_and_channel) = a.x0.tail(x.size() - plant_and_channel);
  }
  for (int64_t k = 0; k < num_samples; ++k) {
    const double t = static_cast<double>(k) * sample_time;
    const double eta =
        setup.noise_bound > 0.0 ? setup.noise_bound * (2.0 * UnitUniform(noise) - 1.0) : 0.0;
    record.t[k] = t;
    record.u[k] = (a.U * x)(0);
    record.y[k] = (a.H_total * x)(0) + eta;
    record.natural_output[k] = (a.H_natural * x)(0) + eta;
    if (k + 1 == num_samples) break;
    advance(x, t, static_cast<double>(k + 1) * sample_time, full);
  }
  return record;
}

}  // namespace idrig
