#include "core/io/csv.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/io/csv_scan.h"

namespace idrig {
namespace {

constexpr std::string_view kStrip = " \t\r\n\"";

}  // namespace

// One pass over the text (csv_scan.h): fields are views into it, numbers by std::from_chars,
// the values go into one row-major buffer.
IoRecord ParseIoRecordCsv(const std::string& text, const std::string& source_name) {
  return ParseIoRecordCsv(text, source_name, nullptr);
}

IoRecord ParseIoRecordCsv(const std::string& text, const std::string& source_name, const CsvColumns* select) {
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument(source_name + ": " + what);
  };
  csv::LineReader lines(text);
  std::string_view line;
  std::vector<std::string_view> fields;
  std::vector<std::string> header;
  while (lines.Next(&line)) {
    const std::string_view trimmed = csv::Trim(line, kStrip);
    if (!trimmed.empty() && trimmed[0] != '#') {
      csv::SplitFields(line, kStrip, &fields);
      header.assign(fields.begin(), fields.end());
      break;
    }
  }
  if (header.empty()) fail("empty file: expected a header line such as 't,u,y'");
  {
    double ignored = 0.0;
    if (csv::ParseDouble(header[0], &ignored))
      fail("missing header line: the first line holds numbers; expected column names such as 't,u,y'");
  }
  int time_column = -1;
  std::vector<int> input_columns, output_columns;
  IoRecord record;
  auto lower = [](const std::string& text) {
    std::string out;
    for (char ch : text) out += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return out;
  };
  if (select != nullptr) {
    auto names = [&] {
      std::string list;
      for (const auto& h : header) list += (list.empty() ? "" : ", ") + h;
      return list;
    };
    auto find = [&](const std::string& name, const char* role) {
      int found = -1;
      for (size_t c = 0; c < header.size(); ++c)
        if (header[c] == name) found = static_cast<int>(c);
      if (found < 0) fail("no column '" + name + "' (" + role + ") in the header; its columns: " + names());
      if (found == time_column || std::count(input_columns.begin(), input_columns.end(), found) > 0 ||
          std::count(output_columns.begin(), output_columns.end(), found) > 0)
        fail("column '" + name + "' is named twice (" + role + ")");
      return found;
    };
    if (!select->time.empty()) {
      time_column = find(select->time, "time");
    } else {
      for (size_t c = 0; c < header.size() && time_column < 0; ++c)
        if (lower(header[c]) == "t" || lower(header[c]) == "time") time_column = static_cast<int>(c);
    }
    for (const auto& name : select->inputs) {
      input_columns.push_back(find(name, "input"));
      record.input_names.push_back(name);
    }
    for (const auto& name : select->outputs) {
      output_columns.push_back(find(name, "output"));
      record.output_names.push_back(name);
    }
  }
  for (size_t c = 0; c < header.size() && select == nullptr; ++c) {
    const std::string name = lower(header[c]);
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
      fail("column '" + header[c] + "' is not t, u… or y… (header must be t,u,y or t,u1,…,y1,…; "
           "a rig's own names are chosen with --u NAME --y NAME)");
    }
  }
  if (time_column < 0) fail("no time column 't' in the header");
  if (input_columns.empty()) fail("no input column ('u' or 'u1', 'u2', …) in the header");
  if (output_columns.empty()) fail("no output column ('y' or 'y1', 'y2', …) in the header");

  const size_t width = header.size();
  std::vector<double> values;  // row-major, `width` per row
  values.reserve(lines.RemainingBytes() / 8);  // a guess (≥ 8 bytes per value): it grows if short
  while (true) {
    // Fast path: a plain numeric row parsed in place; anything else goes the general way.
    const size_t at = values.size();
    values.resize(at + width);
    const size_t used = csv::ParseNumericRow(lines.Rest(), width, values.data() + at);
    if (used > 0) {
      lines.Consume(used);
      continue;
    }
    values.resize(at);
    if (!lines.Next(&line)) break;
    const std::string_view trimmed = csv::Trim(line, kStrip);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    csv::SplitFields(line, kStrip, &fields);
    if (fields.size() != width)
      fail("line " + std::to_string(lines.line_number()) + " has " + std::to_string(fields.size()) +
           " fields, the header has " + std::to_string(width) + " (truncated file?)");
    for (size_t c = 0; c < width; ++c) {
      double value = 0.0;
      if (!csv::ParseDouble(fields[c], &value))
        fail("line " + std::to_string(lines.line_number()) + ", column '" + header[c] + "': '" +
             std::string(fields[c]) + "' is not a number");
      values.push_back(value);
    }
  }
  const long n = static_cast<long>(values.size() / width);
  if (n == 0) fail("no data rows after the header");
  record.t.resize(n);
  record.u.resize(n, input_columns.size());
  record.y.resize(n, output_columns.size());
  for (long r = 0; r < n; ++r) {
    const double* row = values.data() + r * width;
    record.t(r) = row[time_column];
    for (size_t c = 0; c < input_columns.size(); ++c) record.u(r, c) = row[input_columns[c]];
    for (size_t c = 0; c < output_columns.size(); ++c) record.y(r, c) = row[output_columns[c]];
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
  return ParseIoRecordCsv(csv::ReadFile(path, path + ": cannot open the file for reading"), path);
}

IoRecord ReadIoRecordCsv(const std::string& path, const CsvColumns& columns) {
  return ParseIoRecordCsv(csv::ReadFile(path, path + ": cannot open the file for reading"), path, &columns);
}

std::vector<std::string> SplitColumnNames(const std::string& list, const std::string& what) {
  std::vector<std::string> names;
  size_t start = 0;
  while (true) {
    const size_t comma = list.find(',', start);
    const std::string_view item = csv::Trim(std::string_view(list).substr(start, comma == std::string::npos ? std::string::npos : comma - start), kStrip);
    if (item.empty()) throw std::invalid_argument(what + ": an empty column name in '" + list + "'");
    names.emplace_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return names;
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
