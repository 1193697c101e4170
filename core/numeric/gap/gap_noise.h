#pragma once
// Evidence about the records that needs no candidate model: the noise floor, the period of a
// periodic excitation, the even/odd detection lines of an odd multisine (gap_lines.cc) and the
// lattice a quantised output sits on (gap_lattice.cc). All Eigen-only and I/O-free.
#include <Eigen/Dense>
#include <string>
#include <vector>

namespace idrig {

struct GapRecord;

// A record whose input repeats: u(k + P) ≈ u(k) over the whole record (RMS of the difference
// ≤ 2 % of RMS(u)), at least two full periods. period = 0: not periodic.
struct Periodicity {
  int period = 0;    // samples
  int periods = 0;   // full periods in the record
};
Periodicity FindPeriod(const Eigen::VectorXd& u, int min_period = 8);

// The output noise level, estimated without any candidate of the diagnosis.
//  - "periods": the input is periodic in at least one record — the sample variance of y across
//    periods, pooled over the samples of a period and the periodic records (the first period is
//    dropped as the transient when there are three or more). Exact for any noise colour: what
//    repeats is the system's response, linear or not; what does not is noise.
//  - "arx_prediction": otherwise — a high-order ARX(n, n+1) predictor with a constant, fitted by
//    least squares on the estimation records for n = 4, 8, 16, 32, … (≤ N_est/20), its one-step
//    prediction errors ε taken on the validation records (scored samples), and
//    σ̂² = mean(ε²)/Σ a_i² (a_0 = 1, the fitted AR coefficients). For y = G u + v + e with white e:
//    ε = A(q)e + (model error), the two independent, so σ̂² ≥ σ_e², with equality when the
//    predictor captures everything else; the order with the smallest σ̂² is kept. Coloured
//    noise is partly predictable and then reads below its simulation floor.
struct NoiseFloor {
  std::string method;          // "periods" or "arx_prediction"
  double sigma = 0;            // [units of y]
  int period = 0, periods = 0; // periods method
  int order = 0;               // arx_prediction: n
  double ar_gain = 1;          // arx_prediction: Σ a_i² of the kept predictor
  long samples = 0;            // samples behind the estimate
};
// Throws std::invalid_argument when the records are too short for even the lowest order.
NoiseFloor EstimateNoiseFloor(const std::vector<GapRecord>& estimation,
                              const std::vector<GapRecord>& validation);

struct GapVerdict;
// The verdict's figures against an independent floor (all NRMSE on the validation records):
// shrink = (before − after)/(before − floor) (0 when before ≤ floor: nothing to explain),
// remaining_gap_to_noise = after − floor, below_noise_floor = after < floor (then shrink may
// exceed 1: the floor is an upper bound that the model beat, or the noise is coloured).
void ApplyNoiseFloor(double floor_nrmse, GapVerdict& verdict);

}  // namespace idrig
