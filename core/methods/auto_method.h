#pragma once
// Held-out splits of the `auto` method (auto_method.cc), exposed for tests.
#include <Eigen/Dense>
#include <vector>

#include "core/numeric/io_record.h"

namespace idrig {

// A channel's mean "stands out" when |mean| > kOffsetShare·(max − min): a rig run about an
// operating point with actuator and sensor offsets, not a test signal about zero (a PRBS ±a
// has |mean| ≤ a/N; the response of a slow plant to it has a mean that is a larger share of its
// RMS spread, but not of its range). auto then also fits every candidate about the record's
// means (option offsets=mean) and lets the folds choose, so a step test from rest, whose means
// stand out too, keeps its from-rest fit when that is better.
inline constexpr double kOffsetShare = 0.1;
bool OffsetsStandOut(const IoRecord& record);

// The first sample index s at which the cumulative input energy reaches `fraction` of its
// total: Σ_{k<s} Σ_j (u_j[k] − ū_j)² / (nu·E_j) >= fraction, E_j = Σ_k (u_j[k] − ū_j)² (each
// input weighs 1/nu, whatever its scale). The information the record carries about the
// parameters of an output-error model is Σ ψψᵀ/σ² with ψ = ∂ŷ/∂θ a filtered input
// ([Ljung] Eq. (9.18)), so for a slowly varying input envelope it accrues with the input energy:
// splitting there gives the estimation part `fraction` of the information, which a split by
// sample count does not on a non-stationary record (a burst). Clamped to
// [min_head, N − min_tail]; an input without energy splits by sample count.
// Throws std::invalid_argument if fraction is not in (0, 1) or min_head + min_tail > N.
int InputEnergySplit(const Eigen::MatrixXd& u, double fraction, int min_head, int min_tail);

// The folds of `auto` on an N-sample record: the distinct splits at 2/3 and 3/4 of the input
// energy, clamped to [N/2, N − max(10, N/10)], ascending (by_energy = false, option
// split=samples: at N − ⌊N/3⌋ and N − ⌊N/4⌋). Each fold estimates on samples 0..s−1 and is
// scored on s..N−1.
std::vector<int> AutoFoldSplits(const Eigen::MatrixXd& u, bool by_energy = true);

}  // namespace idrig
