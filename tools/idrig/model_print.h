#pragma once
// Printing of catalogue models, shared by `idrig models`, `idrig demo` and `idrig status`
// (cmd_models.cc).
#include <cstdint>
#include <string>
#include <vector>

#include "core/catalog/catalog.h"

namespace idrig {

std::string TimeText(int64_t utime);  // UTC, "YYYY-mm-dd HH:MM:SS"
std::string Number(double value, int precision = 4);
void PrintModelTable(Catalog& catalog, const std::vector<ModelRecord>& models);
void PrintModel(Catalog& catalog, const ModelRecord& m, bool json);
// A parameter over time, one line per model, with a bar: the history plot of a terminal.
void PrintHistory(Catalog& catalog, const std::string& rig, const std::string& metric,
                  const std::string& method);

}  // namespace idrig
