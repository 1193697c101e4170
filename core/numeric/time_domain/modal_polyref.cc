// MIMO modal identification from impulse-response matrices, [Balda] (seed 002) section 5.
#include "core/numeric/time_domain/modal_polyref.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/numeric/validation.h"

namespace idrig {

namespace {

using cd = std::complex<double>;

[[noreturn]] void Fail(const std::string& what) { throw std::invalid_argument("modal-polyref: " + what); }

std::string Num(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

struct OrderSolution {
  Eigen::VectorXcd z;        // p·n eigenvalues of (49)
  Eigen::MatrixXcd vectors;  // eigenvectors E, stacked E_p; E_{p−1}; …; E_1 (47)
  double condition = 0.0;
};

// (43)–(49) at order p on Gs = G_1, G_2, … (paper numbering).
OrderSolution SolveOrder(const std::vector<Eigen::MatrixXd>& gs, int p, bool vectors) {
  const int m = static_cast<int>(gs[0].rows()), n = static_cast<int>(gs[0].cols());
  const int len = static_cast<int>(gs.size());
  const int blocks = len - p;  // block rows i = 0..len−p−1 of (43)
  Eigen::MatrixXd h(blocks * m, p * n), r(blocks * m, n);
  for (int i = 0; i < blocks; ++i) {
    for (int c = 0; c < p; ++c) h.block(i * m, c * n, m, n) = gs[p - 1 + i - c];  // G_{p+i−c}
    r.block(i * m, 0, m, n) = gs[p + i];                                          // G_{p+1+i}
  }
  OrderSolution out;
  const Eigen::VectorXd sv = Eigen::BDCSVD<Eigen::MatrixXd>(h).singularValues();
  out.condition = sv(sv.size() - 1) > 0 ? sv(0) / sv(sv.size() - 1) : std::numeric_limits<double>::infinity();
  // Eq. (44): F = −H⁺ R (minimum-norm least squares by complete orthogonal decomposition).
  const Eigen::MatrixXd f = -h.completeOrthogonalDecomposition().solve(r);
  // Eq. (47): block companion matrix with first block row −F_1^T … −F_p^T.
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(p * n, p * n);
  for (int k = 0; k < p; ++k) a.block(0, k * n, n, n) = -f.block(k * n, 0, n, n).transpose();
  if (p > 1) a.bottomLeftCorner((p - 1) * n, (p - 1) * n).setIdentity();
  Eigen::EigenSolver<Eigen::MatrixXd> eig(a, vectors);  // Eq. (49): A E = E Z
  out.z = eig.eigenvalues();
  if (vectors) out.vectors = eig.eigenvectors();
  return out;
}

struct Candidate {
  int index = 0;  // in OrderSolution::z
  cd s;
  double f_hz = 0.0, zeta = 0.0;
};

std::vector<Candidate> Candidates(const OrderSolution& sol, double fs, const ModalPolyrefOptions& o, double band_hz) {
  std::vector<Candidate> out;
  for (int i = 0; i < sol.z.size(); ++i) {
    const cd z = sol.z(i);
    if (std::abs(z) == 0.0) continue;
    const cd s = fs * std::log(z);  // Eq. (50)
    if (!(s.imag() > 0.0)) continue;
    Candidate c;
    c.index = i;
    c.s = s;
    c.f_hz = std::abs(s) / (2.0 * M_PI);
    c.zeta = -s.real() / std::abs(s);
    if (c.zeta <= 0.0 || c.zeta > o.max_damping || c.f_hz > band_hz) continue;
    out.push_back(c);
  }
  std::sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) { return a.f_hz < b.f_hz; });
  return out;
}

bool Matches(const Candidate& a, const Candidate& b, const ModalPolyrefOptions& o, bool check_damping) {
  if (std::abs(a.f_hz - b.f_hz) > o.frequency_tolerance * a.f_hz) return false;
  return !check_damping || std::abs(a.zeta - b.zeta) <= o.damping_tolerance * a.zeta + 0.001;
}

}  // namespace

double Mac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  const double num = std::norm(a.dot(b));  // dot() conjugates the first argument
  const double den = a.squaredNorm() * b.squaredNorm();
  return den > 0 ? num / den : 0.0;
}

ModalPolyrefResult IdentifyModalPolyref(const std::vector<Eigen::MatrixXd>& g, double sample_time,
                                        const ModalPolyrefOptions& options) {
  if (g.empty()) Fail("the impulse-response series is empty");
  if (!(sample_time > 0.0) || !std::isfinite(sample_time)) Fail("sample time must be positive");
  const int m = static_cast<int>(g[0].rows()), n = static_cast<int>(g[0].cols());
  if (m == 0 || n == 0) Fail("G(0) is empty (" + std::to_string(m) + "x" + std::to_string(n) + ")");
  for (size_t k = 0; k < g.size(); ++k) {
    if (g[k].rows() != m || g[k].cols() != n)
      Fail("inconsistent impulse-response matrix size: G(" + std::to_string(k) + "T) is " +
           std::to_string(g[k].rows()) + "x" + std::to_string(g[k].cols()) + " but G(0) is " + std::to_string(m) +
           "x" + std::to_string(n) + " (outputs x inputs)");
    if (!g[k].allFinite()) Fail("G(" + std::to_string(k) + "T) contains NaN or Inf");
  }
  if (options.first_sample < 0 || options.first_sample >= static_cast<int>(g.size()))
    Fail("first_sample must be in [0, N)");
  if (options.p < 0 || options.p_min < 1 || options.p_max < 0 || options.modes < 0)
    Fail("p, p_min, p_max and modes must be non-negative (p_min >= 1)");
  const std::vector<Eigen::MatrixXd> gs(g.begin() + options.first_sample, g.end());
  const int len = static_cast<int>(gs.size());
  // Largest p with at least as many equations as unknowns in (44): (len − p)·m >= p·n.
  const int p_limit = (len * m) / (m + n);
  ModalPolyrefResult result;
  result.sample_time = sample_time;
  result.outputs = m;
  result.inputs = n;
  result.samples = static_cast<int>(g.size());
  if (options.modes > 0) result.p_eq42 = (2 * options.modes + n - 1) / n;  // Eq. (42): p >= 2 n_f / n
  int p_max = options.p_max > 0 ? options.p_max : std::max(4 * result.p_eq42, 20);
  p_max = std::max(p_max, options.p);
  const int p_needed = std::max({options.p, result.p_eq42, options.p_min});
  if (p_needed > p_limit)
    Fail("too few samples for p = " + std::to_string(p_needed) + ": " + std::to_string(len) + " samples of a " +
         std::to_string(m) + "x" + std::to_string(n) + " response give at most p = " + std::to_string(p_limit) +
         " in (44)");
  if (p_max > p_limit) {
    result.warnings.push_back("p_max lowered from " + std::to_string(p_max) + " to " + std::to_string(p_limit) +
                              " (samples)");
    p_max = p_limit;
  }
  const int p_final = options.p > 0 ? options.p : p_max;
  const double fs = 1.0 / sample_time;
  const double band = options.max_frequency_hz > 0 ? options.max_frequency_hz : 0.5 * fs;

  // Stabilisation diagram over p.
  std::vector<std::vector<Candidate>> by_order(p_max + 1);
  OrderSolution final_solution;
  for (int p = options.p_min; p <= p_max; ++p) {
    const OrderSolution sol = SolveOrder(gs, p, p == p_final);
    by_order[p] = Candidates(sol, fs, options, band);
    if (p == p_final) final_solution = sol;
    for (const auto& c : by_order[p]) {
      StabilisationPoint pt;
      pt.p = p;
      pt.frequency_hz = c.f_hz;
      pt.damping_ratio = c.zeta;
      if (p > options.p_min)
        for (const auto& prev : by_order[p - 1]) {
          pt.stable_frequency |= Matches(c, prev, options, false);
          pt.stable |= Matches(c, prev, options, true);
        }
      result.stabilisation.push_back(pt);
    }
  }
  result.p = p_final;
  result.excitation_condition_number = final_solution.condition;
  result.eigenvalues_z = final_solution.z;

  // Physical modes: poles at p_final found (within the tolerances) at >= min_stable_orders orders.
  struct Pick {
    Candidate c;
    int orders = 0;
  };
  std::vector<Pick> picks;
  const int orders_in_diagram = p_max - options.p_min + 1;
  const int needed = std::min(orders_in_diagram,
                              std::max(options.min_stable_orders,
                                       static_cast<int>(std::ceil(options.min_stable_fraction * orders_in_diagram))));
  for (const auto& c : by_order[p_final]) {
    Pick pick{c, 1};
    for (int p = options.p_min; p <= p_max; ++p) {
      if (p == p_final) continue;
      for (const auto& other : by_order[p])
        if (Matches(c, other, options, true)) {
          ++pick.orders;
          break;
        }
    }
    if (pick.orders >= needed) picks.push_back(pick);
  }
  const bool none_stable = picks.empty();
  if (none_stable) {
    // Nothing persisted: keep every candidate pole at p_final so that a model still exists,
    // and say so (status ill-conditioned).
    for (const auto& c : by_order[p_final]) picks.push_back(Pick{c, 1});
    result.warnings.push_back("no pole persisted over " + std::to_string(needed) + " orders of the stabilisation "
                              "diagram; every candidate pole at p = " + std::to_string(p_final) +
                              " is kept (loosen frequency_tolerance/damping_tolerance or min_stable_fraction)");
  }
  if (options.modes > 0 && static_cast<int>(picks.size()) > options.modes) {
    std::stable_sort(picks.begin(), picks.end(), [](const Pick& a, const Pick& b) {
      return a.orders != b.orders ? a.orders > b.orders : a.c.zeta < b.c.zeta;
    });
    picks.resize(options.modes);
  }
  std::sort(picks.begin(), picks.end(), [](const Pick& a, const Pick& b) { return a.c.f_hz < b.c.f_hz; });
  if (options.modes > 0 && static_cast<int>(picks.size()) < options.modes)
    result.warnings.push_back("found " + std::to_string(picks.size()) + " stable modes, " +
                              std::to_string(options.modes) + " expected");

  // W by (51) and V by (52), with every mode and its conjugate.
  const int ne = 2 * static_cast<int>(picks.size());
  Eigen::VectorXcd z(ne);
  Eigen::MatrixXcd w(n, ne);
  for (size_t j = 0; j < picks.size(); ++j) {
    const int i = picks[j].c.index;
    const cd zj = final_solution.z(i);
    // Eq. (51): W = E_p [exp(p S T)]⁺; E_p is the top block of the eigenvector.
    const Eigen::VectorXcd wj = final_solution.vectors.col(i).head(n) / std::pow(zj, p_final);
    z(2 * j) = zj;
    z(2 * j + 1) = std::conj(zj);
    w.col(2 * j) = wj;
    w.col(2 * j + 1) = wj.conjugate();
  }
  Eigen::MatrixXcd v(m, ne);
  if (ne > 0) {
    Eigen::MatrixXd gt(len * n, m);  // transpose of [G_1 G_2 …]
    Eigen::MatrixXd gv(len * m, n);  // [G_1; G_2; …]
    for (int k = 0; k < len; ++k) {
      gt.block(k * n, 0, n, m) = gs[k].transpose();
      gv.block(k * m, 0, m, n) = gs[k];
    }
    Eigen::MatrixXcd rt(len * n, ne);  // transpose of [exp(kST) W^T]
    auto solve_v = [&] {
      // Eq. (52): V = [G_k] [exp(k S T) W^T]⁺ over all k (G_k = Σ_j v_j z_j^k w_j^T, k = 1, 2, …).
      for (int k = 0; k < len; ++k)
        for (int j = 0; j < ne; ++j) rt.block(k * n, j, n, 1) = std::pow(z(j), k + 1) * w.col(j);
      v = rt.completeOrthogonalDecomposition().solve(gt.cast<cd>()).transpose();
    };
    solve_v();
    // Optional alternating least squares (beyond the paper): W again from all G_k given V (the
    // transpose of (52)), then V; W of (51) rests on one eigenvector and is noise-sensitive.
    for (int it = 0; it < options.als_iterations; ++it) {
      Eigen::MatrixXcd mv(len * m, ne);
      for (int k = 0; k < len; ++k)
        for (int j = 0; j < ne; ++j) mv.block(k * m, j, m, 1) = std::pow(z(j), k + 1) * v.col(j);
      w = mv.completeOrthogonalDecomposition().solve(gv.cast<cd>()).transpose();
      solve_v();
    }
    // Fit of the modal model (38) to the impulse responses.
    const Eigen::MatrixXd model = (rt * v.transpose()).real();
    result.fit_percent_impulse = FitPercent(Eigen::Map<const Eigen::VectorXd>(gt.data(), gt.size()),
                                            Eigen::Map<const Eigen::VectorXd>(model.data(), model.size()))(0);
  }
  for (size_t j = 0; j < picks.size(); ++j) {
    Mode mode;
    mode.s = picks[j].c.s;
    mode.natural_frequency_rad_s = std::abs(mode.s);
    mode.natural_frequency_hz = picks[j].c.f_hz;
    mode.damping_ratio = picks[j].c.zeta;
    mode.orders_found = picks[j].orders;
    Eigen::VectorXcd shape = v.col(2 * j);
    Eigen::Index at = 0;
    shape.cwiseAbs().maxCoeff(&at);
    const cd scale = shape(at);
    mode.shape = shape / scale;
    mode.participation = w.col(2 * j) * scale;
    result.modes.push_back(mode);
  }
  const int nm = static_cast<int>(result.modes.size());
  result.mac = Eigen::MatrixXd::Zero(nm, nm);
  for (int i = 0; i < nm; ++i)
    for (int j = 0; j < nm; ++j) result.mac(i, j) = Mac(result.modes[i].shape, result.modes[j].shape);

  result.iterations = 1;
  result.fit_percent = result.fit_percent_impulse;
  result.status = nm == 0 ? SolverStatus::kFailed : (none_stable ? SolverStatus::kIllConditioned : SolverStatus::kOk);
  std::ostringstream msg;
  msg << nm << (none_stable ? " unconfirmed" : " stable") << " modes at p = " << p_final << " (stabilisation over p = " << options.p_min << ".." << p_max
      << "), condition number of (44) " << Num(result.excitation_condition_number);
  if (none_stable) msg << "; no pole persisted over " << needed << " orders";
  if (result.excitation_condition_number > 1e12 && nm > 0) {
    msg << "; (44) is rank deficient (p larger than needed): the minimum-norm solution was used";
  }
  result.message = msg.str();
  return result;
}

StateSpace ModalStateSpace(const ModalPolyrefResult& result, int first_sample) {
  const int nm = static_cast<int>(result.modes.size());
  const int m = result.outputs, n = result.inputs;
  StateSpace ss;
  ss.sample_time = result.sample_time;
  ss.A = Eigen::MatrixXd::Zero(2 * nm, 2 * nm);
  ss.B = Eigen::MatrixXd::Zero(2 * nm, n);
  ss.C = Eigen::MatrixXd::Zero(m, 2 * nm);
  ss.D = Eigen::MatrixXd::Zero(m, n);
  for (int j = 0; j < nm; ++j) {
    const Mode& mode = result.modes[j];
    const cd z = std::exp(mode.s * result.sample_time);
    // G(kT) = Σ v z^(k − first + 1) w^T + c.c. = C A^(k−1) B with β = z^(2 − first) w^T.
    const Eigen::VectorXcd beta = std::pow(z, 2 - first_sample) * mode.participation;
    ss.A.block(2 * j, 2 * j, 2, 2) << z.real(), -z.imag(), z.imag(), z.real();
    ss.B.row(2 * j) = beta.real().transpose();
    ss.B.row(2 * j + 1) = beta.imag().transpose();
    ss.C.col(2 * j) = 2.0 * mode.shape.real();
    ss.C.col(2 * j + 1) = -2.0 * mode.shape.imag();
  }
  return ss;
}

FirEstimate EstimateImpulseResponseFir(const IoRecord& record, int length, double lambda) {
  ValidateIoRecord(record, 2);
  const int n = record.NumSamples(), nu = record.NumInputs(), ny = record.NumOutputs();
  if (length < 2) Fail("FIR length must be at least 2");
  const int rows = n - length + 1;
  const int cols = nu * length;
  if (rows < 2 * cols)
    Fail("too few samples for an FIR of length " + std::to_string(length) + ": " + std::to_string(n) +
         " samples give " + std::to_string(rows) + " equations for " + std::to_string(cols) +
         " unknowns per output (need twice as many); shorten fir_length");
  Eigen::MatrixXd phi(rows, cols), y(rows, ny);
  for (int r = 0; r < rows; ++r) {
    const int t = r + length - 1;
    for (int k = 0; k < length; ++k) phi.block(r, k * nu, 1, nu) = record.u.row(t - k);
    y.row(r) = record.y.row(t);
  }
  const Eigen::MatrixXd p = phi.transpose() * phi;
  const Eigen::MatrixXd q = phi.transpose() * y;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(p);
  const Eigen::VectorXd d = eig.eigenvalues().cwiseMax(0.0);
  const Eigen::MatrixXd c = eig.eigenvectors().transpose() * q;
  const double yy = y.squaredNorm();
  FirEstimate out;
  out.condition_number = d(0) > 0 ? d(d.size() - 1) / d(0) : std::numeric_limits<double>::infinity();
  auto rss = [&](double l) {
    double value = yy;
    for (int i = 0; i < d.size(); ++i) value -= c.row(i).squaredNorm() * (2.0 / (d(i) + l) - d(i) / std::pow(d(i) + l, 2));
    return std::max(value, 0.0);
  };
  if (lambda > 0) {
    out.lambda = lambda;
    out.method = "FIR least squares, length " + std::to_string(length) + ", ridge lambda " + Num(lambda) + " (given)";
  } else {
    // Generalised cross-validation over a logarithmic grid.
    double best = std::numeric_limits<double>::infinity();
    const double top = d(d.size() - 1);
    for (int i = 0; i <= 80; ++i) {
      const double l = top * std::pow(10.0, -14.0 + 14.0 * i / 80.0);
      double dof = 0.0;
      for (int j = 0; j < d.size(); ++j) dof += d(j) / (d(j) + l);
      const double gcv = rss(l) / std::pow(std::max(1.0, rows - dof), 2);
      if (gcv < best) {
        best = gcv;
        out.lambda = l;
      }
    }
    out.method = "FIR least squares, length " + std::to_string(length) + ", ridge lambda " + Num(out.lambda) +
                 " by generalised cross-validation";
  }
  const Eigen::MatrixXd theta =
      eig.eigenvectors() * ((d.array() + out.lambda).inverse().matrix().asDiagonal() * c);
  out.impulse_responses.resize(length);
  for (int k = 0; k < length; ++k) out.impulse_responses[k] = theta.block(k * nu, 0, nu, ny).transpose();
  out.fit_percent = FitPercent(y, phi * theta).mean();
  return out;
}

}  // namespace idrig
