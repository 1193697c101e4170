#pragma once
// Internal to step-Prony (seed 000): the pieces shared by its four parts. Not a public API.
//   step_prony_prediction.cc  linear prediction (10)–(19): the LP system (20)/(30), roots (18), b (16)
//   step_prony_averaging.cc   block averaging (25)–(35): the sequence w_α the LP and residues work on
//   step_prony_residues.cc    residues (20)/(23), (32)–(35) or least squares; response (5), K(p) (1)
//   step_prony_refine.cc      variable-projection refinement of the LP poles (beyond the paper)
//   step_prony_order.cc       the driver: x(∞) (6), spacing h (9), order (36)–(41), multiplicities
#include <complex>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/numeric/time_domain/step_prony.h"

namespace idrig::step_prony_detail {

using cd = std::complex<double>;

inline std::string Num(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

// How samples are turned into the LP sequence w_α: point values x̄(αh), block means (25) or
// interval integrals. `spacing` samples per h, `blocks` sub-intervals (spacing % blocks == 0).
struct Grid {
  int spacing = 1, blocks = 1;
  StepAveraging averaging = StepAveraging::kNone;
  double sample_time = 1.0;

  // Samples beyond the start sample that one value needs.
  int Extent() const;
  int Points(int n) const { return (n - 1 - Extent()) / spacing + 1; }  // values at α = 0, h, 2h, …
  // The value starting at sample `base` (α h = base·Ts); Vec is Eigen::VectorXd or VectorXcd.
  template <typename Vec>
  typename Vec::Scalar ReduceAt(const Vec& v, int base) const;
  template <typename Vec>
  typename Vec::Scalar Reduce(const Vec& v, int alpha) const { return ReduceAt(v, alpha * spacing); }
  // Samples needed for the first `points` values.
  int SamplesFor(int points) const;
};

// ---- prediction (step_prony_prediction.cc) ----
Eigen::MatrixXd LpRows(const Eigen::VectorXd& w, int m, int spacing, const std::vector<int>& starts);
double Condition(const Eigen::MatrixXd& a);
struct LpSolution {
  Eigen::VectorXd d;       // D_1 … D_m
  Eigen::VectorXcd roots;  // of (18)
  double cond = 0.0;
};
LpSolution SolveLp(const Eigen::VectorXd& w, int m, int spacing, const std::vector<int>& starts,
                   StepLpSolver solver, int columns);
std::vector<StepPole> ClusterRoots(const Eigen::VectorXcd& z, double tau, double h,
                                   std::vector<std::string>* warnings);

// ---- residues (step_prony_residues.cc) ----
size_t DistinctRoots(const std::vector<StepPole>& poles);
double FitResiduesLs(const Eigen::VectorXd& x, const Eigen::VectorXd& t, double c,
                     std::vector<StepPole>* poles, double* cond);
void FitResiduesEq20(const Eigen::VectorXd& w, const Eigen::VectorXd& t, double c, const Grid& grid,
                     std::vector<StepPole>* poles, double* cond);
double Rss(const std::vector<StepPole>& poles, bool ls, double c, const Eigen::VectorXd& t,
           const Eigen::VectorXd& x);

// ---- refinement (step_prony_refine.cc) ----
// b per root (conjugates included) refined on all samples; LM iterations in *iterations.
Eigen::VectorXcd RefineRoots(const Eigen::VectorXcd& b_in, const Eigen::VectorXd& t, const Eigen::VectorXd& x,
                             int* iterations);
// Number of real parameters b of a structure (a complex pair counts twice).
int StructureParameters(const std::vector<StepPole>& poles);
// The b of a fixed multiplicity structure by variable projection; returns Σ (x − x̂)².
double RefineStructure(std::vector<StepPole>* poles, const Eigen::VectorXd& t, const Eigen::VectorXd& x, double c,
                       int* iterations);

}  // namespace idrig::step_prony_detail
