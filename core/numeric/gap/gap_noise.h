#pragma once
// Evidence about the records that needs no candidate model: the noise floor, the period of a
// periodic excitation, the even/odd detection lines of an odd multisine (gap_lines.cc) and the
// lattice a quantised output sits on (gap_lattice.cc). All Eigen-only and I/O-free.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "core/numeric/model/lti_model.h"

namespace idrig {

struct GapRecord;

// A record whose input repeats: u(k + P) ≈ u(k) over the whole record (RMS of the difference
// ≤ 2 % of RMS(u)), at least two full periods. period = 0: not periodic.
struct Periodicity {
  int period = 0;    // samples
  int periods = 0;   // full periods in the record
};
Periodicity FindPeriod(const Eigen::VectorXd& u, int min_period = 8);
// The first period of y that no longer holds the transient: leading periods whose difference to
// the next (each without its own mean) exceeds 1.5× the median consecutive-period difference are
// dropped (two are kept).
int SteadyPeriodStart(const Eigen::VectorXd& y, const Periodicity& p);
// The mean of y over each full period.
Eigen::VectorXd PeriodLevels(const Eigen::VectorXd& y, const Periodicity& p);
// The drift of y per sample: the least-squares slope of the period means from period `first` on,
// divided by the period. An integrating plant turns an actuator offset into such a ramp.
double PeriodDrift(const Eigen::VectorXd& y, const Periodicity& p, int first);

// The output noise level, estimated without any candidate of the diagnosis.
//  - "periods": the input is periodic in at least one record — the sample variance of y across
//    periods, pooled over the samples of a period and the periodic records (the first period is
//    dropped as the transient when there are three or more; each period's own mean is removed
//    first, so that the ramp of an integrated offset is not counted as noise; a record whose
//    output ramps by more than 5 % of the period's swing is left out, since a nonlinear rig's
//    periods differ when its state moves). Exact for any noise colour: what repeats is the
//    system's response, linear or not; what does not is noise.
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
  int drifting_records = 0;    // periodic inputs whose output ramps (not used for "periods")
};
// Throws std::invalid_argument when the records are too short for even the lowest order.
NoiseFloor EstimateNoiseFloor(const std::vector<GapRecord>& estimation,
                              const std::vector<GapRecord>& validation);

// Even/odd detection lines of a periodic odd multisine (gap_lines.cc), after Pintelon and
// Schoukens (System Identification: A Frequency Domain Approach, 2nd ed., §3.5 and §4.3): the
// DFT of every steady period; on the excited (odd) lines the best linear approximation
// G_BLA(k) = Ȳ(k)/Ū(k); on the non-excited lines the output holds only noise and nonlinear
// distortion — odd-degree distortion falls on odd lines, even-degree on even lines. The noise of
// the period mean, σ²(k) = Σ_p |Y_p(k) − Ȳ(k)|²/(M(M−1)), comes from the M periods.
struct DetectionLine {
  double f_hz = 0;
  int line = 0;                  // DFT line of one period
  std::string kind;              // "excited", "odd" (non-excited odd), "even"
  double y_power = 0;            // |Ȳ(k)|²
  double noise_power = 0;        // σ²(k) of the mean
  bool significant = false;      // |Ȳ|²/σ² above the 99.9 % level of F(2, 2(M−1))
  // excited lines: the BLA, its noise 1σ and its nonlinear-distortion 1σ (from the odd detection
  // lines next to it; NaN when there are none), and G0 there when the sim model is known
  double bla_magnitude = 0, bla_phase = 0, bla_noise_std = 0, bla_distortion_std = 0;
  double sim_magnitude = 0;
};

struct DetectionLines {
  bool available = false;
  std::string reason;            // why not, when not available
  int period_samples = 0, periods = 0, steady_from = 0;
  double f0_hz = 0;              // line spacing
  int excited = 0, odd_lines = 0, even_lines = 0;  // counts in the excited band
  bool odd_out_of_band = false;  // no odd detection line in band: odd lines above it used
  int odd_significant = 0, even_significant = 0;
  double odd_to_noise_db = 0, even_to_noise_db = 0;    // mean |Ȳ|² / mean σ² on the lines
  double odd_to_output_db = 0, even_to_output_db = 0;  // mean |Ȳ|² / mean |Ȳ|² on excited lines
  bool odd_distortion = false, even_distortion = false;  // more significant lines than chance
  double bla_vs_sim = 0;         // median |G_BLA − G0|/|G0| on excited lines (sim model given)
  std::vector<DetectionLine> lines;  // in frequency order, up to 3× the highest excited line
};
// The first record whose input is a periodic odd multisine (at least two periods). `sim`: G0,
// or null. Never throws on data that do not qualify: available = false with the reason.
DetectionLines AnalyseDetectionLines(const std::vector<GapRecord>& records, const TransferFunction* sim);

// The lattice a quantised output sits on (gap_lattice.cc): y ≈ offset + k·step for (nearly)
// every sample. An ADC puts every reading on its lattice whatever the noise before it, so the
// test is the share of samples within 5 % of a step of a lattice point (≥ 95 %), not the noise.
// Whether it matters is physics: the rounding adds q²/12 to the noise variance, so the lattice
// is called quantisation only when that is a material share of the noise floor,
// q²/12 ≥ 5 % of σ̂² (q ≳ 0.77 σ̂). A lattice that only the printing of the numbers made (a CSV
// with few digits: q far below the noise) is not quantisation.
struct OutputLattice {
  bool lattice = false;          // the samples sit on a lattice
  bool detected = false;         // …and it is coarse enough against the noise to matter
  double step = 0, offset = 0;   // y ≈ offset + k·step (offset in [0, step))
  double on_lattice = 0;         // share of samples within 0.05·step of a lattice point
  double resultant = 0;          // |mean exp(2πi y/step)|
  int levels = 0;                // distinct lattice levels used
  double noise_share = 0;        // (step²/12) / σ̂²
  std::string reason;
};
// `step`: the candidate step (QuantisationStep); `noise_sigma`: the independent noise floor.
OutputLattice DetectOutputLattice(const std::vector<GapRecord>& records, double step, double noise_sigma);

struct GapReport;
// A detected lattice names output_quantization: as the verdict when it was `none` (the
// quantisation candidate's fit, confidence = the share of samples on the lattice), or as a
// second effect in verdict.effects when one effect was named and the rounding noise is a material
// share (≥ 5 %) of what that effect leaves, (q²/12)/(σ̂·after/floor)². Notes say so.
void NameLatticeQuantisation(const OutputLattice& lattice, double noise_nrmse, GapReport& report);

struct GapVerdict;
// The verdict's figures against an independent floor (all NRMSE on the validation records):
// shrink = (before − after)/(before − min(floor, after)) (0 when before ≤ floor: nothing to
// explain; 1 when after < floor < before: the floor is an upper bound that the model beat, or
// the noise is coloured, and then at least before − after was explainable),
// remaining_gap_to_noise = after − floor (negative below the floor), below_noise_floor = after < floor.
void ApplyNoiseFloor(double floor_nrmse, GapVerdict& verdict);

}  // namespace idrig
