#pragma once
// CSV records with a header row. SISO: columns t,u,y. MIMO: t,u1,…,unu,y1,…,yny.
// Column names starting with 'u' are inputs, with 'y' outputs; 't' is time [s].
#include <string>
#include <vector>

#include "core/numeric/io_record.h"

namespace idrig {

// Reads and validates a record. Throws std::invalid_argument naming the file and the problem:
// unreadable file, empty file, missing header, missing or misnamed columns, a row with the
// wrong number of fields or a field that is not a number (with line number), NaN/Inf,
// non-increasing or non-uniform time.
IoRecord ReadIoRecordCsv(const std::string& path);
IoRecord ParseIoRecordCsv(const std::string& text, const std::string& source_name = "<text>");

// A rig's own column names: the named columns (exact match) are the inputs and outputs, in the
// order given; the time column is `time` when given, else 't' or 'time' (any case); every other
// column is read (it must hold numbers) and left out. Throws std::invalid_argument naming a
// column that is missing (with the header's names) or named twice.
struct CsvColumns {
  std::vector<std::string> inputs, outputs;
  std::string time;
};
IoRecord ReadIoRecordCsv(const std::string& path, const CsvColumns& columns);
IoRecord ParseIoRecordCsv(const std::string& text, const std::string& source_name, const CsvColumns* columns);
// "a,b" -> {"a", "b"} (items trimmed; an empty item is an error naming `what`).
std::vector<std::string> SplitColumnNames(const std::string& list, const std::string& what);

// Writes t, inputs, outputs with full precision. Throws std::runtime_error on I/O failure.
void WriteIoRecordCsv(const IoRecord& record, const std::string& path);
std::string FormatIoRecordCsv(const IoRecord& record);

}  // namespace idrig
