#pragma once
// Eigen values as report JSON, shared by the method adapters: vectors as arrays, matrices as
// arrays of rows, complex vectors as [re, im] pairs.
#include <Eigen/Dense>
#include <nlohmann/json.hpp>
#include <vector>

namespace idrig::report_json {

inline nlohmann::json Vec(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}
inline nlohmann::json Mat(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < m.rows(); ++r) rows.push_back(Vec(m.row(r).transpose()));
  return rows;
}
inline nlohmann::json Complex(const Eigen::VectorXcd& v) {
  nlohmann::json out = nlohmann::json::array();
  for (int i = 0; i < v.size(); ++i) out.push_back({v(i).real(), v(i).imag()});
  return out;
}

}  // namespace idrig::report_json
