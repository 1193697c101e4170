#pragma once
// Views of the catalogue and the experiment store shared by the command line (`idrig models
// …`, `idrig experiment list|export`) and the dashboard (`idrig serve`): the same lineage, the
// same comparison, the same history and the same responses in the terminal, in files and on
// the page. Read-only: nothing here writes to a database.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/catalog/catalog.h"
#include "core/io/svg_plot.h"
#include "core/numeric/io_record.h"

namespace idrig {

std::string UtcTimeText(int64_t utime);  // "2026-12-01 17:40:05" (UTC) from µs

// The whole lineage of a model: ids, rig, experiment and its signal, method and options, data
// hash, sample count, Ts, software version, worker, compute time, storage time, fits, status.
nlohmann::json ModelLineageJson(const ModelRecord& m);
// One row of the models table: lineage essentials plus fit, order, DC gain, poles.
nlohmann::json ModelSummaryJson(Catalog& catalog, const ModelRecord& m);
// Throws std::invalid_argument "no model ID in DB" when absent.
ModelRecord RequireModel(Catalog& catalog, int64_t model_id, const std::string& db_path);

// Two models side by side, row by row: lineage fields, then every metric of either model, with
// b − a (and the relative difference) where both are numbers.
struct CompareRow {
  std::string name, unit, a, b, difference;
};
std::vector<CompareRow> CompareModels(Catalog& catalog, const ModelRecord& a, const ModelRecord& b);
nlohmann::json CompareJson(const std::vector<CompareRow>& rows);

// A metric over time for a rig, one series per method:
// {"rig","param","unit","series":[{"method","points":[{"model_id","utime","t","value"}]}]}.
nlohmann::json HistoryJson(Catalog& catalog, const std::string& rig, const std::string& metric,
                           const std::string& method = "");
// The same as an SVG line plot: time axis with UTC labels, or the storage order (labelled with
// the storage times) when models stored close together would overlap on a time axis.
LinePlot HistoryPlot(const nlohmann::json& history);

// Responses of a stored model (channel 1→1 of a MIMO model):
// Bode {"omega","mag_db","phase_deg", optional "band":{"omega","mag_db_lo","mag_db_hi",
// "phase_deg_lo","phase_deg_hi","note"}} — the ±2σ band where the method stored a parameter
// covariance (arx, arx-oe); step {"t","y"}; poles/zeros {"domain","Ts","poles":[[re,im]],
// "zeros":[[re,im]]}; the stabilisation diagram of modal results (empty when none).
nlohmann::json BodeJson(const ModelRecord& m);
nlohmann::json StepJson(const ModelRecord& m);
nlohmann::json PoleZeroJson(const ModelRecord& m);
nlohmann::json StabilisationJson(const ModelRecord& m);

// The experiments the catalogue and the store know, with blocks stored and what is missing.
nlohmann::json ExperimentsJson(Catalog* catalog, const std::string& store_path);
// The measured record of an experiment from the logger's store (decoded blocks). Throws
// std::invalid_argument naming the store, the experiment, or the missing blocks.
IoRecord LoadExperimentRecord(const std::string& store_path, const std::string& rig,
                              int64_t experiment_id, std::string* signal_spec = nullptr);
// Writes a record as CSV (.csv) or MATLAB (.mat) by the file's extension; text variables go
// into the .mat file. Throws std::invalid_argument for any other extension.
void WriteRecordFile(const IoRecord& record, const std::string& path,
                     const std::map<std::string, std::string>& text = {});

}  // namespace idrig
