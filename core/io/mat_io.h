#pragma once
// MATLAB .mat files (level 5, as written by MATLAB's and Octave's `save -v7`/`-v6`), through
// Debian's libmatio: records in (variables named by the user), records and models out.
//
//   record file:  t (N×1) [s], u (N×nu), y (N×ny), Ts [s], plus text variables (rig_id, ...)
//   model file:   tf: num (1×m), den (1×n+1), Ts, delay  -> MATLAB: tf(num, den, Ts, 'InputDelay', delay)
//                 ss: A, B, C, D, Ts, delay               -> MATLAB: ss(A, B, C, D, Ts, 'InputDelay', delay)
//                 delay is MATLAB's InputDelay: seconds (continuous) or samples (discrete);
//                 delay_s is always seconds.
//                 kind ('tf'/'ss'), domain ('continuous'/'discrete'), and a struct `lineage`
//                 whose fields are the catalogue's lineage (rig, experiment, method, worker, ...);
//                 u0 (nu×1), y0 (ny×1) when the model has an operating point: y = y0 + G(u − u0).
// Ts = 0 means continuous time (MATLAB's convention for tf/ss too).
#include <Eigen/Dense>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/numeric/io_record.h"
#include "core/numeric/model/lti_model.h"

namespace idrig {

// Names of the variables in a .mat file. Throws std::invalid_argument naming the file when it
// cannot be opened as a .mat file.
std::vector<std::string> MatVariableNames(const std::string& path);

// A real numeric variable (double, single, integer or logical) as a matrix (rows × columns).
// Throws std::invalid_argument naming the file and the variable: missing (with the names that
// exist), complex, not numeric (struct, cell, char), more than two dimensions, or empty.
Eigen::MatrixXd ReadMatMatrix(const std::string& path, const std::string& name);

// A record from variables of a .mat file: `u_names` and `y_names` each name one variable or
// several (comma-separated); each variable is a vector (one channel) or an N×k matrix (k
// channels, or a 1×N row that is taken as a column). The sample time is `ts` when > 0, else
// the variable `Ts` (or `ts`, `dt`), else the uniform time vector `t` (or `time`).
// Throws std::invalid_argument naming the file and the problem (missing variable, lengths that
// differ, no sample time, NaN, ...).
IoRecord ReadMatRecord(const std::string& path, const std::string& u_names,
                       const std::string& y_names, double ts = 0.0);

// Writes t, u, y, Ts and the text variables (name -> value). Throws std::runtime_error when the
// file cannot be written.
void WriteMatRecord(const IoRecord& record, const std::string& path,
                    const std::map<std::string, std::string>& text = {});

// Writes a model (see above); `lineage` is a flat JSON object (numbers, strings, booleans;
// nested values are written as their JSON text) stored as the struct `lineage`.
void WriteMatModel(const LtiModel& model, const std::string& path,
                   const nlohmann::json& lineage = nlohmann::json::object(),
                   const OperatingPoint& operating_point = {});

}  // namespace idrig
