#pragma once
// Plots of a gap diagnosis report (idrig.gap/1 JSON) as standalone SVG files: the gap by
// frequency band, by input amplitude, by state (velocity sign, reversals, output level), and
// the ranking of the candidate effects. Plain SVG 1.1 text, viewable in any browser.
#include <map>
#include <nlohmann/json.hpp>
#include <string>

namespace idrig {

// File name (e.g. "gap_frequency.svg") → SVG text.
std::map<std::string, std::string> GapReportSvgs(const nlohmann::json& report);

// Writes every plot into `directory` (created if missing); returns the paths written.
std::vector<std::string> WriteGapReportSvgs(const nlohmann::json& report, const std::string& directory);

}  // namespace idrig
