#include "core/numeric/model/model_checks.h"

#include <cmath>
#include <sstream>

namespace idrig {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string Pole(std::complex<double> p) {
  std::ostringstream s;
  s.precision(5);
  s << p.real() << (p.imag() < 0 ? " - " : " + ") << std::abs(p.imag()) << "j";
  return s.str();
}

}  // namespace

int Severity(SolverStatus status) {
  switch (status) {
    case SolverStatus::kOk: return 0;
    case SolverStatus::kIllConditioned: return 1;
    case SolverStatus::kPoorFit: return 2;
    case SolverStatus::kNyquistPole: return 3;
    case SolverStatus::kNotConverged: return 4;
    case SolverStatus::kUnstable: return 5;
    case SolverStatus::kFailed: return 6;
  }
  return 6;
}

SolverStatus WorseStatus(SolverStatus a, SolverStatus b) { return Severity(b) > Severity(a) ? b : a; }

std::vector<ModelIssue> CheckModel(const LtiModel& model, double fit_percent, const ModelCheckOptions& options) {
  std::vector<ModelIssue> issues;
  const bool discrete = std::visit([](const auto& m) { return m.IsDiscrete(); }, model);
  const double ts = discrete ? std::visit([](const auto& m) { return m.sample_time; }, model) : options.sample_time;
  const Eigen::VectorXcd poles = std::visit([](const auto& m) { return Poles(m); }, model);

  if (options.expect_stable) {
    std::vector<std::string> bad;
    for (int i = 0; i < poles.size(); ++i) {
      const std::complex<double> p = poles(i);
      if (p.imag() < 0) continue;  // each pair once
      if (discrete ? std::abs(p) >= 1.0 : p.real() >= 0.0) {
        std::ostringstream s;
        s.precision(6);
        s << Pole(p) << (discrete ? " (|z| = " : " (Re s = ") << (discrete ? std::abs(p) : p.real()) << ")";
        bad.push_back(s.str());
      }
    }
    if (!bad.empty()) {
      std::string list;
      for (const auto& b : bad) list += (list.empty() ? "" : ", ") + b;
      issues.push_back({SolverStatus::kUnstable,
                        std::string("unstable model: ") + (discrete ? "pole(s) on or outside the unit circle: "
                                                                    : "pole(s) in the closed right half-plane: ") +
                            list + "; its simulation diverges and its fit means nothing"});
    }
  }

  if (ts > 0.0) {
    const double nyquist = kPi / ts;
    for (int i = 0; i < poles.size(); ++i) {
      const std::complex<double> p = poles(i);
      if (p.imag() < 0) continue;
      const double angle = discrete ? std::abs(std::arg(p)) : std::abs(p.imag()) * ts;
      const double magnitude = discrete ? std::abs(p) : std::exp(p.real() * ts);
      if (angle >= options.nyquist_fraction * kPi && magnitude >= options.nyquist_min_magnitude) {
        std::ostringstream s;
        s.precision(4);
        s << "pole " << Pole(p) << " lies at " << 100.0 * angle / kPi
          << " % of the Nyquist frequency (" << nyquist << " rad/s, Ts = " << ts
          << " s): a mode at the sampling limit comes from noise, aliasing or the estimator, not the plant; "
             "try a lower order, a band limit, or weights from the FRF's variance";
        issues.push_back({SolverStatus::kNyquistPole, s.str()});
        break;
      }
    }
  }

  if (std::isfinite(options.min_fit_percent) && !std::isnan(fit_percent) && fit_percent < options.min_fit_percent) {
    std::ostringstream s;
    s.precision(4);
    s << "poor fit: " << fit_percent << " % < " << options.min_fit_percent
      << " % (100·(1 − NRMSE) on the estimation data): the model explains little of the output";
    issues.push_back({SolverStatus::kPoorFit, s.str()});
  }
  return issues;
}

}  // namespace idrig
