// SPEC string grammar of excitation signals (docs/excitation.md):
//   spec   := kind [ ":" pair { "," pair } ]
//   pair   := key "=" value
//   kind   := step | exp | sine | multisine | prbs | rbs | chirp
//   list   := item { ";" item },  item := integer | integer "-" integer   (lines=)
//   reals  := real { ";" real }                                           (amps=, phases=)
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/numeric/signal/excitation.h"

namespace idrig {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

[[noreturn]] void Fail(const std::string& text, const std::string& message) {
  throw std::invalid_argument("excitation spec '" + text + "': " + message);
}

std::string Trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  const auto end = s.find_last_not_of(" \t");
  return s.substr(begin, end - begin + 1);
}

std::vector<std::string> Split(const std::string& s, char separator) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(s);
  while (std::getline(in, part, separator)) parts.push_back(Trim(part));
  if (!s.empty() && s.back() == separator) parts.push_back("");
  return parts;
}

double ParseReal(const std::string& text, const std::string& key, const std::string& value) {
  size_t used = 0;
  double x = 0.0;
  try {
    x = std::stod(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != value.size() || !std::isfinite(x))
    Fail(text, key + "=" + value + " is not a finite number");
  return x;
}

long long ParseInteger(const std::string& text, const std::string& key, const std::string& value) {
  size_t used = 0;
  long long x = 0;
  try {
    x = std::stoll(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != value.size()) Fail(text, key + "=" + value + " is not an integer");
  return x;
}

std::vector<int> ParseLines(const std::string& text, const std::string& value) {
  std::vector<int> lines;
  for (const std::string& item : Split(value, ';')) {
    if (item.empty()) Fail(text, "lines=" + value + " has an empty item");
    const auto dash = item.find('-', 1);
    if (dash == std::string::npos) {
      const long long n = ParseInteger(text, "lines", item);
      if (n < 1 || n > std::numeric_limits<int>::max())
        Fail(text, "lines must be positive integers (harmonics of f0), got " + item);
      lines.push_back(static_cast<int>(n));
    } else {
      const long long first = ParseInteger(text, "lines", Trim(item.substr(0, dash)));
      const long long last = ParseInteger(text, "lines", Trim(item.substr(dash + 1)));
      if (first < 1 || last < first || last > std::numeric_limits<int>::max())
        Fail(text, "lines range '" + item + "' must be a-b with 1 <= a <= b");
      // The sum of the ranges, checked before the loop (each range alone was capped at 10^6:
      // "lines=1198-886128;8-886128;…", 3.5 M lines, took 15 s; found by fuzz_excitation_spec).
      if (last - first + 1 > kMaxMultisineLines - static_cast<long long>(lines.size()))
        Fail(text, "lines=" + value + " lists more than " + std::to_string(kMaxMultisineLines) +
                       " lines");
      for (long long n = first; n <= last; ++n) lines.push_back(static_cast<int>(n));
    }
    if (static_cast<long long>(lines.size()) > kMaxMultisineLines)
      Fail(text, "lines=" + value + " lists more than " + std::to_string(kMaxMultisineLines) + " lines");
  }
  for (int n : lines)
    if (n < 1) Fail(text, "lines must be positive integers (harmonics of f0), got " + std::to_string(n));
  return lines;
}

std::vector<double> ParseReals(const std::string& text, const std::string& key,
                               const std::string& value) {
  std::vector<double> values;
  for (const std::string& item : Split(value, ';')) values.push_back(ParseReal(text, key, item));
  return values;
}

std::string Join(const std::set<std::string>& keys) {
  std::string out;
  for (const auto& k : keys) out += (out.empty() ? "" : ", ") + k;
  return out;
}

// Shortest of 15 or 17 significant digits that reads back to the same double.
std::string Num(double value) {
  for (int digits : {15, 17}) {
    std::ostringstream out;
    out.precision(digits);
    out << value;
    if (digits == 17 || std::stod(out.str()) == value) return out.str();
  }
  return "";
}

// Harmonic numbers as ranges: 1;2;3;5 -> 1-3;5.
std::string FormatLines(const std::vector<int>& lines) {
  std::string out;
  for (size_t i = 0; i < lines.size();) {
    size_t j = i;
    while (j + 1 < lines.size() && lines[j + 1] == lines[j] + 1) ++j;
    out += (out.empty() ? "" : ";") + std::to_string(lines[i]);
    if (j > i) out += "-" + std::to_string(lines[j]);
    i = j + 1;
  }
  return out;
}

}  // namespace

ExcitationSpec ParseExcitationSpec(const std::string& raw) {
  const std::string text = Trim(raw);
  const auto colon = text.find(':');
  const std::string kind = Trim(text.substr(0, colon));
  ExcitationSpec spec;
  static const std::map<std::string, ExcitationKind> kKinds = {
      {"step", ExcitationKind::kStep},       {"exp", ExcitationKind::kExponential},
      {"sine", ExcitationKind::kSine},       {"multisine", ExcitationKind::kMultisine},
      {"prbs", ExcitationKind::kPrbs},       {"rbs", ExcitationKind::kRandomBinary},
      {"chirp", ExcitationKind::kChirp},     {"diagnose", ExcitationKind::kDiagnose}};
  const auto found = kKinds.find(kind);
  if (found == kKinds.end())
    Fail(text, "unknown signal kind '" + kind +
                   "'; use one of step, exp, sine, multisine, prbs, rbs, chirp, diagnose");
  spec.kind = found->second;
  std::set<std::string> allowed = {"amp", "offset"};
  switch (spec.kind) {
    case ExcitationKind::kStep: allowed.insert({"at"}); break;
    case ExcitationKind::kExponential: allowed.insert({"at", "T"}); break;
    case ExcitationKind::kSine: allowed.insert({"f", "w", "phase"}); break;
    case ExcitationKind::kMultisine:
      allowed.insert({"f0", "w0", "lines", "set", "phase", "amps", "phases", "scale", "seed"});
      break;
    case ExcitationKind::kPrbs: allowed.insert({"bits", "fc"}); break;
    case ExcitationKind::kRandomBinary: allowed.insert({"fc", "seed"}); break;
    case ExcitationKind::kChirp: allowed.insert({"f0", "f1", "T", "sweep"}); break;
    case ExcitationKind::kDiagnose:
      allowed.insert({"T", "f1", "seed"});
      spec.sweep_time = 60.0;
      spec.end_frequency_hz = 1.0;
      break;
  }
  std::set<std::string> seen;
  if (colon != std::string::npos) {
    for (const std::string& pair : Split(text.substr(colon + 1), ',')) {
      const auto eq = pair.find('=');
      if (pair.empty() || eq == std::string::npos || eq == 0)
        Fail(text, "expected key=value, got '" + pair + "'");
      const std::string key = Trim(pair.substr(0, eq));
      const std::string value = Trim(pair.substr(eq + 1));
      if (!allowed.count(key))
        Fail(text, "unknown key '" + key + "' for " + kind + "; allowed: " + Join(allowed));
      if (!seen.insert(key).second) Fail(text, "key '" + key + "' given twice");
      if (value.empty()) Fail(text, "key '" + key + "' has no value");
      if (key == "amp") {
        spec.amplitude = ParseReal(text, key, value);
      } else if (key == "offset") {
        spec.offset = ParseReal(text, key, value);
      } else if (key == "at") {
        spec.start_time = ParseReal(text, key, value);
      } else if (key == "T") {
        (spec.kind == ExcitationKind::kChirp || spec.kind == ExcitationKind::kDiagnose
             ? spec.sweep_time
             : spec.time_constant) =
            ParseReal(text, key, value);
      } else if (key == "f") {
        spec.frequency_hz = ParseReal(text, key, value);
      } else if (key == "w") {
        spec.frequency_hz = ParseReal(text, key, value) / kTwoPi;
      } else if (key == "phase" && spec.kind == ExcitationKind::kSine) {
        spec.phase = ParseReal(text, key, value);
      } else if (key == "phase") {
        if (value == "zero") spec.phase_rule = MultisinePhase::kZero;
        else if (value == "schroeder") spec.phase_rule = MultisinePhase::kSchroeder;
        else if (value == "random") spec.phase_rule = MultisinePhase::kRandom;
        else Fail(text, "phase=" + value + " is not one of zero, schroeder, random");
      } else if (key == "f0") {
        (spec.kind == ExcitationKind::kChirp ? spec.start_frequency_hz : spec.base_frequency_hz) =
            ParseReal(text, key, value);
      } else if (key == "w0") {
        spec.base_frequency_hz = ParseReal(text, key, value) / kTwoPi;
      } else if (key == "f1") {
        spec.end_frequency_hz = ParseReal(text, key, value);
      } else if (key == "lines") {
        spec.lines = ParseLines(text, value);
      } else if (key == "set") {
        if (value == "all") spec.line_set = MultisineLineSet::kAll;
        else if (value == "odd") spec.line_set = MultisineLineSet::kOdd;
        else if (value == "oddodd" || value == "odd-odd") spec.line_set = MultisineLineSet::kOddOdd;
        else Fail(text, "set=" + value + " is not one of all, odd, oddodd");
      } else if (key == "scale") {
        if (value == "line") spec.scale = MultisineScale::kLine;
        else if (value == "rms") spec.scale = MultisineScale::kRms;
        else Fail(text, "scale=" + value + " is not one of line, rms");
      } else if (key == "amps") {
        spec.line_amplitudes = ParseReals(text, key, value);
      } else if (key == "phases") {
        spec.line_phases = ParseReals(text, key, value);
      } else if (key == "seed") {
        const long long seed = ParseInteger(text, key, value);
        if (seed < 0) Fail(text, "seed must be >= 0");
        spec.seed = static_cast<uint64_t>(seed);
      } else if (key == "bits") {
        const long long bits = ParseInteger(text, key, value);
        if (bits < 2 || bits > 32) Fail(text, "bits=" + value + " must be in 2..32");
        spec.register_bits = static_cast<int>(bits);
      } else if (key == "fc") {
        spec.clock_hz = ParseReal(text, key, value);
      } else if (key == "sweep") {
        if (value == "linear" || value == "lin") spec.sweep = ChirpSweep::kLinear;
        else if (value == "log") spec.sweep = ChirpSweep::kLogarithmic;
        else Fail(text, "sweep=" + value + " is not one of linear, log");
      }
    }
  }
  if (seen.count("f") && seen.count("w")) Fail(text, "give f (Hz) or w (rad/s), not both");
  if (seen.count("f0") && seen.count("w0")) Fail(text, "give f0 (Hz) or w0 (rad/s), not both");
  if (spec.kind == ExcitationKind::kMultisine && seen.count("phases") && seen.count("phase"))
    Fail(text, "give phase=<rule> or phases=<list>, not both");
  // Checks that do not need the sample rate (the rest happen in ValidateExcitation).
  try {
    if (spec.kind == ExcitationKind::kMultisine) MultisineLines(spec);
    ValidateExcitation(spec, 1e300);
  } catch (const std::invalid_argument& e) {
    Fail(text, e.what());
  }
  return spec;
}

std::string FormatExcitationSpec(const ExcitationSpec& spec) {
  std::string out = ToString(spec.kind);
  out += ":amp=" + Num(spec.amplitude);
  if (spec.offset != 0.0) out += ",offset=" + Num(spec.offset);
  auto list = [](const auto& values) {
    std::string s;
    for (const auto& v : values) s += (s.empty() ? "" : ";") + Num(v);
    return s;
  };
  switch (spec.kind) {
    case ExcitationKind::kStep: out += ",at=" + Num(spec.start_time); break;
    case ExcitationKind::kExponential:
      out += ",at=" + Num(spec.start_time) + ",T=" + Num(spec.time_constant);
      break;
    case ExcitationKind::kSine:
      out += ",f=" + Num(spec.frequency_hz) + ",phase=" + Num(spec.phase);
      break;
    case ExcitationKind::kMultisine: {
      out += ",f0=" + Num(spec.base_frequency_hz);
      if (!spec.lines.empty()) out += ",lines=" + FormatLines(spec.lines);
      static const char* kSets[] = {"all", "odd", "oddodd"};
      static const char* kPhases[] = {"zero", "schroeder", "random"};
      out += std::string(",set=") + kSets[static_cast<int>(spec.line_set)];
      if (!spec.line_phases.empty()) out += ",phases=" + list(spec.line_phases);
      else out += std::string(",phase=") + kPhases[static_cast<int>(spec.phase_rule)];
      if (!spec.line_amplitudes.empty()) out += ",amps=" + list(spec.line_amplitudes);
      out += spec.scale == MultisineScale::kRms ? ",scale=rms" : ",scale=line";
      out += ",seed=" + std::to_string(spec.seed);
      break;
    }
    case ExcitationKind::kPrbs:
      out += ",bits=" + std::to_string(spec.register_bits) + ",fc=" + Num(spec.clock_hz);
      break;
    case ExcitationKind::kRandomBinary:
      out += ",fc=" + Num(spec.clock_hz) + ",seed=" + std::to_string(spec.seed);
      break;
    case ExcitationKind::kChirp:
      out += ",f0=" + Num(spec.start_frequency_hz) + ",f1=" + Num(spec.end_frequency_hz) +
             ",T=" + Num(spec.sweep_time) +
             (spec.sweep == ChirpSweep::kLinear ? ",sweep=linear" : ",sweep=log");
      break;
    case ExcitationKind::kDiagnose:
      out += ",T=" + Num(spec.sweep_time) + ",f1=" + Num(spec.end_frequency_hz) +
             ",seed=" + std::to_string(spec.seed);
      break;
  }
  return out;
}

}  // namespace idrig
