#pragma once
// Model exchange format "idrig.model/1", read and written by every command and the catalogue:
//   {"format":"idrig.model/1","kind":"tf","domain":"continuous"|"discrete","Ts":0.2,
//    "num":[…],"den":[…],"delay_s":0.0}             (descending powers)
//   {"format":"idrig.model/1","kind":"ss","domain":…,"Ts":…,
//    "A":[[…],…],"B":[[…],…],"C":[[…],…],"D":[[…],…],"delay_s":…}  (nested row arrays)
// Extra keys are allowed and ignored on input (e.g. "identification" metadata).
#include <nlohmann/json.hpp>
#include <string>

#include "core/numeric/model/lti_model.h"

namespace idrig {

inline constexpr const char* kModelFormat = "idrig.model/1";

nlohmann::json ModelToJson(const LtiModel& model);
nlohmann::json ModelToJson(const TransferFunction& tf);
nlohmann::json ModelToJson(const StateSpace& ss);

// Throws std::invalid_argument naming the key and the problem.
LtiModel ModelFromJson(const nlohmann::json& json);
// Reads a model file; the error names the file (unreadable, not JSON, wrong format).
LtiModel ReadModelFile(const std::string& path);
void WriteModelFile(const LtiModel& model, const std::string& path);

}  // namespace idrig
