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

// Found by tests/fuzz/fuzz_config (crash-46c586a2, the input below): a seed beyond 2^64 is a JSON
// float, and get<uint64_t>() converted it out of range (undefined behaviour). Integer keys now
// take integral numbers within the type's range, and say so.
TEST(ConfigReaders, IntegerKeysTakeIntegersInRangeOnly) {
  const nlohmann::json crash = ParseJsonConfig(
      R"({"rig_id":"rig-2","model":{"format":"idrig.model/1","kind":"tf","domain":"continuous","Ts":0,)"
      R"("num":[0.5,1],"den":[0,2.5,4,1.5],"delay_s":0},"effectamples":3000,"seed":18893488147419103230})",
      "crash.json");
  EXPECT_NE(ErrorOf([&] { ConfigValue<uint64_t>(crash, "seed", 1); })
                .find("config key 'seed' must be an integer in [0, 18446744073709551615]"),
            std::string::npos);
  const nlohmann::json c = nlohmann::json::parse(
      R"({"max":18446744073709551615,"neg":-5,"half":2.5,"big":3000000000,"text":"7","int":100})");
  EXPECT_EQ(ConfigValue<uint64_t>(c, "max", 1), 18446744073709551615ull);
  EXPECT_EQ(ConfigValue<int>(c, "neg", 1), -5);
  EXPECT_EQ(ConfigValue<int>(c, "int", 1), 100);
  EXPECT_EQ(ConfigValue<int64_t>(c, "big", 1), 3000000000);
  EXPECT_EQ(ConfigValue<int>(c, "absent", 42), 42);
  EXPECT_NE(ErrorOf([&] { ConfigValue<int>(c, "half", 1); }).find("'half' must be an integer"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ConfigValue<int>(c, "big", 1); }).find("[-2147483648, 2147483647]"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ConfigValue<size_t>(c, "neg", 1); }).find("'neg' must be an integer"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ConfigValue<int>(c, "text", 1); }).find("'text' must be an integer"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ConfigValue<double>(c, "text", 1); }).find("'text' has the wrong type"),
            std::string::npos);
  EXPECT_DOUBLE_EQ(ConfigValue<double>(c, "half", 1), 2.5);
}

}  // namespace
}  // namespace idrig
