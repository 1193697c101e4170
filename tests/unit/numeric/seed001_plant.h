#pragma once
// Seed 001's plant R1 (Figs. 3–9 of [Ivanovsky]): W(p) = (0.5p + 1)/(p³ + 2.5p² + 4p + 1.5).
#include <Eigen/Dense>
#include <algorithm>

#include "core/numeric/model/lti_model.h"

namespace idrig::testing {

inline Eigen::MatrixXd PlantA() {
  Eigen::MatrixXd a(3, 3);
  a << 0, 1, 0, 0, 0, 1, -1.5, -4.0, -2.5;
  return a;
}
inline Eigen::VectorXd PlantB() { return Eigen::Vector3d(0, 0.5, -0.25); }
inline Eigen::RowVectorXd PlantH() { return Eigen::RowVector3d(1, 0, 0); }
inline TransferFunction PlantTf() {
  TransferFunction tf;
  tf.num = Eigen::Vector2d(0.5, 1.0);
  tf.den = Eigen::Vector4d(1.0, 2.5, 4.0, 1.5);
  return tf;
}

// max over true poles of the distance to the nearest estimated pole.
inline double MaxPoleDistance(const Eigen::VectorXcd& truth, const Eigen::VectorXcd& estimate) {
  double worst = 0.0;
  for (int i = 0; i < truth.size(); ++i) {
    double best = 1e300;
    for (int j = 0; j < estimate.size(); ++j) best = std::min(best, std::abs(truth(i) - estimate(j)));
    worst = std::max(worst, best);
  }
  return worst;
}

}  // namespace idrig::testing
