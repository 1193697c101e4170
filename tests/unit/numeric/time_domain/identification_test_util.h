#pragma once
// Shared by the subspace and prediction-error tests: seeded excitation and noise, and the
// message of the std::invalid_argument a call throws ("" when it does not throw).
#include <Eigen/Dense>
#include <random>
#include <stdexcept>
#include <string>

namespace idrig::testing {

// Random binary ±1 per input, each value held `hold` samples.
inline Eigen::MatrixXd RandomBinary(int samples, int inputs, int hold, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution coin(0.5);
  Eigen::MatrixXd u(samples, inputs);
  for (int q = 0; q < inputs; ++q)
    for (int k = 0; k < samples; ++k) u(k, q) = (k % hold == 0) ? (coin(rng) ? 1.0 : -1.0) : u(k - 1, q);
  return u;
}

inline Eigen::VectorXd WhiteNoise(int samples, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma);
  Eigen::VectorXd e(samples);
  for (int k = 0; k < samples; ++k) e(k) = normal(rng);
  return e;
}

template <typename Call>
std::string InvalidArgumentMessage(Call&& call) {
  try {
    call();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace idrig::testing
