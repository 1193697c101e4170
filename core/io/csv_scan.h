#pragma once
// The one CSV scanner of core/io (records csv.cc, FRF tables frf_csv.cc): one pass over the text
// held in memory, fields as string_views into it (no allocation per field or per line), numbers
// by std::from_chars. The callers keep their own grammar and error messages.
#include <string>
#include <string_view>
#include <vector>

namespace idrig::csv {

// The whole file in one read. Throws std::invalid_argument(`unreadable_message`) when it cannot
// be opened or read.
std::string ReadFile(const std::string& path, const std::string& unreadable_message);

// Lines of `text` split at '\n' (a '\r' before it stays in the line; trimming removes it).
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}
  // The next line (without '\n'); false at the end. `line_number` counts from 1.
  bool Next(std::string_view* line) {
    if (pos_ >= text_.size()) return false;  // as std::getline: "a\n" is one line
    const size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) {
      *line = text_.substr(pos_);
      pos_ = text_.size();
    } else {
      *line = text_.substr(pos_, end - pos_);
      pos_ = end + 1;
    }
    ++line_number_;
    return true;
  }
  int line_number() const { return line_number_; }
  // Bytes not yet read (for reserving).
  size_t RemainingBytes() const { return pos_ < text_.size() ? text_.size() - pos_ : 0; }
  // The fast path of a caller that parsed the next line itself: the unread text, and a step
  // past `bytes` of it holding one line (its '\n' included).
  std::string_view Rest() const { return pos_ < text_.size() ? text_.substr(pos_) : std::string_view(); }
  void Consume(size_t bytes) {
    pos_ += bytes;
    ++line_number_;
  }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  int line_number_ = 0;
};

// `s` without leading and trailing characters of `strip`.
inline std::string_view Trim(std::string_view s, std::string_view strip) {
  const size_t begin = s.find_first_not_of(strip);
  if (begin == std::string_view::npos) return {};
  const size_t end = s.find_last_not_of(strip);
  return s.substr(begin, end - begin + 1);
}

// Splits at every ',' ("a,b," gives three fields, the last empty), each field trimmed of
// `strip`; `fields` is reused (its capacity stays).
void SplitFields(std::string_view line, std::string_view strip, std::vector<std::string_view>* fields);

// A whole field as a double, as strtod reads it (optional sign, decimal or exponent form, inf,
// infinity, nan, any case; out-of-range values become ±inf or 0 as strtod gives them). False
// when the field is empty or anything is left over.
bool ParseDouble(std::string_view field, double* value);

// Fast path for a plain numeric row at the start of `rest`: `width` numbers separated by ',',
// blanks (' ', '\t') around them, the line ended by '\n', "\r\n" or the end of the text.
// Returns the bytes of the line (with its '\n') and fills values[0..width), or 0 when the line
// is anything else (comment, blank, quotes, '+', wrong field count, not a number): the caller
// then takes the general path, which names the problem.
size_t ParseNumericRow(std::string_view rest, size_t width, double* values);

}  // namespace idrig::csv
