#pragma once
// Confidence band of a frequency response from the covariance of the parameters of a
// discrete ARX model (core/numeric/time_domain/arx.h, Eq. (2.2) of [Ivanovsky]):
//   g = (−c_1 … −c_n, d_1 … d_n),  W(z) = (d_1 z^{n−1} + … + d_n) / (z^n + c_1 z^{n−1} + … + c_n),
// times z^{−(nk−1)} for an input delay of nk samples (|·| unchanged, phase shifted).
// First-order (delta-method) propagation of Cov(g) to |W| and ∠W at z = e^{jωTs}:
//   ∂W/∂(−c_i) = W z^{n−i} / D(z),   ∂W/∂d_i = z^{n−i} / D(z),   J = ∂W/∂g (complex row)
//   σ²_|W| = aᵀ Cov a, a = Re(conj(W) J)/|W|;   σ²_∠W = bᵀ Cov b, b = Im(J / W).
#include <Eigen/Dense>

namespace idrig {

struct ResponseBand {
  Eigen::VectorXd omega;        // [rad/s]
  Eigen::VectorXd magnitude;    // |W(e^{jωTs})|
  Eigen::VectorXd phase_rad;    // ∠W, unwrapped along ω
  Eigen::VectorXd magnitude_std, phase_std_rad;  // one standard deviation
};

// Throws std::invalid_argument when g has odd length, Cov is not (2n)×(2n), Ts <= 0, or an ω is
// not in (0, π/Ts].
ResponseBand ArxResponseBand(const Eigen::VectorXd& g, const Eigen::MatrixXd& covariance,
                             double sample_time, int input_delay_samples,
                             const Eigen::VectorXd& omega);

}  // namespace idrig
