#pragma once
// Synthetic blind cases for the gap diagnosis: a random plant G0 (the "sim model"), a withheld
// effect with random parameters added to it (the "real rig"), output noise at a chosen SNR, and
// estimation and validation records from independent excitation realisations of one of three
// kinds (multisine at three amplitude levels with steps; PRBS; random binary). The generator
// simulates the rig more finely than the diagnosis does (feedback effects with 16 sub-steps),
// and the diagnosis never sees the case's truth.
#include <random>
#include <string>

#include "core/numeric/gap/effects.h"
#include "core/numeric/gap/gap_diagnosis.h"

namespace idrig {

struct GapCaseOptions {
  double snr_db = 30.0;        // output SNR (signal RMS / noise RMS in dB)
  int samples = 4000;          // per record
  double sample_time = 0.01;   // [s]
  std::string excitation;      // "levels", "prbs", "rbs"; empty: drawn at random per case
};

struct GapCase {
  EffectKind truth = EffectKind::kNone;
  Effect effect;               // the withheld effect (for parameter_mismatch: none; see real)
  TransferFunction sim;        // what the user's simulation says
  TransferFunction real;       // the rig's linear part
  std::string excitation;      // "levels", "prbs" or "rbs"
  double noise_sigma = 0;
  GapRecord estimation, validation;
};

GapCase MakeGapCase(EffectKind truth, std::mt19937_64& rng, const GapCaseOptions& options = {});

// The rig's output for input u: the linear part with the effect, output noise, and for
// quantisation the noise before the rounding (a noisy signal digitised by an ADC).
Eigen::VectorXd SimulateRig(const TransferFunction& plant, const Effect& effect,
                            const Eigen::VectorXd& u, double sample_time, double noise_sigma,
                            std::mt19937_64& rng);

}  // namespace idrig
