#pragma once
// The gap diagnosis report as JSON (the stable interface of `idrig gap diagnose --json`, stored
// in the catalogue by the workers) and as text. Keys are documented in docs/gap.md.
#include <nlohmann/json.hpp>
#include <string>

#include "core/numeric/gap/gap_diagnosis.h"

namespace idrig {

// {"effect": name, "params": {name: value, …}}. EffectFromJson throws std::invalid_argument
// naming an unknown effect, a missing or unknown parameter, or a bad value.
nlohmann::json EffectToJson(const Effect& effect);
Effect EffectFromJson(const nlohmann::json& json);
nlohmann::json GapReportToJson(const GapReport& report);
std::string GapReportText(const GapReport& report);
// The same text from a stored report (idrig.gap/1 JSON, e.g. from the catalogue).
std::string GapReportText(const nlohmann::json& report);

}  // namespace idrig
