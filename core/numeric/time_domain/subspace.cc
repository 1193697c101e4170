#include "core/numeric/time_domain/subspace.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/numeric/validation.h"

namespace idrig {
namespace {

[[noreturn]] void Fail(const std::string& what) { throw std::invalid_argument("subspace: " + what); }

std::string Num(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

// u[k − m], zero before the record starts.
Eigen::MatrixXd Delayed(const Eigen::MatrixXd& u, int m) {
  if (m == 0) return u;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(u.rows(), u.cols());
  if (m < u.rows()) out.bottomRows(u.rows() - m) = u.topRows(u.rows() - m);
  return out;
}

// Gram matrix (1/j)·H Hᵀ of the block Hankel matrix of [VODM] (2.1)–(2.4) built from the
// channels of z (N×m), rows ordered as `rows` (channel, shift), j = N − 2i + 1 columns:
//   G[(a,k),(b,l)] = (1/j) Σ_{t=0}^{j−1} z_a(t+k) z_b(t+l).
// Only the first row and column of each 2i×2i lag table are dot products; the rest follow
// along diagonals: c(k+1,l+1) = c(k,l) + z_a(k+j) z_b(l+j) − z_a(k) z_b(l).
Eigen::MatrixXd HankelGram(const Eigen::MatrixXd& z, int shifts,
                           const std::vector<std::pair<int, int>>& rows) {
  const int m = static_cast<int>(z.cols());
  const long j = z.rows() - shifts + 1;
  // First row and column of every lag table at once: c_ab(0,l) = (Z_0ᵀ Z_l)_ab and
  // c_ab(k,0) = (Z_kᵀ Z_0)_ab with Z_k = z(k : k+j−1, :), m×m products over j samples.
  // In chunks of samples that stay in cache for all lags.
  std::vector<Eigen::MatrixXd> first_row(shifts, Eigen::MatrixXd::Zero(m, m)), first_col(shifts);
  constexpr long kChunk = 2048;
  for (long t0 = 0; t0 < j; t0 += kChunk) {
    const long len = std::min(kChunk, j - t0);
    const auto head = z.middleRows(t0, len);
    for (int l = 0; l < shifts; ++l) first_row[l].noalias() += head.transpose() * z.middleRows(t0 + l, len);
  }
  for (int l = 1; l < shifts; ++l) first_col[l] = first_row[l].transpose();  // Z_lᵀ Z_0 = (Z_0ᵀ Z_l)ᵀ
  std::vector<Eigen::MatrixXd> table(m * m);
  for (int a = 0; a < m; ++a) {
    for (int b = 0; b < m; ++b) {
      Eigen::MatrixXd c(shifts, shifts);
      const auto za = z.col(a), zb = z.col(b);
      for (int l = 0; l < shifts; ++l) c(0, l) = first_row[l](a, b);
      for (int k = 1; k < shifts; ++k) c(k, 0) = first_col[k](a, b);
      for (int k = 0; k + 1 < shifts; ++k)
        for (int l = 0; l + 1 < shifts; ++l)
          c(k + 1, l + 1) = c(k, l) + za(k + j) * zb(l + j) - za(k) * zb(l);
      table[a * m + b] = c / static_cast<double>(j);
    }
  }
  const int size = static_cast<int>(rows.size());
  Eigen::MatrixXd gram(size, size);
  for (int r = 0; r < size; ++r)
    for (int s = 0; s < size; ++s)
      gram(r, s) = table[rows[r].first * m + rows[s].first](rows[r].second, rows[s].second);
  return gram;
}

// Eigenvalues of A outside the unit circle reflected to 1/conj(λ) (kept below 1 − 1e-6): the
// magnitude of each mode's response shape is kept, only its growth is removed.
Eigen::MatrixXd ReflectUnstable(const Eigen::MatrixXd& a, bool* changed) {
  Eigen::EigenSolver<Eigen::MatrixXd> eig(a);
  Eigen::VectorXcd lambda = eig.eigenvalues();
  *changed = false;
  for (int k = 0; k < lambda.size(); ++k) {
    const double r = std::abs(lambda(k));
    if (r >= 1.0 - 1e-6) {
      lambda(k) = std::polar(std::min(1.0 / r, 1.0 - 1e-6), std::arg(lambda(k)));
      *changed = true;
    }
  }
  if (!*changed) return a;
  const Eigen::MatrixXcd v = eig.eigenvectors();
  return (v * lambda.asDiagonal() * v.inverse()).real();
}

double SpectralRadius(const Eigen::MatrixXd& a) {
  if (a.size() == 0) return 0.0;
  return Eigen::EigenSolver<Eigen::MatrixXd>(a, false).eigenvalues().cwiseAbs().maxCoeff();
}

void CheckInputs(const Eigen::MatrixXd& u, int shifts) {
  const int nu = static_cast<int>(u.cols());
  const Eigen::RowVectorXd mean = u.colwise().mean();
  const Eigen::MatrixXd centred = u.rowwise() - mean;
  for (int q = 0; q < nu; ++q) {
    const double spread = centred.col(q).cwiseAbs().maxCoeff();
    if (!(spread > 1e-12 * std::max(1.0, std::abs(mean(q)))))
      Fail("input " + std::to_string(q + 1) + " is constant (" + Num(u(0, q)) +
           "): it is not persistently exciting, so its dynamics cannot be identified");
  }
  if (nu > 1) {
    // Correlation matrix of the centred inputs: singular when one input is a combination of
    // the others (e.g. two identical inputs).
    Eigen::MatrixXd cov = centred.transpose() * centred;
    const Eigen::VectorXd scale = cov.diagonal().cwiseSqrt().cwiseInverse();
    cov = scale.asDiagonal() * cov * scale.asDiagonal();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
    if (eig.eigenvalues()(0) < 1e-10 * eig.eigenvalues()(nu - 1)) {
      const Eigen::VectorXd v = eig.eigenvectors().col(0);
      std::string which;
      for (int q = 0; q < nu; ++q)
        if (std::abs(v(q)) > 0.1) which += (which.empty() ? "" : ", ") + std::to_string(q + 1);
      Fail("the inputs are linearly dependent (inputs " + which +
           " are a combination of each other, e.g. identical): the input matrix is rank "
           "deficient, so their effects cannot be told apart");
    }
  }
  (void)shifts;
}

}  // namespace

const char* ToString(SubspaceWeighting weighting) {
  switch (weighting) {
    case SubspaceWeighting::kMoesp: return "moesp";
    case SubspaceWeighting::kN4sid: return "n4sid";
    case SubspaceWeighting::kCva: return "cva";
  }
  return "?";
}

SubspaceWeighting ParseSubspaceWeighting(const std::string& name) {
  if (name == "moesp") return SubspaceWeighting::kMoesp;
  if (name == "n4sid") return SubspaceWeighting::kN4sid;
  if (name == "cva") return SubspaceWeighting::kCva;
  throw std::invalid_argument("subspace: weighting '" + name + "' is not moesp, n4sid or cva");
}

Eigen::MatrixXd SimulateFrom(const StateSpace& model, const Eigen::MatrixXd& u,
                             const Eigen::VectorXd& x0) {
  const int m = model.sample_time > 0 ? static_cast<int>(std::lround(model.delay_s / model.sample_time)) : 0;
  const Eigen::MatrixXd ud = Delayed(u, m);
  const int n = model.Order();
  Eigen::VectorXd x = x0.size() == n ? x0 : Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd y(u.rows(), model.NumOutputs());
  Eigen::VectorXd next(n);
  for (long k = 0; k < u.rows(); ++k) {
    y.row(k) = (model.C.lazyProduct(x) + model.D.lazyProduct(ud.row(k).transpose())).transpose();
    next.noalias() = model.A.lazyProduct(x) + model.B.lazyProduct(ud.row(k).transpose());
    x.swap(next);
  }
  return y;
}

Eigen::VectorXd EstimateInputMatrices(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
                                      bool feedthrough, bool estimate_x0, StateSpace* model,
                                      Eigen::MatrixXd* covariance) {
  const int n = static_cast<int>(model->A.rows());
  const int nu = static_cast<int>(u.cols()), ny = static_cast<int>(y.cols());
  const long samples = u.rows();
  const int pb = n * nu, pd = feedthrough ? ny * nu : 0, px = estimate_x0 ? n : 0;
  const int p = pb + pd + px;
  // Row recursions ([VV] Eq. (9.47)): ρ_rq[k+1] = ρ_rq[k] A + c_r u_q[k] gives the regressor
  // of B(:,q) in output r; σ_r[k+1] = σ_r[k] A, σ_r[0] = c_r, that of x0.
  const int nrec = ny * nu + ny;
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(nrec, n), wnext(nrec, n);
  if (estimate_x0) w.bottomRows(ny) = model->C;
  // Regressors are the columns of Φᵀ (contiguous), reduced to ΦᵀΦ in blocks.
  constexpr int kBlock = 256;
  // Rows of Φᵀ: [vec B | vec D | target | x0], so one rank update gives ΦᵀΦ, Φᵀy and yᵀy;
  // once the free response has decayed, the x0 rows are zero and only the leading corner
  // is updated.
  const int q_target = pb + pd, rows = p + 1;
  Eigen::MatrixXd phi_t = Eigen::MatrixXd::Zero(rows, kBlock * ny), full = Eigen::MatrixXd::Zero(rows, rows);
  int filled = 0;
  bool x0_alive = estimate_x0, block_has_x0 = estimate_x0;
  const double c_scale = std::max(model->C.cwiseAbs().maxCoeff(), std::numeric_limits<double>::min());
  auto flush = [&] {
    if (filled == 0) return;
    if (block_has_x0) full.selfadjointView<Eigen::Lower>().rankUpdate(phi_t.leftCols(filled));
    else full.topLeftCorner(q_target + 1, q_target + 1).selfadjointView<Eigen::Lower>().rankUpdate(
             phi_t.topLeftCorner(q_target + 1, filled));
    block_has_x0 = x0_alive;
    filled = 0;
  };
  const int live = ny * nu;  // recursions ρ_rq; the last ny rows of w are σ_r
  for (long k = 0; k < samples; ++k) {
    for (int r = 0; r < ny; ++r) {
      auto col = phi_t.col(filled);
      for (int q = 0; q < nu; ++q) col.segment(q * n, n) = w.row(r * nu + q).transpose();
      if (feedthrough) {
        col.segment(pb, pd).setZero();
        for (int q = 0; q < nu; ++q) col(pb + q * ny + r) = u(k, q);
      }
      col(q_target) = y(k, r);
      if (x0_alive) col.segment(q_target + 1, n) = w.row(live + r).transpose();
      else if (estimate_x0) col.segment(q_target + 1, n).setZero();
      ++filled;
    }
    if (filled + ny > phi_t.cols()) flush();
    if (x0_alive) wnext.noalias() = w.lazyProduct(model->A);  // small: no GEMM blocking per sample
    else wnext.topRows(live).noalias() = w.topRows(live).lazyProduct(model->A);
    for (int r = 0; r < ny; ++r)
      for (int q = 0; q < nu; ++q) wnext.row(r * nu + q) += model->C.row(r) * u(k, q);
    w.swap(wnext);
    // The free response C A^k decays: zero it before it turns denormal (denormal arithmetic
    // is two orders of magnitude slower).
    if (x0_alive && w.bottomRows(ny).cwiseAbs().maxCoeff() < 1e-150 * c_scale) {
      w.bottomRows(ny).setZero();
      wnext.bottomRows(ny).setZero();
      x0_alive = false;
    }
  }
  flush();
  full.triangularView<Eigen::StrictlyUpper>() = full.transpose();
  std::vector<int> order;  // θ = (vec B, vec D, x0) in `full`
  for (int i = 0; i < rows; ++i)
    if (i != q_target) order.push_back(i);
  Eigen::MatrixXd gram(p, p);
  Eigen::VectorXd rhs(p);
  for (int a = 0; a < p; ++a) {
    rhs(a) = full(order[a], q_target);
    for (int b = 0; b < p; ++b) gram(a, b) = full(order[a], order[b]);
  }
  const double yy = full(q_target, q_target);
  // Column-equilibrated pseudo-inverse (x0 is poorly determined when A decays fast).
  Eigen::VectorXd scale = gram.diagonal().cwiseMax(std::numeric_limits<double>::min()).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = scale.asDiagonal() * gram * scale.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
  const Eigen::VectorXd lam = eig.eigenvalues();
  Eigen::VectorXd inv_lam(p);
  for (int i = 0; i < p; ++i) inv_lam(i) = lam(i) > 1e-13 * lam(p - 1) ? 1.0 / lam(i) : 0.0;
  const Eigen::MatrixXd pinv =
      scale.asDiagonal() * eig.eigenvectors() * inv_lam.asDiagonal() * eig.eigenvectors().transpose() * scale.asDiagonal();
  const Eigen::VectorXd theta = pinv * rhs;
  model->B = Eigen::Map<const Eigen::MatrixXd>(theta.data(), n, nu);
  model->D = feedthrough ? Eigen::MatrixXd(Eigen::Map<const Eigen::MatrixXd>(theta.data() + pb, ny, nu))
                         : Eigen::MatrixXd::Zero(ny, nu);
  if (covariance) {
    const double rss = std::max(0.0, yy - 2.0 * theta.dot(rhs) + theta.dot(gram * theta));
    const double dof = std::max(1.0, static_cast<double>(samples * ny - p));
    *covariance = (rss / dof) * pinv;
  }
  return estimate_x0 ? Eigen::VectorXd(theta.tail(n)) : Eigen::VectorXd::Zero(n);
}

SubspaceResult IdentifySubspace(const IoRecord& record, const SubspaceOptions& options) {
  const int nu = record.NumInputs(), ny = record.NumOutputs();
  if (nu < 1) Fail("the record has no input column; subspace identification needs at least one input");
  if (ny < 1) Fail("the record has no output column");
  if (record.u.rows() != record.y.rows())
    Fail("inputs have " + std::to_string(record.u.rows()) + " rows but outputs " + std::to_string(record.y.rows()));
  ValidateIoRecord(record, 2);
  if (options.order < 0) Fail("order must be >= 1 (or 0: chosen from the singular values)");
  if (options.max_order < 1) Fail("max_order must be >= 1");
  if (options.input_delay < 0) Fail("input_delay must be >= 0 samples");
  if (options.block_rows < 0) Fail("block_rows must be >= 1 (or 0: automatic)");
  const int n_max = options.order > 0 ? options.order : options.max_order;
  const long samples = record.NumSamples();
  const int m = nu + ny;
  // j = N − 2i + 1 columns must exceed the 2i·m rows for the Gram matrix to be of full rank.
  auto fits = [&](int i) { return samples - 2L * i + 1 > 2L * i * m; };
  const int i_min = (n_max + ny - 1) / ny + 1;  // (i−1)·ny >= n for the shift of Γ_i
  int i = options.block_rows;
  if (i == 0) {
    i = std::max(10, (3 * (n_max + 1) + 2 * ny - 1) / (2 * ny));
    while (i > i_min && !fits(i)) --i;
  }
  if (i < i_min)
    Fail("block_rows i = " + std::to_string(i) + " is too small for order " + std::to_string(n_max) +
         " with " + std::to_string(ny) + " output(s): (i-1)*ny must be >= n, use i >= " + std::to_string(i_min));
  if (!fits(i))
    Fail("too few samples for the block rows: i = " + std::to_string(i) + " block rows with " +
         std::to_string(nu) + " input(s) and " + std::to_string(ny) + " output(s) need N - 2i + 1 > 2i(nu+ny), i.e. N >= " +
         std::to_string(2L * i * m + 2L * i) + " samples; the record has " + std::to_string(samples) +
         (options.block_rows > 0 ? " (lower block_rows or the order)" : " (lower the order)"));
  CheckInputs(record.u, 2 * i);

  SubspaceResult result;
  result.block_rows = i;
  const Eigen::MatrixXd ud = Delayed(record.u, options.input_delay);
  // Channels scaled to unit RMS, so that no channel dominates the weighting.
  Eigen::MatrixXd z(samples, m);
  z << ud, record.y;
  Eigen::VectorXd scale = (z.colwise().squaredNorm() / static_cast<double>(samples)).cwiseSqrt().transpose();
  for (int c = 0; c < m; ++c) {
    if (!(scale(c) > 0.0)) scale(c) = 1.0;
    z.col(c) /= scale(c);
  }
  // Row order [U_f; W_p; Y_f] with W_p = [U_p; Y_p] ([Verhaegen], PO-MOESP).
  std::vector<std::pair<int, int>> rows;
  for (int k = i; k < 2 * i; ++k) for (int a = 0; a < nu; ++a) rows.push_back({a, k});
  for (int k = 0; k < i; ++k) for (int a = 0; a < nu; ++a) rows.push_back({a, k});
  for (int k = 0; k < i; ++k) for (int b = 0; b < ny; ++b) rows.push_back({nu + b, k});
  for (int k = i; k < 2 * i; ++k) for (int b = 0; b < ny; ++b) rows.push_back({nu + b, k});
  Eigen::MatrixXd gram = HankelGram(z, 2 * i, rows);
  const int uf = i * nu, wp = i * m, yf = i * ny;
  bool weakly_exciting = false;
  {
    // Persistent excitation of order 2i: the input block of the Gram matrix should be regular.
    // A very smooth or few-line input fails this numerically; the factorisation below is then
    // regularised and the result flagged (constant or dependent inputs were refused above).
    const Eigen::MatrixXd gu = gram.topLeftCorner(2 * uf, 2 * uf);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gu, Eigen::EigenvaluesOnly);
    const double ratio = eig.eigenvalues()(0) / eig.eigenvalues()(2 * uf - 1);
    if (ratio < 1e-11) {
      weakly_exciting = true;
      result.warnings.push_back("the input is not persistently exciting of order 2i = " + std::to_string(2 * i) +
                                " (its block Hankel matrix has condition " + Num(1.0 / std::max(ratio, 1e-300)) +
                                ", e.g. too few sine lines or a very smooth input): the estimate rests on a "
                                "regularised factorisation; use a richer input or fewer block_rows");
    }
  }
  // LQ factor H = L Qᵀ from the Cholesky factor of H Hᵀ (a tiny jitter if H is rank
  // deficient, e.g. noise-free data).
  Eigen::LLT<Eigen::MatrixXd> llt(gram);
  double jitter = 1e-13 * gram.trace() / gram.rows();
  while (llt.info() != Eigen::Success && jitter < 1e-3 * gram.trace()) {
    llt.compute(gram + jitter * Eigen::MatrixXd::Identity(gram.rows(), gram.cols()));
    jitter *= 100.0;
  }
  if (llt.info() != Eigen::Success) Fail("the block Hankel matrix is numerically singular");
  const Eigen::MatrixXd l = llt.matrixL();
  const Eigen::MatrixXd l21 = l.block(uf, 0, wp, uf), l22 = l.block(uf, uf, wp, wp);
  const Eigen::MatrixXd l32 = l.block(uf + wp, uf, yf, wp), l33 = l.block(uf + wp, uf + wp, yf, yf);

  // Weighted oblique projection W1 O_i W2 ([VODM] Theorem 2 and Table 3.1).
  Eigen::MatrixXd weighted, w1_inverse = Eigen::MatrixXd::Identity(yf, yf);
  switch (options.weighting) {
    case SubspaceWeighting::kMoesp:  // W1 = I, W2 = Π_{U_f⊥}: O_i Π = L32 Q2ᵀ
      weighted = l32;
      break;
    case SubspaceWeighting::kN4sid: {  // W1 = W2 = I: O_i = L32 L22⁻¹ W_p = L32 L22⁻¹ [L21 L22] Qᵀ
      weighted.resize(yf, uf + wp);
      weighted.leftCols(uf) = l32 * l22.triangularView<Eigen::Lower>().solve(l21);
      weighted.rightCols(wp) = l32;
      break;
    }
    case SubspaceWeighting::kCva: {  // W1 = (Y_f Π_{U_f⊥} Y_fᵀ)^(−1/2) = (L32 L32ᵀ + L33 L33ᵀ)^(−1/2)
      const Eigen::MatrixXd s = l32 * l32.transpose() + l33 * l33.transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(s);
      const Eigen::VectorXd lam = eig.eigenvalues().cwiseMax(1e-14 * eig.eigenvalues().maxCoeff());
      const Eigen::MatrixXd& v = eig.eigenvectors();
      weighted = v * lam.cwiseSqrt().cwiseInverse().asDiagonal() * v.transpose() * l32;
      w1_inverse = v * lam.cwiseSqrt().asDiagonal() * v.transpose();
      break;
    }
  }
  Eigen::BDCSVD<Eigen::MatrixXd> svd(weighted, Eigen::ComputeThinU);
  result.singular_values = svd.singularValues();
  const Eigen::VectorXd& sv = result.singular_values;
  const int usable = std::min<int>(n_max, (i - 1) * ny);
  int n = options.order;
  if (n > (i - 1) * ny)
    Fail("order " + std::to_string(n) + " needs (i-1)*ny >= n; raise block_rows to " + std::to_string(n / ny + 1));
  if (n == 0) {
    double best = -1.0;
    for (int k = 1; k <= usable && k < sv.size(); ++k) {
      const double ratio = sv(k) > 0 ? sv(k - 1) / sv(k) : std::numeric_limits<double>::infinity();
      if (ratio > best) { best = ratio; n = k; }
    }
    result.order_rule = "largest singular-value gap";
  } else {
    result.order_rule = "user";
  }
  result.order = n;
  result.gap = n < sv.size() && sv(n) > 0 ? sv(n - 1) / sv(n) : std::numeric_limits<double>::infinity();

  // Γ_i = W1⁻¹ U_n S_n^(1/2); C from its first block row, A from its shift invariance
  // ([VODM] Eq. (4.16)): Γ_up A = Γ_down in the least-squares sense.
  const Eigen::MatrixXd gamma =
      w1_inverse * svd.matrixU().leftCols(n) * sv.head(n).cwiseSqrt().asDiagonal();
  const Eigen::MatrixXd gamma_up = gamma.topRows((i - 1) * ny), gamma_down = gamma.bottomRows((i - 1) * ny);
  StateSpace& model = result.model;
  model.sample_time = record.sample_time;
  model.delay_s = options.input_delay * record.sample_time;
  model.A = gamma_up.completeOrthogonalDecomposition().solve(gamma_down);
  model.C = scale.tail(ny).asDiagonal() * gamma.topRows(ny);
  if (options.enforce_stability) model.A = ReflectUnstable(model.A, &result.stabilised);
  if (result.stabilised)
    result.warnings.push_back("eigenvalues of A outside the unit circle were reflected inside (enforce_stability)");

  // B, D, x0 by least squares on the output ([VV] Eq. (9.47)), on the original scale.
  result.initial_state = EstimateInputMatrices(ud, record.y, options.feedthrough, options.estimate_initial_state,
                                               &model, &result.parameter_covariance);
  StateSpace undelayed = model;
  undelayed.delay_s = 0.0;
  const Eigen::MatrixXd sim = SimulateFrom(undelayed, ud, result.initial_state);
  result.fit_per_output = FitPercent(record.y, sim);
  result.fit_percent = result.fit_per_output.mean();
  result.final_cost = (record.y - sim).squaredNorm();
  result.spectral_radius = SpectralRadius(model.A);
  result.iterations = 1;
  std::ostringstream msg;
  msg << ToString(options.weighting) << ", order " << n << " (" << result.order_rule << ", s_n/s_n+1 = "
      << Num(result.gap) << "), " << i << " block rows, fit " << Num(result.fit_percent) << " %";
  if (!model.A.allFinite() || !model.B.allFinite() || !sim.allFinite()) {
    result.status = SolverStatus::kFailed;
    msg << "; the estimate is not finite";
  } else if (result.spectral_radius >= 1.0) {
    result.status = SolverStatus::kFailed;
    msg << "; the model is unstable (spectral radius " << Num(result.spectral_radius)
        << "): set enforce_stability=true or lower the order";
    result.warnings.push_back("unstable model");
  } else if (weakly_exciting) {
    result.status = SolverStatus::kIllConditioned;
    msg << "; the input is not persistently exciting of order 2i = " << 2 * i;
  } else {
    result.status = SolverStatus::kOk;
  }
  result.message = msg.str();
  return result;
}

}  // namespace idrig
