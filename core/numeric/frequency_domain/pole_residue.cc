#include "core/numeric/frequency_domain/pole_residue.h"

#include <unsupported/Eigen/LevenbergMarquardt>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/numeric/model/lti_model.h"

namespace idrig {

namespace {
using Complex = std::complex<double>;
const Complex kI(0.0, 1.0);

// Residuals (26) and Jacobian (28)/(33)–(34) in the scaled variable p̃ = p/ω_s.
// x = [Re s̃ (ns), Im s̃ (ns), Re ã (ns), Im ã (ns), Re h_o, Im h_o].
struct Functor : Eigen::DenseFunctor<double> {
  Functor(const Eigen::VectorXcd& p, const Eigen::VectorXcd& g, const Eigen::VectorXd& w, int ns,
          bool conj, bool origin)
      : Eigen::DenseFunctor<double>(4 * ns + 2, 2 * static_cast<int>(p.size())),
        p(p), g(g), w(w), ns(ns), conj(conj), origin(origin) {}
  const Eigen::VectorXcd &p, &g;
  const Eigen::VectorXd& w;
  int ns;
  bool conj, origin;

  Complex S(const Eigen::VectorXd& x, int v) const { return {x(v), x(ns + v)}; }
  Complex A(const Eigen::VectorXd& x, int v) const { return {x(2 * ns + v), x(3 * ns + v)}; }
  Complex Model(const Eigen::VectorXd& x, int k) const {
    Complex v = origin ? Complex(x(4 * ns), x(4 * ns + 1)) : Complex(0.0);
    for (int n = 0; n < ns; ++n) {
      const Complex s = S(x, n), a = A(x, n);
      v += a / (p(k) - s);  // Eq. (35): A1 a
      if (conj) v += std::conj(a) / (p(k) - std::conj(s));
    }
    return v;
  }
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& f) const {
    const int lines = static_cast<int>(p.size());
    for (int k = 0; k < lines; ++k) {
      const Complex r = w(k) * (Model(x, k) - g(k));  // Eq. (26) of [Balda]
      f(k) = r.real();
      f(lines + k) = r.imag();
    }
    return 0;
  }
  int df(const Eigen::VectorXd& x, Eigen::MatrixXd& j) const {
    const int lines = static_cast<int>(p.size());
    j.setZero();
    for (int k = 0; k < lines; ++k) {
      auto put = [&](int col, Complex d) {
        d *= w(k);
        j(k, col) = d.real();
        j(lines + k, col) = d.imag();
      };
      for (int n = 0; n < ns; ++n) {
        const Complex s = S(x, n), a = A(x, n);
        const Complex a1 = 1.0 / (p(k) - s);  // Eq. (33): A1
        const Complex a2 = a1 * a1;           // Eq. (34): A2 = A1∘A1, J = [A2 diag(a), A1]
        Complex d_re_s = a * a2, d_im_s = kI * a * a2, d_re_a = a1, d_im_a = kI * a1;
        if (conj) {
          const Complex b1 = 1.0 / (p(k) - std::conj(s)), b2 = b1 * b1;
          d_re_s += std::conj(a) * b2;
          d_im_s += -kI * std::conj(a) * b2;
          d_re_a += b1;
          d_im_a += -kI * b1;
        }
        put(n, d_re_s);
        put(ns + n, d_im_s);
        put(2 * ns + n, d_re_a);
        put(3 * ns + n, d_im_a);
      }
      if (origin) {
        put(4 * ns, 1.0);
        put(4 * ns + 1, kI);
      }
    }
    return 0;
  }
};

// Eqs. (29)–(31): five lines j … j+4 around the peak; returns ŝ (scaled).
Complex FivePointEstimate(const Eigen::VectorXcd& p, const Eigen::VectorXcd& g, int j, Complex s0) {
  Complex s = s0;
  for (int pass = 0; pass < 2; ++pass) {  // s ≈ p_m first, then refined once with ŝ
    Eigen::MatrixXcd A(5, 3);
    Eigen::VectorXcd y(5);
    for (int r = 0; r < 5; ++r) {
      A(r, 0) = 1.0;
      A(r, 1) = 1.0 / g(j + r);
      A(r, 2) = (p(j + r) - s) / g(j + r);
      y(r) = p(j + r);
    }
    const Eigen::VectorXcd c = A.colPivHouseholderQr().solve(y);  // (31): pseudoinverse
    if (!c.allFinite()) break;
    s = c(0);
  }
  return s;
}

Mode MakeMode(Complex s, Complex a, double ws, bool fictitious) {
  Mode m;
  m.eigenvalue = s * ws;
  m.residue = a * ws;
  m.natural_frequency = std::abs(m.eigenvalue);
  m.damping_ratio = m.natural_frequency > 0.0 ? -m.eigenvalue.real() / m.natural_frequency : 0.0;
  m.q = m.eigenvalue.real() != 0.0 ? m.natural_frequency / (-2.0 * m.eigenvalue.real()) : INFINITY;
  m.fictitious = fictitious;
  return m;
}
bool Converged(Eigen::LevenbergMarquardtSpace::Status status) {
  using namespace Eigen::LevenbergMarquardtSpace;
  return status == RelativeReductionTooSmall || status == RelativeErrorTooSmall ||
         status == RelativeErrorAndReductionTooSmall || status == CosinusTooSmall || status == FtolTooSmall ||
         status == XtolTooSmall || status == GtolTooSmall;
}

// Residues and h_o by linear least squares given the poles s, Eq. (35) (real unknowns);
// returns the LM vector x (layout of Functor).
Eigen::VectorXd LinearResidues(const Eigen::VectorXcd& p, const Eigen::VectorXcd& g, const Eigen::VectorXd& w,
                               const Eigen::VectorXcd& s, const PoleResidueOptions& options) {
  const int lines = static_cast<int>(p.size()), ns = static_cast<int>(s.size());
  const int lin = 2 * ns + (options.origin_correction ? 2 : 0);
  Eigen::MatrixXd L(2 * lines, lin);
  Eigen::VectorXd y(2 * lines);
  for (int k = 0; k < lines; ++k) {
    auto put = [&](int col, Complex d) {
      L(k, col) = w(k) * d.real();
      L(lines + k, col) = w(k) * d.imag();
    };
    for (int n = 0; n < ns; ++n) {
      Complex re = 1.0 / (p(k) - s(n)), im = kI / (p(k) - s(n));
      if (options.conjugate_pairs) {
        re += 1.0 / (p(k) - std::conj(s(n)));
        im += -kI / (p(k) - std::conj(s(n)));
      }
      put(n, re);
      put(ns + n, im);
    }
    if (options.origin_correction) {
      put(2 * ns, 1.0);
      put(2 * ns + 1, kI);
    }
    y(k) = w(k) * g(k).real();
    y(lines + k) = w(k) * g(k).imag();
  }
  const Eigen::VectorXd c = L.colPivHouseholderQr().solve(y);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(4 * ns + 2);
  for (int n = 0; n < ns; ++n) {
    x(n) = s(n).real();
    x(ns + n) = s(n).imag();
    x(2 * ns + n) = c(n);
    x(3 * ns + n) = c(ns + n);
  }
  if (options.origin_correction) x.tail(2) = c.tail(2);
  return x;
}

struct Refinement {
  Eigen::VectorXd x;
  double cost = 0.0;  // Σ w²|model − g|²
  Eigen::LevenbergMarquardtSpace::Status status = Eigen::LevenbergMarquardtSpace::Running;
  int iterations = 0, function_evaluations = 0;
};

// Levenberg–Marquardt (MINPACK lmder) on (26) with the Jacobian (28) from x.
Refinement Refine(const Eigen::VectorXcd& p, const Eigen::VectorXcd& g, const Eigen::VectorXd& w,
                  const Eigen::VectorXd& x0, const PoleResidueOptions& options) {
  const int ns = static_cast<int>(x0.size() - 2) / 4;
  Functor functor(p, g, w, ns, options.conjugate_pairs, options.origin_correction);
  Eigen::LevenbergMarquardt<Functor> lm(functor);
  lm.setMaxfev(options.max_function_evaluations);
  lm.setFtol(options.tolerance);
  lm.setXtol(options.tolerance);
  Refinement out;
  out.x = x0;
  // s ← −|Re s| + i Im s as in `ideSISO`; a pole that crossed into the right half-plane is
  // reflected and LM run once more from there, so the cost is that of the stable model.
  for (int pass = 0; pass < 2; ++pass) {
    out.status = lm.minimize(out.x);
    out.iterations += static_cast<int>(lm.iterations());
    out.function_evaluations += static_cast<int>(lm.nfev());
    if (!out.x.allFinite() || (out.x.head(ns).array() <= 0.0).all()) break;
    out.x.head(ns) = -out.x.head(ns).cwiseAbs();
  }
  out.x.head(ns) = -out.x.head(ns).cwiseAbs();
  Eigen::VectorXd r(functor.values());
  functor(out.x, r);
  out.cost = r.squaredNorm();
  return out;
}

// Cov(x) = σ̂²·(JᵀJ)⁺, σ̂² = |r|²/(2L − P), from the weighted residuals r and their
// Jacobian (28) at the optimum; modes[n] belongs to pole n (before sorting). The (Re s, Im s)
// block gives ω_n = |s| and ζ = −Re s/|s| to first order.
void AttachStandardErrors(const Functor& functor, const Eigen::VectorXd& x, double ws, bool origin,
                          std::vector<Mode>* modes) {
  const int ns = functor.ns, params = 4 * ns + (origin ? 2 : 0);
  const int equations = functor.values();
  if (equations <= params) return;
  Eigen::VectorXd r(equations);
  Eigen::MatrixXd jac(equations, x.size());
  functor(x, r);
  functor.df(x, jac);
  const double variance = r.squaredNorm() / (equations - params);
  const Eigen::MatrixXd used = jac.leftCols(params);
  const Eigen::MatrixXd cov =
      variance * Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(used.transpose() * used).pseudoInverse();
  for (int n = 0; n < ns; ++n) {
    Mode& m = (*modes)[n];
    Eigen::Matrix2d c;
    c << cov(n, n), cov(n, ns + n), cov(ns + n, n), cov(ns + n, ns + n);
    c *= ws * ws;
    m.std_real = std::sqrt(std::max(c(0, 0), 0.0));
    m.std_imag = std::sqrt(std::max(c(1, 1), 0.0));
    const double sr = m.eigenvalue.real(), si = m.eigenvalue.imag(), mag = std::abs(m.eigenvalue);
    if (mag <= 0.0) continue;
    const Eigen::Vector2d d_wn(sr / mag, si / mag);
    const Eigen::Vector2d d_zeta(-si * si / (mag * mag * mag), sr * si / (mag * mag * mag));
    m.std_natural_frequency = std::sqrt(std::max(d_wn.dot(c * d_wn), 0.0));
    m.std_damping_ratio = std::sqrt(std::max(d_zeta.dot(c * d_zeta), 0.0));
  }
}
}  // namespace

std::vector<int> FindPeaks(const Eigen::VectorXd& magnitude, double tolerance) {
  const int n = static_cast<int>(magnitude.size());
  std::vector<int> peaks;
  if (n < 3) return peaks;
  Eigen::VectorXd g = magnitude;
  for (int k = 1; k < n - 1; ++k)  // `peaks`: G(2:N-1) = (aG(1:N-2) + 3aG(2:N-1) + aG(3:N))/5
    g(k) = (magnitude(k - 1) + 3.0 * magnitude(k) + magnitude(k + 1)) / 5.0;
  std::vector<int> maxima, minima;
  if (g(1) > g(0)) minima.push_back(0);
  for (int k = 1; k < n - 1; ++k) {
    if (g(k) > g(k - 1) && g(k) > g(k + 1)) maxima.push_back(k);
    if (g(k) < g(k - 1) && g(k) < g(k + 1)) minima.push_back(k);
  }
  if (g(n - 2) > g(n - 1)) minima.push_back(n - 1);
  for (int i : maxima) {
    // Relative drop of the smoothed |g| on both sides: down to the lowest point before the
    // curve rises above g(i) again (or the band ends), i.e. the topographic prominence.
    // The listing compares with the adjacent minima and takes the larger drop, which with
    // noisy data lets wiggles pass and splits real peaks; this keeps its intent.
    double left = g(i), right = g(i);
    for (int j = i - 1; j >= 0 && g(j) <= g(i); --j) left = std::min(left, g(j));
    for (int j = i + 1; j < n && g(j) <= g(i); ++j) right = std::min(right, g(j));
    const double drop = (g(i) - std::max(left, right)) / g(i);
    if (drop > tolerance) peaks.push_back(i);
  }
  return peaks;
}

PoleResidueResult FitPoleResidue(const Frf& frf, const PoleResidueOptions& options) {
  ValidateFrf(frf);
  if (frf.NumOutputs() != 1 || frf.NumInputs() != 1)
    throw std::invalid_argument("pole-residue: a SISO FRF is expected (pick one output/input element)");
  const int lines = frf.NumLines();
  if (lines < 5) throw std::invalid_argument("pole-residue: at least 5 lines are needed, got " + std::to_string(lines));
  Eigen::VectorXd w = Eigen::VectorXd::Ones(lines);
  if (options.weights.size()) {
    if (options.weights.size() != lines)
      throw std::invalid_argument("pole-residue: " + std::to_string(options.weights.size()) +
                                  " weights for " + std::to_string(lines) + " lines");
    if (!(options.weights.array() > 0.0).all() || !options.weights.allFinite())
      throw std::invalid_argument("pole-residue: weights must be > 0 and finite");
    w = options.weights;
  }
  const double ws = frf.omega.maxCoeff();
  Eigen::VectorXcd p(lines), g(lines);
  for (int k = 0; k < lines; ++k) {
    p(k) = Complex(0.0, frf.omega(k) / ws);
    g(k) = frf.h[k](0, 0);
  }
  PoleResidueResult result;
  if (options.peak_omegas.empty()) {
    result.peak_lines = FindPeaks(g.cwiseAbs(), options.peak_tolerance);
  } else {
    for (double om : options.peak_omegas) {
      if (!(om >= frf.omega(0) && om <= frf.omega(lines - 1)))
        throw std::invalid_argument("pole-residue: peak frequency " + std::to_string(om) +
                                    " rad/s lies outside the band [" + std::to_string(frf.omega(0)) +
                                    ", " + std::to_string(frf.omega(lines - 1)) + "] rad/s");
      int best = 0;  // nearest line, as in `ideSISO`
      for (int k = 1; k < lines; ++k)
        if (std::abs(frf.omega(k) - om) < std::abs(frf.omega(best) - om)) best = k;
      result.peak_lines.push_back(best);
    }
  }
  // Positions of peaks & borders: I = [1 I N].
  std::vector<int> positions;
  std::vector<bool> fictitious;
  if (options.fictitious_poles) { positions.push_back(0); fictitious.push_back(true); }
  for (int i : result.peak_lines) { positions.push_back(i); fictitious.push_back(false); }
  if (options.fictitious_poles) { positions.push_back(lines - 1); fictitious.push_back(true); }
  const int ns = static_cast<int>(positions.size());
  if (ns == 0) throw std::invalid_argument("pole-residue: no peak found and fictitious poles are off: nothing to fit");
  const int unknowns = 4 * ns + (options.origin_correction ? 2 : 0);
  if (2 * lines < unknowns)
    throw std::invalid_argument("pole-residue: " + std::to_string(lines) + " lines give " +
                                std::to_string(2 * lines) + " real equations for " + std::to_string(unknowns) +
                                " unknowns (" + std::to_string(ns) + " poles); use more lines or fewer peaks");

  // Initial eigenvalues (29)–(31).
  Eigen::VectorXcd s(ns);
  for (int n = 0; n < ns; ++n) {
    const int j = std::min(std::max(positions[n] - 2, 0), lines - 5);
    Complex est = FivePointEstimate(p, g, j, p(j + 2));
    if (!std::isfinite(est.real()) || !std::isfinite(est.imag())) est = p(positions[n]) * Complex(1.0, 0.0) - 0.05;
    s(n) = Complex(-std::abs(est.real()), est.imag());  // x = −|Re x| + i Im x
    if (fictitious[n]) {
      // Keep the correction poles near their band end: an estimate that wandered into the
      // band (or beyond twice the band) is replaced by a heavily damped pole at the end.
      const double end = p(positions[n]).imag();
      const double band = p(lines - 1).imag() - p(0).imag();
      if (std::abs(s(n).imag() - end) > 0.5 * band || s(n).real() > -0.02 * band)
        s(n) = Complex(-0.2 * band, end);
    }
  }
  const Eigen::VectorXd x0 = LinearResidues(p, g, w, s, options);
  for (int n = 0; n < ns; ++n)
    result.initial_modes.push_back(MakeMode(s(n), Complex(x0(2 * ns + n), x0(3 * ns + n)), ws, fictitious[n]));
  Refinement run = Refine(p, g, w, x0, options);
  result.iterations = run.iterations;
  result.function_evaluations = run.function_evaluations;

  // Poles the peaks missed: a resonance left in the residual (a peak at the band's edge, a
  // close pair whose sum shows one hump). At the residual's largest local maxima (3-line
  // smoothing as in `peaks`, at least 5 lines apart, largest first) a pole is started from the
  // 5-point estimate (29)–(31) on the residual — and, when that run does not converge, also
  // from a pole two line spacings wide at the line — and all poles are refitted. The first
  // candidate whose pole lies in the band, is wider than one line spacing (narrower ones fit
  // single noisy lines) and lowers the BIC N·ln(cost/N) + P·ln N (N real equations, P real
  // unknowns) is kept; the BIC assumes the weights whiten the noise (w_k = 1/σ_k).
  std::vector<bool> from_residual(ns, false);
  double signal = 0.0;
  for (int k = 0; k < lines; ++k) signal += w(k) * w(k) * std::norm(g(k));
  const int equations = 2 * lines;
  const double spacing = p(1).imag() - p(0).imag(), band = p(lines - 1).imag() - p(0).imag();
  auto bic = [&](double cost, int poles) {
    const int unknowns = 4 * poles + (options.origin_correction ? 2 : 0);
    return equations * std::log(std::max(cost, 1e-300) / equations) + unknowns * std::log(double(equations));
  };
  for (int added = 0; added < options.max_residual_poles && lines >= 7 && Converged(run.status); ++added) {
    if (!(run.cost > 1e-12 * signal)) break;  // already exact to 1e-6 relative
    const Eigen::VectorXd& x = run.x;
    const int poles = static_cast<int>(x.size() - 2) / 4;
    if (equations < 4 * (poles + 1) + (options.origin_correction ? 2 : 0)) break;
    const Functor f(p, g, w, poles, options.conjugate_pairs, options.origin_correction);
    Eigen::VectorXcd residual(lines);
    Eigen::VectorXd power(lines);
    for (int k = 0; k < lines; ++k) residual(k) = g(k) - f.Model(x, k);
    for (int k = 0; k < lines; ++k) power(k) = w(k) * w(k) * std::norm(residual(k));
    std::vector<std::pair<double, int>> maxima;
    for (int k = 2; k < lines - 2; ++k) {
      auto smooth = [&](int i) { return power(i - 1) + 3.0 * power(i) + power(i + 1); };
      if (smooth(k) >= smooth(k - 1) && smooth(k) >= smooth(k + 1)) maxima.push_back({smooth(k), k});
    }
    std::sort(maxima.rbegin(), maxima.rend());
    std::vector<int> candidates;
    for (const auto& m : maxima) {
      bool apart = true;
      for (int c : candidates) apart &= std::abs(c - m.second) >= 5;
      if (apart) candidates.push_back(m.second);
      if (candidates.size() == 2) break;
    }
    bool accepted = false;
    for (int top : candidates) {
      Complex est = FivePointEstimate(p, residual, top - 2, p(top));
      if (!std::isfinite(est.real()) || !std::isfinite(est.imag()) || std::abs(est.imag() - p(top).imag()) > 0.1 * band)
        est = Complex(-2.0 * spacing, p(top).imag());
      // The 5-point start; when its run does not converge, also the fixed one, and the lower
      // cost of the two.
      Refinement best;
      best.cost = INFINITY;
      for (const Complex start : {Complex(-std::max(std::abs(est.real()), spacing), est.imag()),
                                  Complex(-2.0 * spacing, p(top).imag())}) {
        Eigen::VectorXcd s_try(poles + 1);
        for (int n = 0; n < poles; ++n) s_try(n) = Complex(x(n), x(poles + n));
        s_try(poles) = start;
        Refinement trial = Refine(p, g, w, LinearResidues(p, g, w, s_try, options), options);
        result.iterations += trial.iterations;
        result.function_evaluations += trial.function_evaluations;
        if (trial.x.allFinite() && trial.cost < best.cost) best = trial;
        if (Converged(trial.status) && trial.x.allFinite()) break;
      }
      if (!std::isfinite(best.cost)) continue;
      const double width = std::abs(best.x(poles)), at = best.x(2 * (poles + 1) - 1);
      accepted = width >= spacing && at >= p(0).imag() && at <= p(lines - 1).imag() &&
                 bic(best.cost, poles + 1) < bic(run.cost, poles);
      if (accepted) {
        run = best;  // x refers to run.x: nothing below in this step reads it
        break;
      }
    }
    if (!accepted) break;
    fictitious.push_back(false);
    from_residual.push_back(true);
    ++result.residual_poles;
  }
  Eigen::VectorXd x = run.x;
  const int poles = static_cast<int>(x.size() - 2) / 4;
  const auto status = run.status;
  result.lm_status = static_cast<int>(status);
  Functor functor(p, g, w, poles, options.conjugate_pairs, options.origin_correction);

  for (int n = 0; n < poles; ++n) {  // Re s <= 0 already (Refine)
    result.modes.push_back(MakeMode(Complex(x(n), x(poles + n)), Complex(x(2 * poles + n), x(3 * poles + n)), ws,
                                    fictitious[n]));
    result.modes.back().from_residual = from_residual[n];
  }
  AttachStandardErrors(functor, x, ws, options.origin_correction, &result.modes);
  std::sort(result.modes.begin(), result.modes.end(),
            [](const Mode& a, const Mode& b) { return a.eigenvalue.imag() < b.eigenvalue.imag(); });
  result.origin_correction = options.origin_correction ? Complex(x(4 * poles), x(4 * poles + 1)) : Complex(0.0);
  result.fitted.resize(lines);
  for (int k = 0; k < lines; ++k) result.fitted(k) = functor.Model(x, k);
  double gn = 0.0, rn = 0.0;
  for (int k = 0; k < lines; ++k) {
    rn += std::norm(result.fitted(k) - g(k));
    gn += std::norm(g(k));
  }
  result.final_cost = run.cost;  // Σ w²|model − g|² at this x (Refine)
  result.fit_percent = gn > 0.0 ? 100.0 * (1.0 - std::sqrt(rn / gn)) : 0.0;
  using namespace Eigen::LevenbergMarquardtSpace;
  if (!x.allFinite()) {
    result.status = SolverStatus::kFailed;
    result.message = "Levenberg-Marquardt diverged (non-finite parameters)";
  } else if (status == TooManyFunctionEvaluation) {
    result.status = SolverStatus::kNotConverged;
    result.message = "Levenberg-Marquardt stopped at the function-evaluation limit (" +
                     std::to_string(options.max_function_evaluations) + ")";
  } else if (status == ImproperInputParameters) {
    result.status = SolverStatus::kFailed;
    result.message = "Levenberg-Marquardt rejected its input";
  } else {
    result.status = SolverStatus::kOk;
    result.message = std::to_string(poles) + " poles (" + std::to_string(result.peak_lines.size()) + " peaks" +
                     (options.fictitious_poles ? " + 2 fictitious" : "") +
                     (result.residual_poles ? " + " + std::to_string(result.residual_poles) + " from the residual" : "") + ")";
  }
  return result;
}

TransferFunction PoleResidueTransferFunction(const PoleResidueResult& result) {
  auto add = [](Eigen::VectorXd a, Eigen::VectorXd b) {  // descending, aligned at the end
    if (a.size() < b.size()) std::swap(a, b);
    a.tail(b.size()) += b;
    return a;
  };
  TransferFunction tf;
  tf.den = Eigen::VectorXd::Ones(1);
  tf.num = Eigen::VectorXd::Zero(1);
  for (const Mode& m : result.modes) {
    const Complex s = m.eigenvalue, a = m.residue;
    // a/(p−s) + ā/(p−s̄) = (2 Re a · p − 2 Re(a s̄)) / (p² − 2 Re s · p + |s|²)
    const Eigen::Vector2d num(2.0 * a.real(), -2.0 * std::real(a * std::conj(s)));
    const Eigen::Vector3d den(1.0, -2.0 * s.real(), std::norm(s));
    tf.num = add(PolynomialProduct(tf.num, den), PolynomialProduct(num, tf.den));
    tf.den = PolynomialProduct(tf.den, den);
  }
  tf.num = add(tf.num, result.origin_correction.real() * tf.den);
  return tf;
}

}  // namespace idrig
