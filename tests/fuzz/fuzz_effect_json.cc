// EffectFromJson on arbitrary JSON text: a value or std::invalid_argument naming the problem.
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "core/io/gap_json.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const nlohmann::json json =
      nlohmann::json::parse(reinterpret_cast<const char*>(data),
                            reinterpret_cast<const char*>(data) + size, nullptr, false);
  if (json.is_discarded()) return 0;
  try {
    idrig::EffectFromJson(json);
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
