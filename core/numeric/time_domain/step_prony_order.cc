// Step-response identification with multiple complex poles, [Vidinčev] (seed 000).
#include "core/numeric/time_domain/step_prony.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include <unsupported/Eigen/LevenbergMarquardt>
#include <unsupported/Eigen/NumericalDiff>

#include "core/numeric/validation.h"

namespace idrig {

const char* ToString(StepAveraging averaging) {
  switch (averaging) {
    case StepAveraging::kNone: return "none";
    case StepAveraging::kBlock: return "block";
    case StepAveraging::kIntegral: return "integral";
  }
  return "?";
}

const char* ToString(StepLpSolver solver) {
  switch (solver) {
    case StepLpSolver::kQr: return "qr";
    case StepLpSolver::kTls: return "tls";
    case StepLpSolver::kSubspace: return "subspace";
  }
  return "?";
}

namespace {

using cd = std::complex<double>;

[[noreturn]] void Fail(const std::string& what) { throw std::invalid_argument("step-prony: " + what); }

std::string Num(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

// Σ_{k<r} (bt)^k / k!
cd TruncatedExp(cd bt, int r) {
  cd term = 1.0, sum = 0.0;
  for (int k = 0; k < r; ++k) {
    sum += term;
    term *= bt / static_cast<double>(k + 1);
  }
  return sum;
}

// ψ_r(b, t) = b^(−r) e^(−bt) Σ_{k<r} (bt)^k/k!: the part of x̄(t) (7) carried by A/(p+b)^r, with
// C_vj = A_vj / b^(N_v+1−j) (8).
cd TailBasis(cd b, int r, double t) { return std::exp(-b * t) * TruncatedExp(b * t, r) / std::pow(b, r); }

// φ_r(b, t) = L⁻¹{1/(p (p+b)^r)} = b^(−r) − ψ_r(b, t), the term of (5).
cd StepBasis(cd b, int r, double t) { return 1.0 / std::pow(b, r) - TailBasis(b, r, t); }

// How samples are turned into the LP sequence w_α: point values x̄(αh), block means (25) or
// interval integrals. `spacing` samples per h, `blocks` sub-intervals (spacing % blocks == 0).
struct Grid {
  int spacing = 1, blocks = 1;
  StepAveraging averaging = StepAveraging::kNone;
  double sample_time = 1.0;

  // Samples beyond the start sample that one value needs.
  int Extent() const {
    switch (averaging) {
      case StepAveraging::kNone: return 0;
      case StepAveraging::kBlock: return (blocks - 1) * (spacing / blocks);
      case StepAveraging::kIntegral: return spacing;
    }
    return 0;
  }
  int Points(int n) const { return (n - 1 - Extent()) / spacing + 1; }  // values at α = 0, h, 2h, …
  // The value starting at sample `base` (α h = base·Ts).
  template <typename Vec>
  typename Vec::Scalar ReduceAt(const Vec& v, int base) const {
    using S = typename Vec::Scalar;
    switch (averaging) {
      case StepAveraging::kNone: return v(base);
      case StepAveraging::kBlock: {  // Eq. (25): mean over γ = 0..B−1 of x̄(αh + γh/B)
        S sum = 0.0;
        const int step = spacing / blocks;
        for (int g = 0; g < blocks; ++g) sum += v(base + g * step);
        return sum / static_cast<double>(blocks);
      }
      case StepAveraging::kIntegral: {  // ∫_{αh}^{αh+h} x̄ dt, trapezoid rule on the samples
        S sum = 0.5 * (v(base) + v(base + spacing));
        for (int k = 1; k < spacing; ++k) sum += v(base + k);
        return sum * sample_time;
      }
    }
    return S(0.0);
  }
  template <typename Vec>
  typename Vec::Scalar Reduce(const Vec& v, int alpha) const { return ReduceAt(v, alpha * spacing); }
  // Samples needed for the first `points` values.
  int SamplesFor(int points) const {
    switch (averaging) {
      case StepAveraging::kNone: return (points - 1) * spacing + 1;
      case StepAveraging::kBlock: return (points - 1) * spacing + (blocks - 1) * (spacing / blocks) + 1;
      case StepAveraging::kIntegral: return points * spacing + 1;
    }
    return 0;
  }
};

// Rows [w(k), w(k + h), …, w(k + mh)] of the LP system (20)/(30), one per start sample k; `w`
// holds the (averaged) sequence starting at every sample, so that α in (36) runs over every
// shift kTs, not only multiples of h (the derivation (12)–(15) holds for any shift).
Eigen::MatrixXd LpRows(const Eigen::VectorXd& w, int m, int spacing, const std::vector<int>& starts) {
  Eigen::MatrixXd rows(starts.size(), m + 1);
  for (size_t i = 0; i < starts.size(); ++i)
    for (int s = 0; s <= m; ++s) rows(i, s) = w(starts[i] + s * spacing);
  return rows;
}

double Condition(const Eigen::MatrixXd& a) {
  if (a.size() == 0) return 0.0;
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(a).singularValues();
  return sv(sv.size() - 1) > 0 ? sv(0) / sv(sv.size() - 1) : std::numeric_limits<double>::infinity();
}

// Roots of 1 + Σ D_s z^s = 0, Eq. (18).
Eigen::VectorXcd LpRoots(const Eigen::VectorXd& d) {
  const int m = static_cast<int>(d.size());
  Eigen::VectorXd descending(m + 1);
  for (int s = 1; s <= m; ++s) descending(m - s) = d(s - 1);
  descending(m) = 1.0;
  return PolynomialRoots(descending);
}

// D_1…D_m of 1 + Σ D_s z^s = Π (1 − z/z_v): the LP coefficients (18) with the given roots.
Eigen::VectorXd LpFromRoots(const Eigen::VectorXcd& z) {
  const Eigen::VectorXd p = PolynomialFromRoots(z);  // monic, descending
  const int m = static_cast<int>(z.size());
  Eigen::VectorXd d(m);
  for (int s = 1; s <= m; ++s) d(s - 1) = p(m - s) / p(m);
  return d;
}

struct LpSolution {
  Eigen::VectorXd d;       // D_1 … D_m
  Eigen::VectorXcd roots;  // of (18)
  double cond = 0.0;
};

// Solves the LP system (20)/(30) on the rows starting at `starts`, by orthogonalisation as the
// paper asks (never by iteration): QR least squares, TLS, or the rank-m subspace of the
// extended matrix. `cond` is the condition number of the m-dimensional problem: of the
// regressor [w(k+h) … w(k+mh)] (QR, TLS), or σ_1/σ_m of the extended matrix (subspace).
LpSolution SolveLp(const Eigen::VectorXd& w, int m, int spacing, const std::vector<int>& starts,
                   StepLpSolver solver, int columns) {
  LpSolution out;
  if (solver == StepLpSolver::kSubspace) {
    const int l = std::max(columns > 0 ? columns : 3 * m, m + 1);
    std::vector<int> ok;
    for (int k : starts)
      if (k + l * spacing < w.size()) ok.push_back(k);
    if (static_cast<int>(ok.size()) > l) {
      const Eigen::MatrixXd y = LpRows(w, l, spacing, ok);
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(y, Eigen::ComputeThinV);
      const Eigen::VectorXd sv = svd.singularValues();
      out.cond = sv(m - 1) > 0 ? sv(0) / sv(m - 1) : std::numeric_limits<double>::infinity();
      const Eigen::MatrixXd vm = svd.matrixV().leftCols(m);
      // Rows of the signal space are [1, z, …, z^L]·T: shifting by one column multiplies by z.
      const Eigen::MatrixXd shift = vm.topRows(l).colPivHouseholderQr().solve(vm.bottomRows(l));
      out.roots = Eigen::EigenSolver<Eigen::MatrixXd>(shift, false).eigenvalues();
      out.d = LpFromRoots(out.roots);
      return out;
    }
    solver = StepLpSolver::kTls;  // too few rows for the extended matrix
  }
  const Eigen::MatrixXd rows = LpRows(w, m, spacing, starts);
  const Eigen::MatrixXd regressor = rows.rightCols(m);
  out.cond = Condition(regressor);
  bool done = false;
  if (solver == StepLpSolver::kTls) {
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(rows, Eigen::ComputeThinV);
    const Eigen::VectorXd v = svd.matrixV().col(m);
    if (std::abs(v(0)) > 1e-8 * v.norm()) {
      out.d = v.tail(m) / v(0);
      done = true;
    }
  }
  if (!done) out.d = regressor.colPivHouseholderQr().solve(-rows.col(0));
  out.roots = LpRoots(out.d);
  return out;
}

// Distinct poles from root clusters (single linkage at distance τ in the z-plane); b from
// Eq. (16) applied to the cluster centroid.
std::vector<StepPole> ClusterRoots(const Eigen::VectorXcd& z, double tau, double h,
                                   std::vector<std::string>* warnings) {
  const int n = static_cast<int>(z.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::function<int(int)> find = [&](int i) { return parent[i] == i ? i : parent[i] = find(parent[i]); };
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (std::abs(z(i) - z(j)) <= tau) parent[find(i)] = find(j);
  std::vector<StepPole> poles;
  std::vector<bool> done(n, false);
  for (int i = 0; i < n; ++i) {
    if (done[i]) continue;
    const int root = find(i);
    cd sum = 0.0;
    int count = 0;
    for (int j = 0; j < n; ++j)
      if (find(j) == root) {
        sum += z(j);
        ++count;
        done[j] = true;
      }
    const cd c = sum / static_cast<double>(count);
    const bool real = std::abs(c.imag()) <= 1e-9 * (1.0 + std::abs(c));
    if (!real && c.imag() < 0) continue;  // the conjugate cluster is kept instead
    StepPole pole;
    pole.multiplicity = count;
    pole.complex_pair = !real;
    if (real) {
      if (c.real() <= 0.0) {
        warnings->push_back("root z = " + Num(c.real()) + " of (18) is not positive: its pole is taken as real with |z|");
      }
      pole.b = -std::log(std::abs(c.real())) / h;  // Eq. (16)
    } else {
      pole.b = -std::log(c) / h;  // Eq. (16), principal logarithm
    }
    if (pole.b.real() <= 0.0)
      warnings->push_back("root |z| = " + Num(std::abs(c)) + " >= 1: the pole " + Num(-pole.b.real()) +
                          " does not decay (Eq. (2) violated)");
    poles.push_back(pole);
  }
  return poles;
}

// Distinct roots of (18) in a structure (a complex pair counts twice).
size_t DistinctRoots(const std::vector<StepPole>& poles) {
  size_t n = 0;
  for (const auto& p : poles) n += p.complex_pair ? 2 : 1;
  return n;
}

int RealUnknowns(const std::vector<StepPole>& poles) {
  int n = 0;
  for (const auto& p : poles) n += p.multiplicity * (p.complex_pair ? 2 : 1);
  return n;
}

// Columns of the real parametrisation: for each pole, r = N..1 (j = 1..N); a real pole gives
// Re f, a complex pair 2 Re f and −2 Im f for the unknowns Re A, Im A.
template <typename BasisAt>
Eigen::MatrixXd RealColumns(const std::vector<StepPole>& poles, int rows, BasisAt basis_at) {
  Eigen::MatrixXd cols(rows, RealUnknowns(poles));
  int c = 0;
  for (const auto& p : poles) {
    for (int j = 1; j <= p.multiplicity; ++j) {
      const int r = p.multiplicity + 1 - j;
      const Eigen::VectorXcd f = basis_at(p.b, r);
      if (p.complex_pair) {
        cols.col(c++) = 2.0 * f.real();
        cols.col(c++) = -2.0 * f.imag();
      } else {
        cols.col(c++) = f.real();
      }
    }
  }
  return cols;
}

void StoreResidues(const Eigen::VectorXd& a, std::vector<StepPole>* poles, bool ls) {
  int c = 0;
  for (auto& p : *poles) {
    Eigen::VectorXcd res(p.multiplicity);
    for (int j = 0; j < p.multiplicity; ++j) {
      if (p.complex_pair) {
        res(j) = cd(a(c), a(c + 1));
        c += 2;
      } else {
        res(j) = a(c++);
      }
    }
    (ls ? p.residues_ls : p.residues_eq20) = res;
  }
}

Eigen::VectorXd SolveScaled(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, double* cond) {
  Eigen::VectorXd scale = a.colwise().norm().transpose();
  for (int i = 0; i < scale.size(); ++i)
    if (!(scale(i) > 0)) scale(i) = 1.0;
  const Eigen::MatrixXd as = a * scale.cwiseInverse().asDiagonal();
  *cond = Condition(as);
  return as.colPivHouseholderQr().solve(b).cwiseQuotient(scale);
}

// Residues by least squares over all samples of x(t) (the paper's alternative to (20)/(23)).
double FitResiduesLs(const Eigen::VectorXd& x, const Eigen::VectorXd& t, double c,
                     std::vector<StepPole>* poles, double* cond) {
  const Eigen::MatrixXd phi = RealColumns(*poles, static_cast<int>(t.size()), [&](cd b, int r) {
    Eigen::VectorXcd f(t.size());
    for (int k = 0; k < t.size(); ++k) f(k) = c * StepBasis(b, r, t(k));
    return f;
  });
  const Eigen::VectorXd a = SolveScaled(phi, x, cond);
  StoreResidues(a, poles, true);
  return (x - phi * a).squaredNorm();
}

// Residues from the m equations (20)/(23) on α = 0..m−1 (point samples), or (30)/(35) on the
// block means / integrals: the basis is reduced by the same operator as the data, which is
// Eq. (32) summed directly (the closed form (33)–(35) is this sum).
void FitResiduesEq20(const Eigen::VectorXd& w, const Eigen::VectorXd& t, double c, const Grid& grid,
                     std::vector<StepPole>* poles, double* cond) {
  const int m = RealUnknowns(*poles);
  const int samples = grid.SamplesFor(m);
  const Eigen::MatrixXd a = RealColumns(*poles, m, [&](cd b, int r) {
    Eigen::VectorXcd f(samples);
    for (int k = 0; k < samples; ++k) f(k) = c * TailBasis(b, r, t(k));
    Eigen::VectorXcd reduced(m);
    for (int alpha = 0; alpha < m; ++alpha) reduced(alpha) = grid.Reduce(f, alpha);
    return reduced;
  });
  Eigen::VectorXd rhs(m);
  for (int alpha = 0; alpha < m; ++alpha) rhs(alpha) = w(alpha * grid.spacing);
  const Eigen::VectorXd sol = SolveScaled(a, rhs, cond);
  StoreResidues(sol, poles, false);
}

double Rss(const std::vector<StepPole>& poles, bool ls, double c, const Eigen::VectorXd& t,
           const Eigen::VectorXd& x) {
  std::vector<StepPole> copy = poles;
  for (auto& p : copy) p.residues = ls ? p.residues_ls : p.residues_eq20;
  return (x - StepPronyResponse(copy, c, t)).squaredNorm();
}

using CPoly = std::vector<cd>;  // ascending powers
CPoly Mul(const CPoly& a, const CPoly& b) {
  CPoly out(a.size() + b.size() - 1, 0.0);
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j) out[i + j] += a[i] * b[j];
  return out;
}

// ---- Refinement of the LP poles by variable projection (beyond the paper) -------------------
// The denominator is kept as linear factors (p + b) and quadratic factors (p + σ)² − d, whose
// modes e^(−σt)·{cosh √d t, sinh(√d t)/√d} pass continuously through the double pole at d = 0,
// so a double pole split by noise into two reals or a complex pair can close up. The residues
// are eliminated by linear least squares; the step-response columns are f(0) − f(t) (x(0) = 0).
struct Factors {
  int linear = 0, quadratic = 0;  // parameters: b_1..b_linear, then (σ, d) per quadratic
};

Eigen::MatrixXd FactorColumns(const Factors& f, const Eigen::VectorXd& theta, const Eigen::VectorXd& t) {
  const int n = static_cast<int>(t.size());
  Eigen::MatrixXd g(n, f.linear + 2 * f.quadratic);
  for (int i = 0; i < f.linear; ++i) {
    const double b = theta(i);
    for (int k = 0; k < n; ++k) g(k, i) = 1.0 - std::exp(-b * t(k));
  }
  for (int q = 0; q < f.quadratic; ++q) {
    const double sigma = theta(f.linear + 2 * q), d = theta(f.linear + 2 * q + 1);
    const double r = std::sqrt(std::abs(d));
    for (int k = 0; k < n; ++k) {
      double c, sn;
      if (r * t(k) < 1e-8) {
        c = 1.0;
        sn = t(k);
      } else if (d > 0) {
        c = std::cosh(r * t(k));
        sn = std::sinh(r * t(k)) / r;
      } else {
        c = std::cos(r * t(k));
        sn = std::sin(r * t(k)) / r;
      }
      const double e = std::exp(-sigma * t(k));
      g(k, f.linear + 2 * q) = 1.0 - e * c;
      g(k, f.linear + 2 * q + 1) = -e * sn;
    }
  }
  return g;
}

struct VarProFunctor : Eigen::DenseFunctor<double> {
  VarProFunctor(const Factors& f, const Eigen::VectorXd& t, const Eigen::VectorXd& x)
      : Eigen::DenseFunctor<double>(f.linear + 2 * f.quadratic, static_cast<int>(t.size())), f(f), t(t), x(x) {}
  int operator()(const Eigen::VectorXd& theta, Eigen::VectorXd& residual) const {
    const Eigen::MatrixXd g = FactorColumns(f, theta, t);
    Eigen::VectorXd scale = g.colwise().norm().transpose();
    for (int i = 0; i < scale.size(); ++i)
      if (!(scale(i) > 0)) scale(i) = 1.0;
    const Eigen::MatrixXd gs = g * scale.cwiseInverse().asDiagonal();
    residual = x - gs * gs.colPivHouseholderQr().solve(x);
    return 0;
  }
  Factors f;
  Eigen::VectorXd t, x;
};

// Refines the roots b (one entry per root, conjugates included) on all samples; returns the
// refined roots (same count) and the number of LM iterations.
Eigen::VectorXcd RefineRoots(const Eigen::VectorXcd& b_in, const Eigen::VectorXd& t, const Eigen::VectorXd& x,
                             int* iterations) {
  std::vector<cd> complex_upper;
  std::vector<double> reals;
  for (int i = 0; i < b_in.size(); ++i) {
    const cd b = b_in(i);
    if (std::abs(b.imag()) <= 1e-9 * (1.0 + std::abs(b))) reals.push_back(b.real());
    else if (b.imag() < 0) complex_upper.push_back(b);  // pole −b has Im > 0
  }
  std::sort(reals.begin(), reals.end());
  Factors f;
  f.quadratic = static_cast<int>(complex_upper.size()) + static_cast<int>(reals.size()) / 2;
  f.linear = static_cast<int>(reals.size()) % 2;
  Eigen::VectorXd theta(f.linear + 2 * f.quadratic);
  int q = 0;
  // Adjacent reals form a quadratic; with an odd count the one farthest from its neighbours is linear.
  size_t skip = reals.size();
  if (f.linear) {
    double best_gap = -1.0;
    for (size_t i = 0; i < reals.size(); i += 2) {  // candidate positions leaving pairs (0,1),(2,3)…
      const double left = i > 0 ? reals[i] - reals[i - 1] : std::numeric_limits<double>::infinity();
      const double right = i + 1 < reals.size() ? reals[i + 1] - reals[i] : std::numeric_limits<double>::infinity();
      const double gap = std::min(left, right);
      if (gap > best_gap) {
        best_gap = gap;
        skip = i;
      }
    }
    theta(0) = reals[skip];
  }
  std::vector<double> paired;
  for (size_t i = 0; i < reals.size(); ++i)
    if (i != skip) paired.push_back(reals[i]);
  for (size_t i = 0; i + 1 < paired.size(); i += 2, ++q) {
    theta(f.linear + 2 * q) = 0.5 * (paired[i] + paired[i + 1]);
    theta(f.linear + 2 * q + 1) = std::pow(0.5 * (paired[i + 1] - paired[i]), 2);
  }
  for (const cd& b : complex_upper) {
    theta(f.linear + 2 * q) = b.real();
    theta(f.linear + 2 * q + 1) = -b.imag() * b.imag();
    ++q;
  }
  VarProFunctor functor(f, t, x);
  Eigen::NumericalDiff<VarProFunctor> diff(functor);
  Eigen::LevenbergMarquardt<Eigen::NumericalDiff<VarProFunctor>> lm(diff);
  lm.setMaxfev(200 * (static_cast<int>(theta.size()) + 1));
  Eigen::VectorXd start = theta;
  Eigen::VectorXd r0, r1;
  functor(start, r0);
  lm.minimize(theta);
  functor(theta, r1);
  if (!(r1.squaredNorm() <= r0.squaredNorm()) || !theta.allFinite()) theta = start;
  *iterations = static_cast<int>(lm.iterations());
  Eigen::VectorXcd out(b_in.size());
  int k = 0;
  for (int i = 0; i < f.linear; ++i) out(k++) = theta(i);
  for (int j = 0; j < f.quadratic; ++j) {
    const double sigma = theta(f.linear + 2 * j), d = theta(f.linear + 2 * j + 1);
    if (d >= 0) {
      out(k++) = sigma - std::sqrt(d);
      out(k++) = sigma + std::sqrt(d);
    } else {
      out(k++) = cd(sigma, -std::sqrt(-d));
      out(k++) = cd(sigma, std::sqrt(-d));
    }
  }
  return out;
}

// Refines the b of a fixed multiplicity structure by variable projection: the residues are the
// least-squares solution over all samples for every trial b. Returns the final Σ (x − x̂)².
struct StructureFunctor : Eigen::DenseFunctor<double> {
  StructureFunctor(const std::vector<StepPole>& poles, const Eigen::VectorXd& t, const Eigen::VectorXd& x, double c)
      : Eigen::DenseFunctor<double>(Count(poles), static_cast<int>(t.size())), poles(poles), t(t), x(x), c(c) {}
  static int Count(const std::vector<StepPole>& poles) {
    int n = 0;
    for (const auto& p : poles) n += p.complex_pair ? 2 : 1;
    return n;
  }
  Eigen::VectorXd Pack() const {
    Eigen::VectorXd theta(Count(poles));
    int i = 0;
    for (const auto& p : poles) {
      theta(i++) = p.b.real();
      if (p.complex_pair) theta(i++) = p.b.imag();
    }
    return theta;
  }
  std::vector<StepPole> Unpack(const Eigen::VectorXd& theta) const {
    std::vector<StepPole> out = poles;
    int i = 0;
    for (auto& p : out) {
      const double re = theta(i++);
      p.b = p.complex_pair ? cd(re, theta(i++)) : cd(re, 0.0);
    }
    return out;
  }
  int operator()(const Eigen::VectorXd& theta, Eigen::VectorXd& residual) const {
    std::vector<StepPole> trial = Unpack(theta);
    double cond = 0.0;
    FitResiduesLs(x, t, c, &trial, &cond);
    for (auto& p : trial) p.residues = p.residues_ls;
    residual = x - StepPronyResponse(trial, c, t);
    return 0;
  }
  std::vector<StepPole> poles;
  Eigen::VectorXd t, x;
  double c;
};

double RefineStructure(std::vector<StepPole>* poles, const Eigen::VectorXd& t, const Eigen::VectorXd& x, double c,
                       int* iterations) {
  StructureFunctor functor(*poles, t, x, c);
  Eigen::VectorXd theta = functor.Pack();
  const Eigen::VectorXd start = theta;
  Eigen::VectorXd r0, r1;
  functor(start, r0);
  Eigen::NumericalDiff<StructureFunctor> diff(functor);
  Eigen::LevenbergMarquardt<Eigen::NumericalDiff<StructureFunctor>> lm(diff);
  lm.setMaxfev(100 * (static_cast<int>(theta.size()) + 1));
  lm.minimize(theta);
  functor(theta, r1);
  if (!theta.allFinite() || !(r1.squaredNorm() <= r0.squaredNorm())) {
    theta = start;
    r1 = r0;
  }
  *iterations += static_cast<int>(lm.iterations());
  *poles = functor.Unpack(theta);
  return r1.squaredNorm();
}

}  // namespace

Eigen::VectorXd StepPronyResponse(const std::vector<StepPole>& poles, double step_amplitude,
                                  const Eigen::VectorXd& t) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(t.size());
  for (const auto& p : poles) {
    for (int j = 1; j <= p.multiplicity; ++j) {
      const int r = p.multiplicity + 1 - j;
      const cd a = p.residues(j - 1);
      for (int k = 0; k < t.size(); ++k) {
        const cd term = a * StepBasis(p.b, r, t(k));  // Eq. (5)
        x(k) += step_amplitude * (p.complex_pair ? 2.0 * term.real() : term.real());
      }
    }
  }
  return x;
}

TransferFunction StepPolesToTransferFunction(const std::vector<StepPole>& poles) {
  // Every pole with its conjugate, as (b, N, residues).
  struct Term {
    cd b;
    int n;
    Eigen::VectorXcd a;
  };
  std::vector<Term> terms;
  for (const auto& p : poles) {
    terms.push_back({p.b, p.multiplicity, p.residues});
    if (p.complex_pair) terms.push_back({std::conj(p.b), p.multiplicity, p.residues.conjugate()});
  }
  auto power = [](cd b, int n) {
    CPoly out{1.0};
    for (int i = 0; i < n; ++i) out = Mul(out, CPoly{b, 1.0});
    return out;
  };
  CPoly den{1.0};
  for (const auto& t : terms) den = Mul(den, power(t.b, t.n));
  const int m = static_cast<int>(den.size()) - 1;
  CPoly num(std::max(m, 1), 0.0);
  for (size_t i = 0; i < terms.size(); ++i) {
    CPoly others{1.0};
    for (size_t k = 0; k < terms.size(); ++k)
      if (k != i) others = Mul(others, power(terms[k].b, terms[k].n));
    for (int j = 1; j <= terms[i].n; ++j) {
      const int r = terms[i].n + 1 - j;  // Eq. (1): A_vj / (p + b_v)^(N_v+1−j)
      const CPoly part = Mul(others, power(terms[i].b, terms[i].n - r));
      for (size_t q = 0; q < part.size(); ++q) num[q] += terms[i].a(j - 1) * part[q];
    }
  }
  TransferFunction tf;
  tf.den.resize(m + 1);
  for (int q = 0; q <= m; ++q) tf.den(m - q) = den[q].real();
  tf.num.resize(num.size());
  for (size_t q = 0; q < num.size(); ++q) tf.num(num.size() - 1 - q) = num[q].real();
  return tf;
}

StepPronyResult IdentifyStepResponse(const Eigen::VectorXd& x_in, double sample_time,
                                     double step_amplitude, const StepPronyOptions& options) {
  const int n = static_cast<int>(x_in.size());
  if (!(sample_time > 0.0) || !std::isfinite(sample_time)) Fail("sample time must be positive");
  if (!(std::abs(step_amplitude) > 0.0) || !std::isfinite(step_amplitude))
    Fail("the step amplitude C must be non-zero (the input does not step)");
  for (int k = 0; k < n; ++k)
    if (!std::isfinite(x_in(k))) Fail("output sample " + std::to_string(k) + " is NaN or infinite");
  if (options.order < 0 || options.max_order < 1) Fail("order must be >= 0 and max_order >= 1");
  if (options.spacing < 0 || options.blocks < 0) Fail("spacing and blocks must be >= 0");
  if (!(options.tail_fraction > 0.0 && options.tail_fraction < 0.5)) Fail("tail_fraction must be in (0, 0.5)");
  const int min_order = std::max(options.order, 1);
  if (n < 2 * min_order + 1 || n < 10)
    Fail("too few samples for order " + std::to_string(min_order) + ": the linear prediction (20) needs at least " +
         std::to_string(std::max(2 * min_order + 1, 10)) + " samples, the record has " + std::to_string(n));

  StepPronyResult result;
  result.sample_time = sample_time;
  result.step_amplitude = step_amplitude;
  result.averaging = options.averaging;
  result.solver = options.solver;
  result.t = Eigen::VectorXd::LinSpaced(n, 0.0, (n - 1) * sample_time);
  result.measured = x_in;
  const Eigen::VectorXd& t = result.t;
  const Eigen::VectorXd& x = x_in;

  // x(∞) and the noise level from the tail: a straight line through the last samples. A slope
  // that moves the output by more than the tolerance over the tail means the record has not
  // settled and x(∞) (6) cannot be read off.
  const int tail = std::max(5, static_cast<int>(options.tail_fraction * n));
  const Eigen::VectorXd tt = t.tail(tail).array() - t(n - tail);
  const Eigen::VectorXd xt = x.tail(tail);
  Eigen::MatrixXd line(tail, 2);
  line.col(0).setOnes();
  line.col(1) = tt;
  const Eigen::Vector2d coef = line.colPivHouseholderQr().solve(xt);
  const double sigma = std::sqrt((xt - line * coef).squaredNorm() / std::max(1, tail - 2));
  const double range = (x.array() - x(0)).abs().maxCoeff();
  if (!(range > 0.0)) Fail("the output does not respond to the step (constant record)");
  const double drift = std::abs(coef(1)) * tt(tail - 1);
  const double allowed = options.settle_tolerance * range + 4.0 * sigma * std::sqrt(12.0 / tail);
  if (std::isnan(options.x_inf) && drift > allowed)
    Fail("the record never settles, so x(inf) (Eq. (6)) cannot be estimated: the output still moves by " +
         Num(drift) + " over the last " + Num(tt(tail - 1)) + " s (" + Num(100.0 * drift / range) +
         " % of its range, allowed " + Num(100.0 * allowed / range) +
         " %); record longer, or give x_inf explicitly");
  result.noise_sigma = sigma;
  result.x_inf_estimated = std::isnan(options.x_inf);
  result.x_inf = result.x_inf_estimated ? xt.mean() : options.x_inf;
  result.x_inf_tail = xt.mean();
  const Eigen::VectorXd xbar = result.x_inf - x.array();  // Eq. (7), for the transient length

  // Duration of the transient: last time the smoothed |x̄| exceeds 2 % of the range (or 4σ).
  const int smooth = std::max(1, n / 100);
  int last = 0;
  {
    double acc = 0.0;
    for (int k = 0; k < n; ++k) {
      acc += xbar(k);
      if (k >= smooth) acc -= xbar(k - smooth);
      const double mean = acc / std::min(k + 1, smooth);
      if (std::abs(mean) > std::max(0.02 * range, 4.0 * sigma / std::sqrt(smooth))) last = k;
    }
  }
  const double transient = std::max(last, 10) * sample_time;

  // Spacing h (9) and sub-intervals B (25).
  Grid grid;
  grid.averaging = options.averaging;
  grid.sample_time = sample_time;
  const int target_order = options.order > 0 ? options.order : options.max_order;
  grid.spacing = options.spacing > 0 ? options.spacing
                                     : std::max(1, static_cast<int>(std::lround(transient / (sample_time * 4.0 * target_order))));
  grid.blocks = options.averaging == StepAveraging::kBlock ? (options.blocks > 0 ? options.blocks : grid.spacing) : 1;
  if (grid.spacing % grid.blocks != 0)
    Fail("blocks B = " + std::to_string(grid.blocks) + " must divide the spacing " + std::to_string(grid.spacing) +
         " (samples per h) so that the sub-points of (25) fall on samples");
  const double h = grid.spacing * sample_time;
  result.h = h;
  result.spacing = grid.spacing;
  result.blocks = grid.blocks;

  const int points_all = grid.Points(n);
  const int horizon = static_cast<int>(std::ceil(options.horizon_factor * transient / h)) + 1;
  if (points_all < 2 * min_order + 1)
    Fail("too few samples for order " + std::to_string(min_order) + ": spacing h = " + Num(h) + " s gives " +
         std::to_string(points_all) + " LP points, at least " + std::to_string(2 * min_order + 1) +
         " are needed; give a smaller spacing or a longer record");
  const int usable = n - grid.Extent();  // start samples with a complete value
  const int length = std::min(usable, std::max(horizon * grid.spacing, (2 * min_order + 3) * grid.spacing + 1));
  // The LP sequence: (25), the integral, or point values of x̄ = x(∞) − x (7).
  auto make_sequence = [&](double x_inf) {
    const Eigen::VectorXd xbar_now = x_inf - x.array();  // Eq. (7)
    Eigen::VectorXd w(length);
    for (int k = 0; k < length; ++k) w(k) = grid.ReduceAt(xbar_now, k);
    return w;
  };
  Eigen::VectorXd lp_sequence = make_sequence(result.x_inf);
  const int lp_length = static_cast<int>(lp_sequence.size());
  // Equation starts: every sample (sliding) or the grid α h of the paper.
  const int stride = options.sliding ? 1 : grid.spacing;
  auto starts_for = [&](int m) {
    std::vector<int> starts;
    for (int k = 0; k + m * grid.spacing < lp_length; k += stride) starts.push_back(k);
    return starts;
  };
  const double noise_var = std::max(sigma * sigma, 1e-24 * x.squaredNorm() / n);

  // One candidate order: LP (20)/(30) → roots (18) → b (16) (a negative real root taken with
  // |z|) → refinement → least-squares fit over all samples.
  struct Candidate {
    LpSolution lp;
    Eigen::VectorXcd lp_poles, roots_z;  // roots_z after refinement
    double rss = 0.0, lp_residual = 0.0, x_inf_model = 0.0;
    int iterations = 0;
  };
  auto fit_order = [&](int m) {
    Candidate c;
    const std::vector<int> starts = starts_for(m);
    c.lp = SolveLp(lp_sequence, m, grid.spacing, starts, options.solver, options.columns);
    Eigen::VectorXd d1(m + 1);
    d1 << 1.0, c.lp.d;
    // (38)/(39): the residual of the prediction equations, divided by |(1, D)| (the noise part
    // then does not grow with m).
    const Eigen::VectorXd r = LpRows(lp_sequence, m, grid.spacing, starts) * d1 / d1.norm();
    c.lp_residual = std::sqrt(r.squaredNorm() / std::max<Eigen::Index>(1, r.size()));
    Eigen::VectorXcd b(c.lp.roots.size());
    for (int i = 0; i < b.size(); ++i) {
      const cd z = c.lp.roots(i);
      b(i) = std::abs(z.imag()) <= 1e-9 * (1.0 + std::abs(z)) ? cd(-std::log(std::abs(z.real())) / h, 0.0)
                                                              : -std::log(z) / h;  // Eq. (16)
    }
    c.lp_poles = -b;
    if (options.refine) b = RefineRoots(b, t, x, &c.iterations);
    c.roots_z = (-b * h).array().exp();
    std::vector<std::string> ignored;
    std::vector<StepPole> poles = ClusterRoots(c.roots_z, 0.0, h, &ignored);
    double cond = 0.0;
    c.rss = FitResiduesLs(x, t, step_amplitude, &poles, &cond);
    cd gain = 0.0;
    for (const auto& p : poles)
      for (int j = 1; j <= p.multiplicity; ++j) {
        const cd term = p.residues_ls(j - 1) / std::pow(p.b, p.multiplicity + 1 - j);  // Eq. (6)
        gain += p.complex_pair ? 2.0 * term.real() : term.real();
      }
    c.x_inf_model = step_amplitude * gain.real();
    return c;
  };

  // Order (36)–(41): every candidate m is reported with its prediction residual (38)/(39) and
  // the residual of the fitted model over all samples. The order is the smallest m whose
  // fitted residual is within the noise of the minimum (σ² χ²_0.999 of the extra parameters):
  // under noise the prediction residual alone flattens at the noise level.
  int order = options.order;
  Candidate chosen_candidate;
  if (order == 0) {
    std::vector<Candidate> candidates;
    for (int m = 1; m <= options.max_order; ++m) {
      if (static_cast<int>(starts_for(m).size()) < m + 1 ||
          (options.solver == StepLpSolver::kSubspace && m * grid.spacing * 3 >= lp_length))
        break;
      candidates.push_back(fit_order(m));
      StepOrderRow row;
      row.order = m;
      row.residual = candidates.back().lp_residual;
      row.condition_number = candidates.back().lp.cond;
      row.fit_rss = candidates.back().rss;
      result.order_table.push_back(row);
    }
    if (candidates.empty()) Fail("too few samples for order 1 with spacing h = " + Num(h) + " s");
    double best = std::numeric_limits<double>::infinity();
    for (const auto& c : candidates) best = std::min(best, c.rss);
    for (size_t i = 0; i < candidates.size(); ++i) {
      const int extra = 2 * static_cast<int>(candidates.size() - i);
      if (candidates[i].rss <= best + noise_var * ChiSquareQuantile(0.999, extra) + 1e-18 * x.squaredNorm()) {
        order = static_cast<int>(i) + 1;
        chosen_candidate = candidates[i];
        break;
      }
    }
  } else {
    if (static_cast<int>(starts_for(order).size()) < order)
      Fail("too few samples for order " + std::to_string(order) + ": " + std::to_string(starts_for(order).size()) +
           " LP equations for " + std::to_string(order) + " unknowns");
    chosen_candidate = fit_order(order);
  }
  const int m = order;
  result.order = m;
  // x(∞) read off the tail carries the tail's ringing and noise, and a constant error in x̄ is
  // an extra root z = 1 that the order-m LP cannot hold: take x(∞) of the fitted model (6)
  // and solve the LP again.
  if (result.x_inf_estimated && options.refit_x_inf && std::isfinite(chosen_candidate.x_inf_model)) {
    result.x_inf = chosen_candidate.x_inf_model;
    lp_sequence = make_sequence(result.x_inf);
    const int iterations = result.iterations + chosen_candidate.iterations;
    chosen_candidate = fit_order(m);
    result.iterations = iterations;
  }
  result.lp_equations = static_cast<int>(starts_for(m).size());
  result.lp_coefficients = chosen_candidate.lp.d;
  result.lp_condition_number = chosen_candidate.lp.cond;
  result.roots_z = chosen_candidate.lp.roots;
  result.lp_poles = chosen_candidate.lp_poles;
  result.refined = options.refine;
  result.iterations += chosen_candidate.iterations;
  const Eigen::VectorXcd roots_z = chosen_candidate.roots_z;

  // Multiplicities: merge nearby roots when the least-squares fit over all samples does not
  // worsen beyond what the noise explains (χ² spread of σ²·N, σ from the tail).
  // Candidate structures: single-linkage clusters of the roots at every pairwise distance up to
  // max_cluster_distance (z-plane). Each is refined (when refining) and kept when its fit is
  // within the noise of the unmerged fit: ΔRSS ≤ σ²·χ²_0.999(parameters removed) (σ from the tail),
  // the tolerance "tied to the noise" of the multiplicity decision.
  std::vector<double> distances{0.0};
  for (int i = 0; i < roots_z.size(); ++i)
    for (int j = i + 1; j < roots_z.size(); ++j) {
      const double d = std::abs(roots_z(i) - roots_z(j));
      if (d <= options.max_cluster_distance) distances.push_back(d * (1.0 + 1e-12));
    }
  std::sort(distances.begin(), distances.end());
  std::vector<StepPole> chosen;
  double chosen_rss = 0.0, base_rss = 0.0, cond_ls = 0.0;
  int base_params = 0;
  size_t last_count = 0;
  std::vector<std::string> cluster_warnings;
  for (size_t i = 0; i < distances.size(); ++i) {
    std::vector<std::string> warn;
    std::vector<StepPole> poles = ClusterRoots(roots_z, distances[i], h, &warn);
    const size_t distinct = DistinctRoots(poles);
    if (i > 0 && distinct == last_count) continue;  // same partition as before
    last_count = distinct;
    const int params = StructureFunctor::Count(poles);
    if (options.refine && i > 0) RefineStructure(&poles, t, x, step_amplitude, &result.iterations);
    double cond = 0.0;
    const double rss = FitResiduesLs(x, t, step_amplitude, &poles, &cond);
    if (i == 0) {
      base_rss = rss;
      base_params = params;
    } else if (!(rss <= base_rss + noise_var * ChiSquareQuantile(0.999, std::max(1, base_params - params)) +
                           1e-18 * x.squaredNorm())) {
      continue;
    }
    if (i == 0 || distinct < DistinctRoots(chosen)) {
      chosen = poles;
      chosen_rss = rss;
      cond_ls = cond;
      cluster_warnings = warn;
      result.cluster_tolerance = distances[i];
    }
  }
  result.warnings.insert(result.warnings.end(), cluster_warnings.begin(), cluster_warnings.end());

  // Residues both ways; keep the better fit.
  result.residue_rss_ls = chosen_rss;
  result.residue_condition_ls = cond_ls;
  FitResiduesEq20(lp_sequence, t, step_amplitude, grid, &chosen, &result.residue_condition_eq20);
  result.residue_rss_eq20 = Rss(chosen, false, step_amplitude, t, x);
  const bool use_ls = !(result.residue_rss_eq20 < result.residue_rss_ls);
  result.residue_method = use_ls ? "least_squares" : "eq20";
  for (auto& p : chosen) p.residues = use_ls ? p.residues_ls : p.residues_eq20;
  result.poles = chosen;

  result.fitted = StepPronyResponse(result.poles, step_amplitude, t);
  result.fit_percent = FitPercent(x, result.fitted)(0);
  result.final_cost = std::min(result.residue_rss_ls, result.residue_rss_eq20);
  result.iterations = std::max(result.iterations, 1);
  result.tf = StepPolesToTransferFunction(result.poles);
  cd gain = 0.0;
  for (const auto& p : result.poles)
    for (int j = 1; j <= p.multiplicity; ++j) {
      const cd term = p.residues(j - 1) / std::pow(p.b, p.multiplicity + 1 - j);  // Eq. (6)
      gain += p.complex_pair ? 2.0 * term.real() : term.real();
    }
  result.x_inf_model = step_amplitude * gain.real();

  const double cond_limit = 1e12;
  result.status = SolverStatus::kOk;
  std::ostringstream msg;
  msg << "order " << m << ", " << result.poles.size() << " distinct poles, LP condition number "
      << Num(result.lp_condition_number) << ", residues by " << result.residue_method;
  if (result.lp_condition_number > cond_limit) {
    result.status = SolverStatus::kIllConditioned;
    msg << "; the LP system (20)/(30) is ill-conditioned (nearly collinear rows): try a larger spacing or a lower order";
  }
  for (const auto& p : result.poles)
    if (p.b.real() <= 0.0) {
      result.status = SolverStatus::kIllConditioned;
      msg << "; a pole does not decay";
      break;
    }
  result.message = msg.str();
  return result;
}

StepPronyResult IdentifyStepResponse(const IoRecord& record, const StepPronyOptions& options) {
  ValidateIoRecord(record, 10);
  if (record.NumInputs() != 1 || record.NumOutputs() != 1)
    Fail("needs a SISO record (t,u,y); got " + std::to_string(record.NumInputs()) + " inputs and " +
         std::to_string(record.NumOutputs()) + " outputs");
  const int n = record.NumSamples();
  const Eigen::VectorXd u = record.u.col(0), y = record.y.col(0);
  const int tail = std::max(5, static_cast<int>(options.tail_fraction * n));
  const double u1 = u.tail(tail).mean();
  double u0 = u(0);
  // An input already at its final level at the first sample: the step of (4) was applied at
  // t = 0 from rest (zero initial conditions), so the level before it is 0.
  if (std::abs(u1 - u0) <= 1e-12 * (1.0 + std::abs(u1)) && std::abs(u1) > 0.0) u0 = 0.0;
  const double c = u1 - u0;
  if (!(std::abs(c) > 1e-12 * (1.0 + u.cwiseAbs().maxCoeff())))
    Fail("the input does not step: its final level equals its initial level " + Num(u0));
  int k0 = 0;
  while (k0 < n && std::abs(u(k0) - u0) < 0.5 * std::abs(c)) ++k0;
  for (int k = k0; k < n; ++k)
    if (std::abs(u(k) - u1) > 0.05 * std::abs(c))
      Fail("the input is not a step: u(" + Num(record.t(k)) + " s) = " + Num(u(k)) + " differs from the final level " +
           Num(u1) + " after the step at " + Num(record.t(k0)) + " s");
  const double baseline = k0 > 0 ? y.head(k0).mean() : 0.0;
  const Eigen::VectorXd x = y.tail(n - k0).array() - baseline;
  StepPronyOptions o = options;
  if (!std::isnan(o.x_inf)) o.x_inf -= baseline;
  StepPronyResult r = IdentifyStepResponse(x, record.sample_time, c, o);
  r.step_time = record.t(k0);
  if (k0 > 0) r.warnings.push_back("step at t = " + Num(r.step_time) + " s; output baseline " + Num(baseline) + " removed");
  return r;
}

}  // namespace idrig
