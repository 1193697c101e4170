// ParseIoRecordCsv on arbitrary text: a record or std::invalid_argument naming file, line and column.
#include <stdexcept>
#include <string>

#include "core/io/csv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    idrig::ParseIoRecordCsv(text, "fuzz");
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
