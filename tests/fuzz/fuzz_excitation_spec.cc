// The excitation SPEC parser (docs/excitation.md) on arbitrary text: a spec or
// std::invalid_argument naming the problem, nothing else.
#include <stdexcept>
#include <string>

#include "core/numeric/signal/excitation.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const idrig::ExcitationSpec spec = idrig::ParseExcitationSpec(text);
    idrig::FormatExcitationSpec(spec);
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
