#include "core/io/csv_scan.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace idrig::csv {

std::string ReadFile(const std::string& path, const std::string& unreadable_message) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) throw std::invalid_argument(unreadable_message);
  std::string content;
  if (std::fseek(file, 0, SEEK_END) == 0) {
    const long size = std::ftell(file);
    if (size > 0) content.resize(static_cast<size_t>(size));
    std::rewind(file);
  }
  size_t got = content.empty() ? 0 : std::fread(content.data(), 1, content.size(), file);
  content.resize(got);
  // Not seekable (a pipe) or grown meanwhile: read the rest in blocks.
  char block[1 << 16];
  size_t more;
  while ((more = std::fread(block, 1, sizeof block, file)) > 0) content.append(block, more);
  const bool error = std::ferror(file) != 0;
  std::fclose(file);
  if (error) throw std::invalid_argument(unreadable_message);
  return content;
}

size_t ParseNumericRow(std::string_view rest, size_t width, double* values) {
  const char* const begin = rest.data();
  const char* const end = begin + rest.size();
  const char* p = begin;
  for (size_t c = 0; c < width; ++c) {
    while (p < end && (*p == ' ' || *p == '\t')) ++p;
    if (p == end || *p == '+' || *p == '"' || *p == '#') return 0;
    const auto [next, ec] = std::from_chars(p, end, values[c], std::chars_format::general);
    if (ec != std::errc()) return 0;  // out of range or not a number: the general path
    p = next;
    while (p < end && (*p == ' ' || *p == '\t')) ++p;
    if (c + 1 < width) {
      if (p == end || *p != ',') return 0;
      ++p;
    }
  }
  if (p < end && *p == '\r') ++p;
  if (p == end) return static_cast<size_t>(p - begin);
  if (*p != '\n') return 0;
  return static_cast<size_t>(p + 1 - begin);
}

void SplitFields(std::string_view line, std::string_view strip, std::vector<std::string_view>* fields) {
  fields->clear();
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields->push_back(Trim(line.substr(start), strip));
      return;
    }
    fields->push_back(Trim(line.substr(start, comma - start), strip));
    start = comma + 1;
  }
}

bool ParseDouble(std::string_view field, double* value) {
  if (field.empty()) return false;
  const char* begin = field.data();
  const char* end = begin + field.size();
  // from_chars takes no leading '+' (strtod does); "+-1" stays an error.
  const char* first = begin;
  if (*first == '+' && end - first > 1 && first[1] != '-' && first[1] != '+') ++first;
  const auto [ptr, ec] = std::from_chars(first, end, *value, std::chars_format::general);
  if (ec == std::errc::result_out_of_range) {
    // ±HUGE_VAL on overflow, a denormal or 0 on underflow, as strtod: rare, so take strtod.
    const std::string copy(field);
    char* stop = nullptr;
    *value = std::strtod(copy.c_str(), &stop);
    return stop == copy.c_str() + copy.size();
  }
  return ec == std::errc() && ptr == end;
}

}  // namespace idrig::csv
