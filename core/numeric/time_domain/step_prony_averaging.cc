// Step-response identification with multiple complex poles, [Vidinčev] (seed 000): block averaging (25)–(35).
#include "core/numeric/time_domain/step_prony_internal.h"

#include <cmath>

namespace idrig {

const char* ToString(StepAveraging averaging) {
  switch (averaging) {
    case StepAveraging::kNone: return "none";
    case StepAveraging::kBlock: return "block";
    case StepAveraging::kIntegral: return "integral";
  }
  return "?";
}

namespace step_prony_detail {

int Grid::Extent() const {
  switch (averaging) {
    case StepAveraging::kNone: return 0;
    case StepAveraging::kBlock: return (blocks - 1) * (spacing / blocks);
    case StepAveraging::kIntegral: return spacing;
  }
  return 0;
}

template <typename Vec>
typename Vec::Scalar Grid::ReduceAt(const Vec& v, int base) const {
  using S = typename Vec::Scalar;
  switch (averaging) {
    case StepAveraging::kNone: return v(base);
    case StepAveraging::kBlock: {  // Eq. (25): mean over γ = 0..B−1 of x̄(αh + γh/B)
      S sum = 0.0;
      const int step = spacing / blocks;
      for (int g = 0; g < blocks; ++g) sum += v(base + g * step);
      return sum / static_cast<double>(blocks);
    }
    case StepAveraging::kIntegral: {  // ∫_{αh}^{αh+h} x̄ dt, trapezoid rule on the samples
      S sum = 0.5 * (v(base) + v(base + spacing));
      for (int k = 1; k < spacing; ++k) sum += v(base + k);
      return sum * sample_time;
    }
  }
  return S(0.0);
}
template double Grid::ReduceAt<Eigen::VectorXd>(const Eigen::VectorXd&, int) const;
template cd Grid::ReduceAt<Eigen::VectorXcd>(const Eigen::VectorXcd&, int) const;

int Grid::SamplesFor(int points) const {
  switch (averaging) {
    case StepAveraging::kNone: return (points - 1) * spacing + 1;
    case StepAveraging::kBlock: return (points - 1) * spacing + (blocks - 1) * (spacing / blocks) + 1;
    case StepAveraging::kIntegral: return points * spacing + 1;
  }
  return 0;
}

}  // namespace step_prony_detail
}  // namespace idrig
