// The config readers fed by tests/fuzz/fuzz_config: the key-file text, the JSON config file and
// ConfigValue. Each bad input is std::invalid_argument naming the file or key; the regression
// inputs found by the fuzzer are here as literals.
#include <gtest/gtest.h>

#include <string>

#include "core/transport/service_util.h"
#include "core/transport/signing.h"

namespace idrig {
namespace {

template <class F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ConfigReaders, KeyTextIsHexWithWhitespaceIgnored) {
  const HmacKey key = ParseKeyText(
      "3f9a 1c7e 55d2 b804 6e1f 0a9c 3d7b 2e58\n c4a6 1f09 e7d3 b5a2 c8f1 e04d 6b9a 7c31\n", "k");
  ASSERT_EQ(key.size(), 32u);
  EXPECT_EQ(key[0], 0x3f);
  EXPECT_EQ(key[1], 0x9a);
  EXPECT_EQ(key[31], 0x31);
}

TEST(ConfigReaders, BadKeyTextNamesTheFileAndTheFix) {
  EXPECT_NE(ErrorOf([] { ParseKeyText("3f9g", "/etc/k"); }).find("'/etc/k' must hold hex digits"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseKeyText("3f9", "/etc/k"); }).find("even number of hex digits"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseKeyText(std::string(64, '0'), "/etc/k"); }).find("openssl rand"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseKeyText("", "/etc/k"); }).find("too short"), std::string::npos);
}

TEST(ConfigReaders, ConfigTextMustBeAJsonObject) {
  EXPECT_EQ(ParseJsonConfig(R"({"rig_id":"sim1"})", "c.json")["rig_id"], "sim1");
  EXPECT_NE(ErrorOf([] { ParseJsonConfig(R"({"rig_id":)", "c.json"); })
                .find("config file 'c.json' is not valid JSON"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseJsonConfig("[1, 2]", "c.json"); }).find("must hold a JSON object, got array"),
            std::string::npos);
}

}  // namespace
}  // namespace idrig
