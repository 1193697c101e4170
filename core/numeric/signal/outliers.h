#pragma once
// Gross output glitches in a measured record: a sample or a short run that a sensor or an
// acquisition chain got wrong (a spike, a dropout to zero, a bit error), found and bridged
// before a model is fitted. One such sample can outweigh the whole record in a least-squares
// cost: a +50 spike on an output whose range is 2 took a Coulomb friction case to `ambiguous`
// and its noise floor from 0.033 to 0.178 (docs/gap.md, "Glitches in the records").
//
// The rule is a Hampel identifier (Hampel 1974; Pearson, "Outliers in process modeling and
// identification", IEEE TCST 10(1), 2002) made conservative for records of dynamic systems:
//   r_t = y_t − median(y_{t−h} … y_{t+h})   (h = 5: runs of up to 5 samples stand out)
//   s   = 1.4826 · median |r_t|              (robust scale of what the running median leaves)
// y_t is a glitch when |r_t| > max(12 s, span/4), span the output's 0.5–99.5 % range: the
// dynamics a sampled rig output shows move far less than a quarter of its range away from their
// own running median and straight back. It is not a glitch when the input has an isolated
// excursion (against the input's whole range) at t or t − 1: a one-sample input pulse may drive
// a direct-feedthrough output there. A run of such samples is a glitch only when it is entered
// and left sharply: each jump (in from the sample before, out to the sample after) above half the
// threshold and above 1.5 times the largest |Δy| of the h samples on either side (the peaks of a
// coarsely sampled oscillation stand as far from their running median but are reached through
// samples in between). Nothing is marked when the runs of marks (events) exceed
// max(2, 0.2 % of the samples), or the marked samples 5 times that: then the excursions are the
// record's character, not faults. Marked samples are
// bridged linearly between their unmarked neighbours, and every one is reported.
#include <Eigen/Dense>
#include <vector>

namespace idrig {

struct OutputGlitch {
  long sample = 0;       // index in the record
  double value = 0;      // as measured
  double replaced_by = 0;
};

struct GlitchScan {
  std::vector<OutputGlitch> glitches;  // bridged (empty when none or when too many)
  long excursions = 0;   // samples that passed the size rule before the rarity rule
  long events = 0;       // runs of such samples
  bool too_many = false; // events (or samples) beyond the rarity limit: left as measured
};

// Finds the glitches of y and bridges them in y. `inputs`: the record's inputs (one column
// each, as many rows as y), or empty.
GlitchScan BridgeOutputGlitches(Eigen::VectorXd& y, const Eigen::MatrixXd& inputs);

}  // namespace idrig
