#include "core/io/csv.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace idrig {
namespace {

std::string Trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r\n\"");
  if (begin == std::string::npos) return "";
  const auto end = s.find_last_not_of(" \t\r\n\"");
  return s.substr(begin, end - begin + 1);
}

std::vector<std::string> SplitFields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream ss(line);
  std::string field;
  while (std::getline(ss, field, ',')) fields.push_back(Trim(field));
  if (!line.empty() && line.back() == ',') fields.push_back("");
  return fields;
}

double ParseNumber(const std::string& field, bool* ok) {
  if (field.empty()) { *ok = false; return 0.0; }
  const std::string lower = [&] { std::string l; for (char c : field) l += std::tolower(c); return l; }();
  if (lower == "nan") { *ok = true; return std::numeric_limits<double>::quiet_NaN(); }
  if (lower == "inf" || lower == "+inf") { *ok = true; return std::numeric_limits<double>::infinity(); }
  if (lower == "-inf") { *ok = true; return -std::numeric_limits<double>::infinity(); }
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(field.c_str(), &end);
  *ok = end != field.c_str() && *end == '\0';
  return value;
}

}  // namespace

IoRecord ParseIoRecordCsv(const std::string& text, const std::string& source_name) {
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument(source_name + ": " + what);
  };
  std::istringstream in(text);
  std::string line;
  int line_number = 0;
  std::vector<std::string> header;
  while (std::getline(in, line)) {
    ++line_number;
    if (!Trim(line).empty() && Trim(line)[0] != '#') { header = SplitFields(line); break; }
  }
  if (header.empty()) fail("empty file: expected a header line such as 't,u,y'");
  {
    bool numeric = false;
    ParseNumber(header[0], &numeric);
    if (numeric) fail("missing header line: the first line holds numbers; expected column names such as 't,u,y'");
  }
  int time_column = -1;
  std::vector<int> input_columns, output_columns;
  IoRecord record;
  for (size_t c = 0; c < header.size(); ++c) {
    std::string name;
    for (char ch : header[c]) name += std::tolower(ch);
    if (name == "t" || name == "time") {
      if (time_column >= 0) fail("two time columns in the header");
      time_column = static_cast<int>(c);
    } else if (!name.empty() && name[0] == 'u') {
      input_columns.push_back(static_cast<int>(c));
      record.input_names.push_back(header[c]);
    } else if (!name.empty() && name[0] == 'y') {
      output_columns.push_back(static_cast<int>(c));
      record.output_names.push_back(header[c]);
    } else {
      fail("column '" + header[c] + "' is not t, u… or y… (header must be t,u,y or t,u1,…,y1,…)");
    }
  }
  if (time_column < 0) fail("no time column 't' in the header");
  if (input_columns.empty()) fail("no input column ('u' or 'u1', 'u2', …) in the header");
  if (output_columns.empty()) fail("no output column ('y' or 'y1', 'y2', …) in the header");

  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string trimmed = Trim(line);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    const auto fields = SplitFields(line);
    if (fields.size() != header.size())
      fail("line " + std::to_string(line_number) + " has " + std::to_string(fields.size()) +
           " fields, the header has " + std::to_string(header.size()) + " (truncated file?)");
    std::vector<double> row(fields.size());
    for (size_t c = 0; c < fields.size(); ++c) {
      bool ok = false;
      row[c] = ParseNumber(fields[c], &ok);
      if (!ok)
        fail("line " + std::to_string(line_number) + ", column '" + header[c] + "': '" +
             fields[c] + "' is not a number");
    }
    rows.push_back(std::move(row));
  }
  const long n = static_cast<long>(rows.size());
  if (n == 0) fail("no data rows after the header");
  record.t.resize(n);
  record.u.resize(n, input_columns.size());
  record.y.resize(n, output_columns.size());
  for (long r = 0; r < n; ++r) {
    record.t(r) = rows[r][time_column];
    for (size_t c = 0; c < input_columns.size(); ++c) record.u(r, c) = rows[r][input_columns[c]];
    for (size_t c = 0; c < output_columns.size(); ++c) record.y(r, c) = rows[r][output_columns[c]];
  }
  // The mean step: times printed with few digits scatter around the grid, their mean does not.
  record.sample_time = n >= 2 ? (record.t(n - 1) - record.t(0)) / (n - 1) : 0.0;
  try {
    ValidateIoRecord(record, 2);
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  return record;
}

IoRecord ReadIoRecordCsv(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::invalid_argument(path + ": cannot open the file for reading");
  std::ostringstream content;
  content << file.rdbuf();
  return ParseIoRecordCsv(content.str(), path);
}

std::string FormatIoRecordCsv(const IoRecord& record) {
  std::ostringstream out;
  out << std::setprecision(17);
  out << "t";
  for (int i = 0; i < record.NumInputs(); ++i)
    out << "," << (i < static_cast<int>(record.input_names.size()) ? record.input_names[i]
                   : (record.NumInputs() == 1 ? "u" : "u" + std::to_string(i + 1)));
  for (int i = 0; i < record.NumOutputs(); ++i)
    out << "," << (i < static_cast<int>(record.output_names.size()) ? record.output_names[i]
                   : (record.NumOutputs() == 1 ? "y" : "y" + std::to_string(i + 1)));
  out << "\n";
  for (int k = 0; k < record.NumSamples(); ++k) {
    out << (record.t.size() == record.NumSamples() ? record.t(k) : k * record.sample_time);
    for (int i = 0; i < record.NumInputs(); ++i) out << "," << record.u(k, i);
    for (int i = 0; i < record.NumOutputs(); ++i) out << "," << record.y(k, i);
    out << "\n";
  }
  return out.str();
}

void WriteIoRecordCsv(const IoRecord& record, const std::string& path) {
  std::ofstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error(path + ": cannot open the file for writing");
  file << FormatIoRecordCsv(record);
  if (!file) throw std::runtime_error(path + ": write failed");
}

}  // namespace idrig
