#pragma once
// A sensor re-zeroed (or knocked, or switched to another range) in the middle of a record: the
// reading jumps to a new level at one sample and stays there, whatever the input does. Fitted
// with one output offset per record, the jump is a gap that a static effect or extra dynamics
// takes (docs/gap.md, stop 27: 3 of 5 `none` cases named an effect far above the noise floor).
// Found here against a model's simulated output ŷ (the sim model, from rest), so that what the
// input drives is not a jump — and only where the step stands out of what that model leaves
// (a step smaller than a large gap's own wander is not found): with r = y − ŷ,
//   J_t = mean(r_t … r_{t+w−1}) − mean(r_{t−w} … r_{t−1})        (w = 8)
// is a level shift's step when it stands out of J's robust spread (12 × 1.4826 MAD of J over
// the record) and out of the noise (6 σ, σ from the MAD of r's increments), and it is a sensor
// step when it is
//   - sharp: one increment of r carries at least half of it (a rig's dynamics move over
//     several samples; a wrong model's residual does too),
//   - not the input's doing: that increment less what the model's error does to r's
//     increments where ŷ moves as it does there (Δr ≈ β·Δŷ, least squares over the record)
//     still carries half of it, and stands 3 σ√2 out of the noise (a plant that responds
//     within a sample, with another gain than the model's, moves r at every input step),
//   - persistent: the median of r over up to W = min(N/8, 500) samples after it stands off the
//     median before it by at least 60 % of the step, over W and over W/4 (a delay's pulse, a
//     dropout or a burst returns).
// At most `max_shifts`, the largest first, each at least 2W from the others.
#include <Eigen/Dense>
#include <vector>

namespace idrig {

struct LevelShift {
  long sample = 0;     // the first sample at the new level
  double size = 0;     // the new level less the old (the output's units)
  double score = 0;    // |J| in units of J's robust spread
};

std::vector<LevelShift> FindSensorSteps(const Eigen::VectorXd& y, const Eigen::VectorXd& model_output,
                                        int max_shifts = 2);

}  // namespace idrig
