#include "core/numeric/model/response_band.h"

#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>

namespace idrig {

ResponseBand ArxResponseBand(const Eigen::VectorXd& g, const Eigen::MatrixXd& covariance,
                             double sample_time, int input_delay_samples,
                             const Eigen::VectorXd& omega) {
  const Eigen::Index n2 = g.size();
  if (n2 == 0 || n2 % 2 != 0)
    throw std::invalid_argument("ARX parameters g must have 2n entries, got " + std::to_string(n2));
  if (covariance.rows() != n2 || covariance.cols() != n2)
    throw std::invalid_argument("covariance must be " + std::to_string(n2) + "x" +
                                std::to_string(n2));
  if (!(sample_time > 0)) throw std::invalid_argument("sample time must be positive");
  const int n = static_cast<int>(n2 / 2);
  ResponseBand out;
  out.omega = omega;
  out.magnitude.resize(omega.size());
  out.phase_rad.resize(omega.size());
  out.magnitude_std.resize(omega.size());
  out.phase_std_rad.resize(omega.size());
  double previous = 0.0;
  for (Eigen::Index k = 0; k < omega.size(); ++k) {
    const double w = omega(k);
    if (!(w > 0) || w > M_PI / sample_time * (1 + 1e-12))
      throw std::invalid_argument("frequency " + std::to_string(w) + " rad/s is not in (0, π/Ts]");
    const std::complex<double> z = std::polar(1.0, w * sample_time);
    std::vector<std::complex<double>> power(n + 1);  // z^0 … z^n
    power[0] = 1.0;
    for (int i = 1; i <= n; ++i) power[i] = power[i - 1] * z;
    std::complex<double> num = 0.0, den = power[n];
    for (int i = 1; i <= n; ++i) {
      num += g(n + i - 1) * power[n - i];  // d_i z^{n−i}
      den -= g(i - 1) * power[n - i];      // c_i = −g_i
    }
    const std::complex<double> W = num / den;
    Eigen::RowVectorXcd J(n2);
    for (int i = 1; i <= n; ++i) {
      J(i - 1) = W * power[n - i] / den;  // ∂W/∂(−c_i)
      J(n + i - 1) = power[n - i] / den;  // ∂W/∂d_i
    }
    const double mag = std::abs(W);
    const Eigen::RowVectorXd a = (std::conj(W) * J).real() / mag;
    const Eigen::RowVectorXd b = (J / W).imag();
    out.magnitude(k) = mag;
    double phase = std::arg(W) - (input_delay_samples - 1) * w * sample_time;
    if (k > 0) phase -= 2 * M_PI * std::round((phase - previous) / (2 * M_PI));
    out.phase_rad(k) = previous = phase;
    out.magnitude_std(k) = std::sqrt(std::max(0.0, (a * covariance * a.transpose())(0, 0)));
    out.phase_std_rad(k) = std::sqrt(std::max(0.0, (b * covariance * b.transpose())(0, 0)));
  }
  return out;
}

}  // namespace idrig
