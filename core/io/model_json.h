#pragma once
// Model exchange format "idrig.model/1", read and written by every command and the catalogue:
//   {"format":"idrig.model/1","kind":"tf","domain":"continuous"|"discrete","Ts":0.2,
//    "num":[…],"den":[…],"delay_s":0.0}             (descending powers)
//   {"format":"idrig.model/1","kind":"ss","domain":…,"Ts":…,
//    "A":[[…],…],"B":[[…],…],"C":[[…],…],"D":[[…],…],"delay_s":…}  (nested row arrays)
// Extra keys are allowed and ignored on input (e.g. "identification" metadata).
// Optional: "operating_point": {"u":[u0…],"y":[y0…]} — the model maps deviations about it,
// y = y0 + G(u − u0) (identify --offsets mean); absent: y = G u.
#include <nlohmann/json.hpp>
#include <string>

#include "core/numeric/io_record.h"
#include "core/numeric/model/lti_model.h"

namespace idrig {

inline constexpr const char* kModelFormat = "idrig.model/1";

nlohmann::json ModelToJson(const LtiModel& model);
nlohmann::json ModelToJson(const TransferFunction& tf);
nlohmann::json ModelToJson(const StateSpace& ss);

// Throws std::invalid_argument naming the key and the problem.
LtiModel ModelFromJson(const nlohmann::json& json);
// Reads a model file; the error names the file (unreadable, not JSON, wrong format, a
// malformed operating point).
LtiModel ReadModelFile(const std::string& path);
// The same, as the checked JSON (with its operating point and metadata).
nlohmann::json ReadModelJsonFile(const std::string& path);
void WriteModelFile(const LtiModel& model, const std::string& path);

nlohmann::json OperatingPointToJson(const OperatingPoint& op);
// The model's "operating_point" (empty when absent). Throws std::invalid_argument naming the
// problem when it is malformed or its sizes differ from the model's inputs and outputs.
OperatingPoint OperatingPointFromModelJson(const nlohmann::json& model);
// Simulates a model given as JSON on the inputs u (N×nu) from rest at its operating point:
// y0 + G(u − u0) (G u without one).
Eigen::MatrixXd SimulateModelJson(const nlohmann::json& model, const Eigen::MatrixXd& u,
                                  double sample_time);

}  // namespace idrig
