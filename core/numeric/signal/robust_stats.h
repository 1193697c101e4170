#pragma once
// Robust location and scale of a sample, shared by the record-fault scans (outliers.h,
// level_shifts.h).
#include <algorithm>
#include <cmath>
#include <vector>

namespace idrig {

// The median (the upper one for an even count); 0 for an empty sample.
inline double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<long>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// 1.4826 · median |v − median v|: the standard deviation for Gaussian data, robust to outliers.
inline double RobustSpread(const std::vector<double>& v) {
  const double m = Median(v);
  std::vector<double> dev(v.size());
  for (size_t i = 0; i < v.size(); ++i) dev[i] = std::abs(v[i] - m);
  return 1.4826 * Median(dev);
}

}  // namespace idrig
