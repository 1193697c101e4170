#pragma once
// FRF tables as CSV with a header row.
//   SISO:  f_hz,re,im
//   MIMO:  f_hz,re_1_1,im_1_1,re_2_1,im_2_1,…   (re_<output>_<input>, 1-based, any order,
//          every output/input pair present exactly once)
// Optional noise columns: sigma (SISO) or sigma_<output>_<input>, the standard deviation of the
// complex noise on that element (σ² = E|e|²), for every element or none; they become
// Frf::variance (σ²) and the frequency methods weight each line by 1/σ (maximum likelihood).
// The first column may instead be w_rad_s (angular frequency). Frequencies are converted to
// rad/s (Frf::omega). A file whose first header field is `t` is a time record (csv.h).
#include <string>

#include "core/numeric/signal/frf.h"

namespace idrig {

// Throws std::invalid_argument naming the file and the problem: unreadable, empty, unknown
// frequency column, unpaired/misnamed/duplicate re/im columns, missing output/input pairs, a
// row with the wrong number of fields or a non-number (with line number), NaN/Inf.
// Frequency order and sign are checked by the methods (ValidateFrf), not here.
Frf ReadFrfCsv(const std::string& path);
Frf ParseFrfCsv(const std::string& text, const std::string& source_name = "<text>");

// Writes f_hz and the column pairs (and sigma columns when the FRF has a variance) with full precision. Throws std::runtime_error on I/O failure.
void WriteFrfCsv(const Frf& frf, const std::string& path);

// True when the first header field of the file is `t` (a time record, not an FRF table).
bool IsTimeRecordCsv(const std::string& path);

}  // namespace idrig
