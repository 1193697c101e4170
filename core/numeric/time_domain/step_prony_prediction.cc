// Step-response identification with multiple complex poles, [Vidinčev] (seed 000): linear prediction (10)–(19).
#include "core/numeric/time_domain/step_prony_internal.h"

#include <cmath>
#include <functional>
#include <limits>
#include <numeric>

namespace idrig {

const char* ToString(StepLpSolver solver) {
  switch (solver) {
    case StepLpSolver::kQr: return "qr";
    case StepLpSolver::kTls: return "tls";
    case StepLpSolver::kSubspace: return "subspace";
  }
  return "?";
}

namespace step_prony_detail {

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

}  // namespace step_prony_detail
}  // namespace idrig
