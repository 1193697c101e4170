#include "core/numeric/time_domain/pem.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/numeric/model/lti_model.h"
#include "core/numeric/time_domain/pem_internal.h"
#include "core/numeric/validation.h"

namespace idrig {

using namespace pem_internal;  // NOLINT: the internals of this file

namespace {

[[noreturn]] void Fail(const std::string& what) { throw std::invalid_argument("pem: " + what); }

const Eigen::VectorXd& One() {
  static const Eigen::VectorXd one = Eigen::VectorXd::Ones(1);
  return one;
}

struct Evaluation {
  Eigen::VectorXd eps;
  Eigen::MatrixXd jacobian;  // ∂ε/∂θ
  double cost = 0.0;         // Σ ε²
};

// ε(t, θ) and its exact Jacobian by filtered regressors ([Ljung] Eqs. (10.52)–(10.55)).
Evaluation Evaluate(const Layout& layout, const Eigen::VectorXd& theta, const Eigen::VectorXd& y,
                    const Eigen::MatrixXd& ushift, bool jacobian) {
  const Polys p = Unpack(layout, theta);
  const long n = y.size();
  Eigen::VectorXd v = layout.na > 0 ? FilterPolynomial(p.a, One(), y) : y;
  std::vector<Eigen::VectorXd> w(layout.nu);
  for (int j = 0; j < layout.nu; ++j) {
    w[j] = FilterPolynomial(p.b[j], p.f[j], ushift.col(j));
    v -= w[j];
  }
  Evaluation out;
  out.eps = (layout.nc + layout.nd > 0) ? FilterPolynomial(p.d, p.c, v) : v;
  out.cost = out.eps.squaredNorm();
  if (!jacobian) return out;
  out.jacobian.resize(n, layout.Size());
  auto& jac = out.jacobian;
  if (layout.na > 0) {
    const Eigen::VectorXd yt = FilterPolynomial(p.d, p.c, y);
    for (int k = 1; k <= layout.na; ++k) jac.col(k - 1) = Shifted(yt, k);
  }
  for (int j = 0; j < layout.nu; ++j) {
    const Eigen::VectorXd cf = PolynomialProduct(p.c, p.f[j]);
    const Eigen::VectorXd ut = FilterPolynomial(p.d, cf, ushift.col(j));
    for (int k = 0; k < layout.nb; ++k) jac.col(layout.B(j) + k) = -Shifted(ut, k);
    if (layout.nf > 0) {
      const Eigen::VectorXd wt = FilterPolynomial(p.d, cf, w[j]);
      for (int k = 1; k <= layout.nf; ++k) jac.col(layout.F(j) + k - 1) = Shifted(wt, k);
    }
  }
  if (layout.nc > 0) {
    const Eigen::VectorXd et = FilterPolynomial(One(), p.c, out.eps);
    for (int k = 1; k <= layout.nc; ++k) jac.col(layout.C() + k - 1) = -Shifted(et, k);
  }
  if (layout.nd > 0) {
    const Eigen::VectorXd vt = FilterPolynomial(One(), p.c, v);
    for (int k = 1; k <= layout.nd; ++k) jac.col(layout.D() + k - 1) = Shifted(vt, k);
  }
  return out;
}

// The predictor is stable when C, D and every F_j are ([Ljung] §4.2); the simulated model
// also needs A.
bool PredictorStable(const Polys& p) {
  if (!IsStablePolynomial(p.c) || !IsStablePolynomial(p.d)) return false;
  for (const auto& f : p.f)
    if (!IsStablePolynomial(f)) return false;
  return true;
}

struct Refinement {
  Eigen::VectorXd theta;
  double initial_cost = 0.0, cost = 0.0;
  int iterations = 0;
  bool converged = false;
  Eigen::MatrixXd jtj;
};

// Levenberg–Marquardt on Σ ε² with Marquardt's diagonal scaling; a trial that makes the
// predictor unstable is rejected like one that raises the cost.
Refinement Refine(const Layout& layout, Eigen::VectorXd theta, const Eigen::VectorXd& y,
                  const Eigen::MatrixXd& ushift, const PemOptions& options) {
  Refinement out;
  Evaluation now = Evaluate(layout, theta, y, ushift, true);
  out.initial_cost = now.cost;
  double mu = 1e-4;
  const int p = layout.Size();
  for (int it = 0; it < options.max_iterations; ++it) {
    out.iterations = it + 1;
    const Eigen::MatrixXd h = now.jacobian.transpose() * now.jacobian;
    const Eigen::VectorXd g = now.jacobian.transpose() * now.eps;
    Eigen::VectorXd diag = h.diagonal().cwiseMax(1e-12 * std::max(1e-300, h.diagonal().maxCoeff()));
    bool accepted = false;
    while (mu < 1e12) {
      Eigen::MatrixXd lhs = h;
      lhs.diagonal() += mu * diag;
      const Eigen::VectorXd step = -lhs.ldlt().solve(g);
      const Eigen::VectorXd trial = theta + step;
      if (step.allFinite() && PredictorStable(Unpack(layout, trial))) {
        Evaluation next = Evaluate(layout, trial, y, ushift, false);
        if (std::isfinite(next.cost) && next.cost < now.cost) {
          const double decrease = (now.cost - next.cost) / std::max(now.cost, 1e-300);
          const double step_size = step.norm() / (theta.norm() + 1e-8);
          theta = trial;
          now = Evaluate(layout, theta, y, ushift, true);
          mu = std::max(mu / 10.0, 1e-12);
          accepted = true;
          if (decrease < options.tolerance || step_size < options.tolerance) out.converged = true;
          break;
        }
      }
      mu *= 10.0;
    }
    if (!accepted) {
      // No descent at any damping: at a (local) minimum when the gradient is negligible.
      const double predicted = g.dot(h.ldlt().solve(g));
      out.converged = !(predicted > 1e3 * options.tolerance * now.cost) || p == 0;
      break;
    }
    if (out.converged) break;
  }
  out.theta = theta;
  out.cost = now.cost;
  out.jtj = now.jacobian.transpose() * now.jacobian;
  return out;
}

// G_j(z) = z^{−nk} B_j / (A F_j) as a discrete transfer function in descending powers of z,
// one sample of delay kept in the polynomials and the rest in delay_s.
TransferFunction InputTf(const Polys& p, int j, int nk, double ts) {
  const Eigen::VectorXd den_q = PolynomialProduct(p.a, p.f[j]);
  const int s = std::min(nk, 1);
  const int nb = static_cast<int>(p.b[j].size());
  const int degree = std::max<int>(static_cast<int>(den_q.size()) - 1, s + nb - 1);
  TransferFunction tf;
  tf.num = Eigen::VectorXd::Zero(degree + 1);
  tf.den = Eigen::VectorXd::Zero(degree + 1);
  tf.num.segment(s, nb) = p.b[j];
  tf.den.head(den_q.size()) = den_q;
  tf.sample_time = ts;
  tf.delay_s = (nk - s) * ts;
  // Leading zeros of num are harmless; a numerator of zeros only stays one zero.
  if (tf.num.cwiseAbs().maxCoeff() == 0.0) tf.num = Eigen::VectorXd::Zero(1);
  return Normalized(tf);
}

StateSpace Parallel(const std::vector<TransferFunction>& tfs) {
  std::vector<StateSpace> parts;
  int n = 0;
  for (const auto& tf : tfs) {
    parts.push_back(ToStateSpace(tf));
    n += parts.back().Order();
  }
  StateSpace ss;
  const int nu = static_cast<int>(tfs.size());
  ss.A = Eigen::MatrixXd::Zero(n, n);
  ss.B = Eigen::MatrixXd::Zero(n, nu);
  ss.C = Eigen::MatrixXd::Zero(1, n);
  ss.D = Eigen::MatrixXd::Zero(1, nu);
  int at = 0;
  for (int j = 0; j < nu; ++j) {
    const int k = parts[j].Order();
    ss.A.block(at, at, k, k) = parts[j].A;
    ss.B.block(at, j, k, 1) = parts[j].B;
    ss.C.block(0, at, 1, k) = parts[j].C;
    ss.D(0, j) = parts[j].D(0, 0);
    at += k;
  }
  ss.sample_time = tfs.front().sample_time;
  ss.delay_s = tfs.front().delay_s;
  return ss;
}

std::vector<std::string> ParameterNames(const Layout& layout) {
  std::vector<std::string> names;
  auto input = [&](int j) { return layout.nu > 1 ? std::to_string(j + 1) + "_" : std::string(); };
  for (int k = 1; k <= layout.na; ++k) names.push_back("a" + std::to_string(k));
  for (int j = 0; j < layout.nu; ++j)
    for (int k = 0; k < layout.nb; ++k) names.push_back("b" + input(j) + std::to_string(layout.nk + k));
  for (int k = 1; k <= layout.nc; ++k) names.push_back("c" + std::to_string(k));
  for (int k = 1; k <= layout.nd; ++k) names.push_back("d" + std::to_string(k));
  for (int j = 0; j < layout.nu; ++j)
    for (int k = 1; k <= layout.nf; ++k) names.push_back("f" + input(j) + std::to_string(k));
  return names;
}

Layout MakeLayout(const PemOptions& o, int n, int nu) {
  auto pick = [&](int v) { return v >= 0 ? v : n; };
  Layout l;
  l.nu = nu;
  l.nk = o.input_delay;
  l.nb = o.nb >= 0 ? o.nb : (o.input_delay == 0 ? n + 1 : n);
  switch (o.structure) {
    case PemStructure::kOutputError: l.nf = pick(o.nf); break;
    case PemStructure::kArmax: l.na = pick(o.na); l.nc = pick(o.nc); break;
    case PemStructure::kBoxJenkins: l.nf = pick(o.nf); l.nc = pick(o.nc); l.nd = pick(o.nd); break;
  }
  return l;
}

std::string Num(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

}  // namespace

namespace pem_internal {

Polys Unpack(const Layout& layout, const Eigen::VectorXd& theta) {
  Polys p;
  auto monic = [&](int at, int degree) {
    Eigen::VectorXd v(degree + 1);
    v(0) = 1.0;
    v.tail(degree) = theta.segment(at, degree);
    return v;
  };
  p.a = monic(0, layout.na);
  p.c = monic(layout.C(), layout.nc);
  p.d = monic(layout.D(), layout.nd);
  for (int j = 0; j < layout.nu; ++j) {
    p.b.push_back(theta.segment(layout.B(j), layout.nb));
    p.f.push_back(monic(layout.F(j), layout.nf));
  }
  return p;
}

Eigen::VectorXd Pack(const Layout& layout, const Polys& p) {
  Eigen::VectorXd theta(layout.Size());
  theta.head(layout.na) = p.a.tail(layout.na);
  theta.segment(layout.C(), layout.nc) = p.c.tail(layout.nc);
  theta.segment(layout.D(), layout.nd) = p.d.tail(layout.nd);
  for (int j = 0; j < layout.nu; ++j) {
    theta.segment(layout.B(j), layout.nb) = p.b[j];
    theta.segment(layout.F(j), layout.nf) = p.f[j].tail(layout.nf);
  }
  return theta;
}

}  // namespace pem_internal

const char* ToString(PemStructure structure) {
  switch (structure) {
    case PemStructure::kOutputError: return "oe";
    case PemStructure::kArmax: return "armax";
    case PemStructure::kBoxJenkins: return "bj";
  }
  return "?";
}

Eigen::VectorXd FilterPolynomial(const Eigen::VectorXd& num, const Eigen::VectorXd& den,
                                 const Eigen::VectorXd& x) {
  const long n = x.size();
  const int nn = static_cast<int>(num.size()), nd = static_cast<int>(den.size());
  Eigen::VectorXd y(n);
  const double* xp = x.data();
  const double* bp = num.data();
  const double* ap = den.data();
  double* yp = y.data();
  const long warm = std::min<long>(n, std::max(nn, nd));
  for (long t = 0; t < warm; ++t) {  // the first samples: fewer past values
    double acc = 0.0;
    for (int k = 0; k < nn && k <= t; ++k) acc += bp[k] * xp[t - k];
    for (int k = 1; k < nd && k <= t; ++k) acc -= ap[k] * yp[t - k];
    yp[t] = acc;
  }
  for (long t = warm; t < n; ++t) {
    double acc = 0.0;
    for (int k = 0; k < nn; ++k) acc += bp[k] * xp[t - k];
    for (int k = 1; k < nd; ++k) acc -= ap[k] * yp[t - k];
    yp[t] = acc;
  }
  return y;
}

Eigen::VectorXd SimulatePem(const PemResult& result, const Eigen::MatrixXd& u) {
  if (result.a.size() == 0 || static_cast<long>(result.b.size()) != u.cols() ||
      static_cast<long>(result.f.size()) != u.cols())
    Fail(std::string("cannot simulate a ") + ToString(result.structure) + " result without its polynomials for " +
         std::to_string(u.cols()) + " input(s)" + (result.ok() ? "" : " (the fit failed: " + result.message + ")"));
  Polys p;
  p.a = result.a;
  p.b = result.b;
  p.f = result.f;
  Eigen::VectorXd y = Eigen::VectorXd::Zero(u.rows());
  for (int j = 0; j < u.cols(); ++j)
    y += FilterPolynomial(p.b[j], PolynomialProduct(p.a, p.f[j]), Shifted(u.col(j), result.input_delay));
  return y;
}

PemResult IdentifyPem(const IoRecord& record, const PemOptions& options) {
  const int nu = record.NumInputs();
  const std::string name = ToString(options.structure);
  if (nu < 1) Fail(name + " needs at least one input column");
  if (record.NumOutputs() < 1) Fail(name + ": the record has no output column");
  if (options.output < 0 || options.output >= record.NumOutputs())
    Fail("output " + std::to_string(options.output + 1) + " does not exist (the record has " +
         std::to_string(record.NumOutputs()) + ")");
  ValidateIoRecord(record, 3);
  if (options.order < 0 || options.max_order < 1) Fail("order must be >= 1 (or 0: chosen on held-out data)");
  if (options.input_delay < 0) Fail("input_delay must be >= 0 samples");
  for (int v : {options.nb, options.nf, options.na, options.nc, options.nd})
    if (v < -1) Fail("polynomial orders must be >= 0");
  {
    // A constant input, or inputs that are a combination of each other, carry no information.
    const Eigen::MatrixXd centred = record.u.rowwise() - record.u.colwise().mean();
    for (int j = 0; j < nu; ++j)
      if (!(centred.col(j).cwiseAbs().maxCoeff() > 1e-12 * std::max(1.0, record.u.col(j).cwiseAbs().maxCoeff())))
        Fail("input " + std::to_string(j + 1) + " is constant: it is not persistently exciting");
    if (nu > 1) {
      Eigen::MatrixXd cov = centred.transpose() * centred;
      const Eigen::VectorXd s = cov.diagonal().cwiseSqrt().cwiseInverse();
      cov = s.asDiagonal() * cov * s.asDiagonal();
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov, Eigen::EigenvaluesOnly);
      if (eig.eigenvalues()(0) < 1e-10 * eig.eigenvalues()(nu - 1))
        Fail("the inputs are linearly dependent (e.g. two identical inputs): the input matrix is rank deficient");
    }
  }
  const Eigen::VectorXd y = record.y.col(options.output);
  PemResult result;
  int n = options.order;
  if (n == 0) {
    // Order on held-out data: estimate on the first two thirds, simulate the whole record and
    // score the last third; the smallest order within 2 % (NRMSE) of the best.
    const int split = 2 * record.NumSamples() / 3;
    const IoRecord head = Slice(record, 0, split);
    double best = std::numeric_limits<double>::infinity();
    std::vector<double> nrmse;
    for (int k = 1; k <= options.max_order; ++k) {
      PemOptions sub = options;
      sub.order = k;
      if (3 * MakeLayout(sub, k, nu).Size() > split) break;
      PemResult r = IdentifyPem(head, sub);
      double e = std::numeric_limits<double>::infinity();
      // A failed order (no start gave a stable model) has no polynomials to simulate.
      if (r.ok()) {
        const Eigen::VectorXd sim = SimulatePem(r, record.u);
        const long tail = record.NumSamples() - split;
        e = Nrmse(y.tail(tail), sim.tail(tail))(0);
        if (!std::isfinite(e)) e = std::numeric_limits<double>::infinity();
      }
      nrmse.push_back(e);
      best = std::min(best, e);
      result.order_table.push_back({k, 100.0 * (1.0 - e)});
    }
    for (size_t k = 0; k < nrmse.size(); ++k)
      if (nrmse[k] <= 1.02 * best + 1e-12) { n = static_cast<int>(k) + 1; break; }
    if (n == 0) Fail("no order in 1.." + std::to_string(options.max_order) + " gives a usable model on the record");
  }
  const Layout layout = MakeLayout(options, n, nu);
  const int p = layout.Size();
  if (record.NumSamples() < 3 * p)
    Fail("order " + std::to_string(n) + " has " + std::to_string(p) + " parameters and needs at least " +
         std::to_string(3 * p) + " samples; the record has " + std::to_string(record.NumSamples()));
  Eigen::MatrixXd ushift(record.NumSamples(), nu);
  for (int j = 0; j < nu; ++j) ushift.col(j) = Shifted(record.u.col(j), layout.nk);

  const std::vector<Start> starts = MakeStarts(layout, y, record.u, record.sample_time, options);
  Refinement best;
  best.cost = std::numeric_limits<double>::infinity();
  int chosen = -1;
  for (size_t s = 0; s < starts.size(); ++s) {
    PemStart info;
    info.name = starts[s].name;
    const Eigen::VectorXd theta0 = Pack(layout, starts[s].polys);
    if (!theta0.allFinite() || !PredictorStable(Unpack(layout, theta0))) {
      info.initial_cost = std::numeric_limits<double>::infinity();
      info.final_cost = info.initial_cost;
      result.starts.push_back(info);
      continue;
    }
    Refinement r = Refine(layout, theta0, y, ushift, options);
    const Polys polys = Unpack(layout, r.theta);
    info.initial_cost = r.initial_cost;
    info.final_cost = r.cost;
    info.iterations = r.iterations;
    info.stable = PredictorStable(polys) && IsStablePolynomial(polys.a);
    result.starts.push_back(info);
    if (info.stable && r.cost < best.cost) {
      best = r;
      chosen = static_cast<int>(s);
    }
  }
  result.structure = options.structure;
  result.order = n;
  result.input_delay = layout.nk;
  result.sample_time = record.sample_time;
  if (chosen < 0) {
    result.status = SolverStatus::kFailed;
    result.message = name + ": no start gave a stable model";
    return result;
  }
  result.starts[chosen].chosen = true;
  const Polys polys = Unpack(layout, best.theta);
  result.a = polys.a;
  result.b = polys.b;
  result.c = polys.c;
  result.d = polys.d;
  result.f = polys.f;
  result.theta = best.theta;
  result.parameter_names = ParameterNames(layout);
  result.iterations = best.iterations;
  result.final_cost = best.cost;
  const long samples = record.NumSamples();
  result.noise_variance = best.cost / std::max<long>(1, samples - p);
  // Cov θ̂ = σ² (JᵀJ)⁻¹ ([Ljung] Eq. (9.18)), by a pseudo-inverse if JᵀJ is singular.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(best.jtj);
  Eigen::VectorXd inv = eig.eigenvalues();
  for (int i = 0; i < p; ++i) inv(i) = inv(i) > 1e-14 * eig.eigenvalues().maxCoeff() ? 1.0 / inv(i) : 0.0;
  result.covariance = result.noise_variance * eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
  result.theta_std = result.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (int j = 0; j < nu; ++j) result.input_tfs.push_back(InputTf(polys, j, layout.nk, record.sample_time));
  result.model = Parallel(result.input_tfs);
  const Eigen::VectorXd sim = SimulatePem(result, record.u);
  result.fit_percent = FitPercent(y, sim)(0);
  std::ostringstream msg;
  msg << name << ", order " << n << ", " << p << " parameters, start '" << starts[chosen].name << "', "
      << best.iterations << " iterations, fit " << Num(result.fit_percent) << " %";
  result.status = best.converged ? SolverStatus::kOk : SolverStatus::kNotConverged;
  if (!best.converged) {
    msg << "; not converged in " << options.max_iterations << " iterations";
    result.warnings.push_back("Levenberg-Marquardt did not converge: raise max_iterations");
  }
  result.message = msg.str();
  return result;
}

}  // namespace idrig
