// Step-response identification with multiple complex poles, [Vidinčev] (seed 000): residues (20)/(23), (32)–(35) or by least squares; the step response (5) and K(p) (1).
#include "core/numeric/time_domain/step_prony_internal.h"

#include <algorithm>
#include <cmath>

namespace idrig {
namespace step_prony_detail {

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

using CPoly = std::vector<cd>;  // ascending powers
CPoly Mul(const CPoly& a, const CPoly& b) {
  CPoly out(a.size() + b.size() - 1, 0.0);
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j) out[i + j] += a[i] * b[j];
  return out;
}

// Distinct roots of (18) in a structure (a complex pair counts twice).
size_t DistinctRoots(const std::vector<StepPole>& poles) {
  size_t n = 0;
  for (const auto& p : poles) n += p.complex_pair ? 2 : 1;
  return n;
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

}  // namespace step_prony_detail

using step_prony_detail::cd;
using step_prony_detail::CPoly;
using step_prony_detail::Mul;
using step_prony_detail::StepBasis;

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

}  // namespace idrig
