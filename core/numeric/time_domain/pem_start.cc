// Starting values of the prediction-error methods (pem.h): Steiglitz–McBride, the subspace
// estimate and Hannan–Rissanen regressions for the noise polynomials.
#include <algorithm>
#include <cmath>

#include "core/numeric/time_domain/pem_internal.h"
#include "core/numeric/time_domain/subspace.h"

namespace idrig::pem_internal {

Eigen::VectorXd Shifted(const Eigen::VectorXd& x, int k) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(x.size());
  if (k < x.size()) out.tail(x.size() - k) = x.head(x.size() - k);
  return out;
}

bool IsStablePolynomial(const Eigen::VectorXd& monic) {
  if (monic.size() <= 1) return true;
  const Eigen::VectorXcd roots = PolynomialRoots(monic);
  return roots.size() == 0 || roots.cwiseAbs().maxCoeff() < 1.0;
}

Eigen::VectorXd StabilisedMonic(const Eigen::VectorXd& monic, int degree) {
  Eigen::VectorXd p = Eigen::VectorXd::Zero(degree + 1);
  const int keep = std::min<int>(degree + 1, static_cast<int>(monic.size()));
  p.head(keep) = monic.head(keep);
  p(0) = 1.0;
  if (degree == 0) return p;
  Eigen::VectorXcd roots = PolynomialRoots(p);
  bool changed = false;
  for (int i = 0; i < roots.size(); ++i)
    if (std::abs(roots(i)) >= 0.999) {
      roots(i) = std::polar(std::min(0.999, 1.0 / std::abs(roots(i))), std::arg(roots(i)));
      changed = true;
    }
  if (!changed) return p;
  Eigen::VectorXd out = Eigen::VectorXd::Zero(degree + 1);
  const Eigen::VectorXd from_roots = PolynomialFromRoots(roots);
  out.head(from_roots.size()) = from_roots;
  return out;
}

Eigen::VectorXd LeastSquares(const Eigen::MatrixXd& phi, const Eigen::VectorXd& y) {
  // Starting values only: normal equations on equilibrated columns (O(N p²), no N×p QR), with
  // a QR fallback when they are too ill-conditioned.
  const int p = static_cast<int>(phi.cols());
  if (p == 0) return Eigen::VectorXd();
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(p, p);
  gram.selfadjointView<Eigen::Lower>().rankUpdate(phi.transpose());
  gram.triangularView<Eigen::StrictlyUpper>() = gram.transpose();
  const Eigen::VectorXd scale = gram.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = scale.asDiagonal() * gram * scale.asDiagonal();
  Eigen::LDLT<Eigen::MatrixXd> ldlt(scaled);
  if (ldlt.info() == Eigen::Success && ldlt.rcond() > 1e-10)
    return scale.asDiagonal() * ldlt.solve(scale.asDiagonal() * (phi.transpose() * y));
  return phi.colPivHouseholderQr().solve(y);
}

namespace {

// One (prefiltered) common-denominator ARX regression:
// y(t) = −Σ a_k y(t−k) + Σ_j Σ_k b_jk u_j(t−nk−k) (+ Σ c_k e(t−k) when e is given).
void Regress(const Eigen::VectorXd& y, const Eigen::MatrixXd& u, int na, int nb, int nk,
             const Eigen::VectorXd* e, int nc, Eigen::VectorXd* a, std::vector<Eigen::VectorXd>* b,
             Eigen::VectorXd* c) {
  const int nu = static_cast<int>(u.cols());
  const int p = na + nu * nb + (e ? nc : 0);
  const long n = y.size();
  Eigen::MatrixXd phi(n, p);
  int col = 0;
  for (int k = 1; k <= na; ++k) phi.col(col++) = -Shifted(y, k);
  for (int j = 0; j < nu; ++j)
    for (int k = 0; k < nb; ++k) phi.col(col++) = Shifted(u.col(j), nk + k);
  if (e)
    for (int k = 1; k <= nc; ++k) phi.col(col++) = Shifted(*e, k);
  const Eigen::VectorXd theta = LeastSquares(phi, y);
  a->resize(na + 1);
  (*a)(0) = 1.0;
  a->tail(na) = theta.head(na);
  b->assign(nu, Eigen::VectorXd());
  for (int j = 0; j < nu; ++j) (*b)[j] = theta.segment(na + j * nb, nb);
  if (c) {
    c->resize(nc + 1);
    (*c)(0) = 1.0;
    if (e) c->tail(nc) = theta.tail(nc);
    else c->tail(nc).setZero();
  }
}

// Steiglitz–McBride: ARX on u, y prefiltered by 1/Â, repeated ([Ljung] §10.4).
void SteiglitzMcBride(const Eigen::VectorXd& y, const Eigen::MatrixXd& u, int n, int nb, int nk,
                      Eigen::VectorXd* a, std::vector<Eigen::VectorXd>* b) {
  Eigen::VectorXd one = Eigen::VectorXd::Ones(1);
  Regress(y, u, n, nb, nk, nullptr, 0, a, b, nullptr);
  for (int it = 0; it < 30; ++it) {
    const Eigen::VectorXd filt = StabilisedMonic(*a, n);
    Eigen::MatrixXd uf(u.rows(), u.cols());
    for (int j = 0; j < u.cols(); ++j) uf.col(j) = FilterPolynomial(one, filt, u.col(j));
    const Eigen::VectorXd yf = FilterPolynomial(one, filt, y);
    Eigen::VectorXd a_new;
    Regress(yf, uf, n, nb, nk, nullptr, 0, &a_new, b, nullptr);
    const double change = (a_new - *a).norm();
    *a = a_new;
    if (change < 1e-10) break;
  }
  *a = StabilisedMonic(*a, n);
}

// ARMA(nd, nc) of a residual r by Hannan–Rissanen: e from a long AR, then D r = C e by LS.
void NoiseModel(const Eigen::VectorXd& r, int nc, int nd, Eigen::VectorXd* c, Eigen::VectorXd* d) {
  const int long_order = std::min<int>(std::max(20, 3 * (nc + nd)), static_cast<int>(r.size() / 10));
  Eigen::MatrixXd phi(r.size(), long_order);
  for (int k = 1; k <= long_order; ++k) phi.col(k - 1) = -Shifted(r, k);
  const Eigen::VectorXd ar = LeastSquares(phi, r);
  const Eigen::VectorXd e = r - phi * ar;
  Eigen::MatrixXd reg(r.size(), nc + nd);
  for (int k = 1; k <= nd; ++k) reg.col(k - 1) = -Shifted(r, k);
  for (int k = 1; k <= nc; ++k) reg.col(nd + k - 1) = Shifted(e, k);
  const Eigen::VectorXd theta = nc + nd > 0 ? LeastSquares(reg, r) : Eigen::VectorXd();
  Eigen::VectorXd dd(nd + 1), cc(nc + 1);
  dd << 1.0, theta.head(nd);
  cc << 1.0, theta.tail(nc);
  *d = StabilisedMonic(dd, nd);
  *c = StabilisedMonic(cc, nc);
}

// The subspace model's common denominator and per-input numerators as (a, b_j).
bool SubspacePolys(const Eigen::VectorXd& y, const Eigen::MatrixXd& u, double ts, int n, int nb, int nk,
                   Eigen::VectorXd* a, std::vector<Eigen::VectorXd>* b) {
  SubspaceOptions so;
  so.order = n;
  so.enforce_stability = true;
  so.feedthrough = nk == 0;
  so.input_delay = std::max(0, nk - 1);
  so.block_rows = std::max(10, n + 2);
  while (so.block_rows > n + 1 && y.size() - 2L * so.block_rows + 1 <= 2L * so.block_rows * (u.cols() + 1))
    --so.block_rows;
  SubspaceResult sr;
  try {
    sr = IdentifySubspace(MakeIoRecord(u, y, ts > 0 ? ts : 1.0), so);
  } catch (const std::invalid_argument&) {
    return false;
  }
  if (!sr.model.A.allFinite() || sr.model.Order() != n) return false;
  b->assign(u.cols(), Eigen::VectorXd::Zero(nb));
  for (int j = 0; j < u.cols(); ++j) {
    StateSpace channel = sr.model;
    channel.delay_s = 0.0;
    const TransferFunction tf = ToTransferFunction(channel, 0, j);
    Eigen::VectorXd num = Eigen::VectorXd::Zero(n + 1);
    num.tail(tf.num.size()) = tf.num;
    *a = tf.den / tf.den(0);
    num /= tf.den(0);
    // z^{−m} Σ β_k z^{n−k} / Σ a_k z^{n−k} = q^{−m} Σ β_k q^{−k} / A(q): b_i = β_{i + (nk ≥ 1)}.
    const int first = nk >= 1 ? 1 : 0;
    for (int i = 0; i < nb && first + i <= n; ++i) (*b)[j](i) = num(first + i);
  }
  return true;
}

Start FromDenominator(const std::string& name, const Layout& layout, const Eigen::VectorXd& a,
                      const std::vector<Eigen::VectorXd>& b, const PemOptions& options,
                      const Eigen::VectorXd& y, const Eigen::MatrixXd& u) {
  Start s;
  s.name = name;
  Polys& p = s.polys;
  p.b.assign(layout.nu, Eigen::VectorXd::Zero(layout.nb));
  for (int j = 0; j < layout.nu; ++j) {
    const int keep = std::min<int>(layout.nb, static_cast<int>(b[j].size()));
    p.b[j].head(keep) = b[j].head(keep);
  }
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(1);
  if (options.structure == PemStructure::kArmax) {
    p.a = StabilisedMonic(a, layout.na);
    p.c = StabilisedMonic(a, layout.nc);  // C = A: the output-error noise model
    p.d = one;
    p.f.assign(layout.nu, one);
  } else {
    p.a = one;
    p.f.assign(layout.nu, StabilisedMonic(a, layout.nf));
    p.c = one;
    p.d = one;
    if (options.structure == PemStructure::kBoxJenkins) {
      Eigen::VectorXd r = y;
      for (int j = 0; j < layout.nu; ++j)
        r -= FilterPolynomial(p.b[j], p.f[j], Shifted(u.col(j), layout.nk));
      NoiseModel(r, layout.nc, layout.nd, &p.c, &p.d);
    }
  }
  return s;
}

}  // namespace

std::vector<Start> MakeStarts(const Layout& layout, const Eigen::VectorXd& y, const Eigen::MatrixXd& u,
                              double sample_time, const PemOptions& options) {
  std::vector<Start> starts;
  const int n = options.structure == PemStructure::kArmax ? layout.na : layout.nf;
  if (options.steiglitz_mcbride_start || n == 0) {
    Eigen::VectorXd a;
    std::vector<Eigen::VectorXd> b;
    SteiglitzMcBride(y, u, n, layout.nb, layout.nk, &a, &b);
    starts.push_back(FromDenominator("steiglitz-mcbride", layout, a, b, options, y, u));
  }
  if (options.subspace_start && n > 0) {
    Eigen::VectorXd a;
    std::vector<Eigen::VectorXd> b;
    if (SubspacePolys(y, u, sample_time, n, layout.nb, layout.nk, &a, &b))
      starts.push_back(FromDenominator("subspace", layout, a, b, options, y, u));
  }
  if (options.structure == PemStructure::kArmax) {
    // Hannan–Rissanen: innovations from a long ARX, then A y = B u + C e by least squares.
    const int long_order = std::min<int>(std::max(20, 3 * layout.na), static_cast<int>(y.size() / (10 * (1 + layout.nu))));
    Eigen::VectorXd a_long;
    std::vector<Eigen::VectorXd> b_long;
    Regress(y, u, long_order, long_order, layout.nk, nullptr, 0, &a_long, &b_long, nullptr);
    Eigen::VectorXd e = FilterPolynomial(a_long, Eigen::VectorXd::Ones(1), y);
    for (int j = 0; j < layout.nu; ++j) e -= FilterPolynomial(b_long[j], Eigen::VectorXd::Ones(1), Shifted(u.col(j), layout.nk));
    Start s;
    s.name = "hannan-rissanen";
    Regress(y, u, layout.na, layout.nb, layout.nk, &e, layout.nc, &s.polys.a, &s.polys.b, &s.polys.c);
    s.polys.c = StabilisedMonic(s.polys.c, layout.nc);
    s.polys.d = Eigen::VectorXd::Ones(1);
    s.polys.f.assign(layout.nu, Eigen::VectorXd::Ones(1));
    starts.push_back(s);
  }
  return starts;
}

}  // namespace idrig::pem_internal
