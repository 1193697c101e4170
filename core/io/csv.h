#pragma once
// CSV records with a header row. SISO: columns t,u,y. MIMO: t,u1,…,unu,y1,…,yny.
// Column names starting with 'u' are inputs, with 'y' outputs; 't' is time [s].
#include <string>

#include "core/numeric/io_record.h"

namespace idrig {

// Reads and validates a record. Throws std::invalid_argument naming the file and the problem:
// unreadable file, empty file, missing header, missing or misnamed columns, a row with the
// wrong number of fields or a field that is not a number (with line number), NaN/Inf,
// non-increasing or non-uniform time.
IoRecord ReadIoRecordCsv(const std::string& path);
IoRecord ParseIoRecordCsv(const std::string& text, const std::string& source_name = "<text>");

// Writes t, inputs, outputs with full precision. Throws std::runtime_error on I/O failure.
void WriteIoRecordCsv(const IoRecord& record, const std::string& path);
std::string FormatIoRecordCsv(const IoRecord& record);

}  // namespace idrig
