#pragma once
// Shared declarations of the gap diagnosis' parts (internal to core/numeric/gap):
// candidate_fit.cc (one candidate's model and its output-error fit), ranking.cc (likelihood-ratio
// tests, validation BIC, signature, eligibility and weights), gap_report.cc (data checks, the
// verdict and DiagnoseGap itself). Not a public interface.
#include <Eigen/Dense>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/numeric/gap/gap_diagnosis.h"

namespace idrig::gap_detail {

[[noreturn]] void Fail(const std::string& message);

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

double Quantile(std::vector<double> v, double p);

struct Scales {
  double ts = 1, slow = 1, u_max = 1, y_max = 1;
  double lag_of_best_match = 0;  // [s] shift of G0's output that best matches y (cross-correlation)
  double u_quantile[5] = {0, 0, 0, 0, 0};  // 2, 15, 50, 85, 98 %
  double y_quantile[4] = {0, 0, 0, 0};     // 0.5, 2, 98, 99.5 %
};

// One candidate: the plant's free coefficients θ (log multipliers) and the effect's φ.
class Candidate {
 public:
  Candidate(const TransferFunction& base, EffectKind kind, bool fit_plant, const Scales& scales,
            int substeps, std::vector<double> fixed = {});

  static int NumEffectParams(EffectKind kind, const std::vector<double>& fixed);

  int PlantParams() const {
    return static_cast<int>(free_den_.size() + free_num_.size()) + (gain_only_ ? 1 : 0);
  }
  // Only the plant's gain moves (one multiplier on num): a gap that is a pure gain change.
  void SetGainOnly() {
    free_den_.clear();
    free_num_.clear();
    gain_only_ = true;
  }
  int EffectParams() const { return effect_params_; }
  int Size() const { return PlantParams() + EffectParams(); }

  TransferFunction Plant(const Eigen::VectorXd& x) const;
  // φ → physical parameters, in EffectParameterNames order.
  Effect EffectOf(const Eigen::VectorXd& x) const;
  // Inverse of EffectOf for the effect part, for starting points given in physical units.
  Eigen::VectorXd Phi(const std::vector<double>& p) const;
  Eigen::VectorXd Simulate(const Eigen::VectorXd& x, const GapRecord& record) const;

  EffectKind kind() const { return kind_; }

 private:
  TransferFunction base_;
  EffectKind kind_;
  Scales scales_;
  int substeps_;
  std::vector<double> fixed_;
  std::vector<int> free_den_, free_num_;
  bool gain_only_ = false;
  int effect_params_ = 0;
};

// Residuals y − ŷ over the scored samples of every record, as one vector.
struct Residuals {
  const Candidate* candidate;
  const std::vector<GapRecord>* records;
  long count = 0;
  void operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const;
};

struct LmFunctor {
  using Scalar = double;
  enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;
  Residuals residuals;
  int n_inputs = 0;
  int* calls = nullptr;
  int inputs() const { return n_inputs; }
  int values() const { return static_cast<int>(residuals.count); }
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& f) const {
    ++*calls;
    residuals(x, f);
    return 0;
  }
};

double Mse(const Residuals& residuals, const Eigen::VectorXd& x);

struct FitOutcome {
  Eigen::VectorXd x;
  double mse = kNan;
  int evaluations = 0;
  bool converged = false;
};

FitOutcome Minimise(const Residuals& residuals, Eigen::VectorXd x, int max_evaluations);

// Starting points (physical units) for each effect, from the data's scales.
std::vector<std::vector<double>> Starts(EffectKind kind, const Scales& s);

// Candidate quantisation step from the samples' lattice; *strength = its mean resultant length.
double QuantisationStep(const std::vector<GapRecord>& records, double* strength);

// Every sample within 2 % of the range from the minimum or the maximum.
bool BinaryInput(const std::vector<GapRecord>& records);

double Correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b);

// Simulation over the scored samples of every record, concatenated.
Eigen::VectorXd Stack(const std::vector<GapRecord>& records,
                      const std::function<Eigen::VectorXd(const GapRecord&)>& f);

// A fitted candidate with its validation simulation (concatenated scored samples).
struct CandidateWork {
  CandidateFit fit;
  Eigen::VectorXd y_val;
};

// Everything the candidates share: the data, the scales, G0 and its refit.
struct FitContext {
  const TransferFunction* g0 = nullptr;
  const std::vector<GapRecord>* estimation = nullptr;
  const std::vector<GapRecord>* validation = nullptr;
  const GapOptions* options = nullptr;
  Scales scales;
  long n_est = 0, n_val = 0;
  Eigen::VectorXd y_val, y0_val, y_refit_val;  // measured, G0, refitted G0 on validation
  double as_is_mse = 0;                         // G0 on estimation
  FitOutcome refit_fit;                         // refitted G0 (parameter_mismatch)
  int refit_size = 0;
  double q_step = 0, q_strength = 0;
  int k_effects = 1;                            // effects tested (Bonferroni)
};

// Fits one effect (not none, not parameter_mismatch) from its starts: fills effect, plant,
// parameters, estimation_mse, param_std, evaluations, note and the validation simulation.
void FitEffect(const FitContext& ctx, EffectKind kind, CandidateWork& w);

// ranking.cc: the likelihood-ratio test, validation MSE/NRMSE/BIC and signature of one fitted
// candidate; then eligibility, ordering and BIC weights over all of them (best first).
void ScoreCandidate(const FitContext& ctx, CandidateWork& w);
std::vector<CandidateFit> RankCandidates(std::vector<CandidateWork> work, const GapOptions& options);

}  // namespace idrig::gap_detail
