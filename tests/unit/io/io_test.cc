// CSV records and model JSON: round trips and every bad input named in the foundation issue.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "core/io/csv.h"
#include "core/io/model_json.h"

namespace idrig {
namespace {

void ExpectError(const std::string& csv, const std::string& fragment) {
  try {
    ParseIoRecordCsv(csv, "rec.csv");
    FAIL() << "accepted: " << csv;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rec.csv"), std::string::npos) << e.what();
  }
}

TEST(Csv, SisoAndMimoRoundTrip) {
  const IoRecord siso = ParseIoRecordCsv("t,u,y\n0,1,2\n0.5,3,4\n1,5,6\n");
  EXPECT_EQ(siso.NumInputs(), 1);
  EXPECT_DOUBLE_EQ(siso.sample_time, 0.5);
  EXPECT_DOUBLE_EQ(siso.y(2, 0), 6.0);
  const IoRecord mimo = ParseIoRecordCsv("t,u1,u2,y1,y2,y3\n0,1,2,3,4,5\n1,1,2,3,4,5\n");
  EXPECT_EQ(mimo.NumInputs(), 2);
  EXPECT_EQ(mimo.NumOutputs(), 3);
  const IoRecord again = ParseIoRecordCsv(FormatIoRecordCsv(mimo));
  EXPECT_EQ(again.u, mimo.u);
  EXPECT_EQ(again.y, mimo.y);
}

TEST(Csv, TimesPrintedWithFewDigitsAreTheUniformGrid) {
  // t = k/300 s printed with "%.4f" (±5e-5 s per value: ±1.5 % of the step, ±3 % per step):
  // accepted, with the mean step as the sample time.
  std::string csv = "t,u,y\n";
  char line[64];
  for (int k = 0; k < 3000; ++k) {
    std::snprintf(line, sizeof line, "%.4f,%d,%d\n", k / 300.0, k % 2, k % 3);
    csv += line;
  }
  const IoRecord record = ParseIoRecordCsv(csv);
  EXPECT_NEAR(record.sample_time, 1 / 300.0, 1e-7);
  EXPECT_EQ(record.NumSamples(), 3000);
  // A missing sample in the same file is still an error.
  const auto cut = csv.find("\n", csv.find("\n3.3333,") + 1) + 1;
  const std::string missing = csv.substr(0, csv.find("\n3.3333,") + 1) + csv.substr(cut);
  EXPECT_THROW(ParseIoRecordCsv(missing), std::invalid_argument);
}

TEST(CsvBadInput, EachProblemIsNamed) {
  ExpectError("", "empty file");
  ExpectError("0,1,2\n1,2,3\n", "missing header");
  ExpectError("t,u\n0,1\n", "no output column");
  ExpectError("time,x,y\n0,1,2\n", "column 'x'");
  ExpectError("u,y\n1,2\n", "no time column");
  ExpectError("t,u,y\n", "no data rows");
  ExpectError("t,u,y\n0,1,2\n1,2\n", "line 3 has 2 fields");
  ExpectError("t,u,y\n0,1,2\n1,abc,3\n", "'abc' is not a number");
  ExpectError("t,u,y\n0,1,2\n1,nan,3\n", "NaN in input column 'u' at sample 1");
  ExpectError("t,u,y\n0,1,2\n1,1,inf\n", "Inf in output column 'y' at sample 1");
  ExpectError("t,u,y\n0,1,2\n1,1,2\n1,1,2\n", "not increasing at sample 2");
  ExpectError("t,u,y\n0,1,2\n1,1,2\n2.5,1,2\n3.5,1,2\n", "not uniform");
}

// A record with a stretch cut out (a splice) is named at the jump, against the record's own
// step: the mean step, which the jump distorts, had put the fault at the first sample.
TEST(Csv, ASplicedRecordIsNamedAtItsJump) {
  std::string text = "t,u,y\n";
  for (int k = 0; k < 1000; ++k) {
    if (k >= 600 && k < 800) continue;  // 200 samples cut out
    text += std::to_string(0.01 * k) + ",1,2\n";
  }
  ExpectError(text, "not uniform at sample 600: t jumps from 5.99 to 8 s where the record's step is 0.01 s "
                    "(about 200 samples missing or two records spliced there; 1 such step)");
  std::string drift = "t,u,y\n";
  for (int k = 0; k < 400; ++k) drift += std::to_string(0.0101 * k * (1.0 + 0.002 * k)) + ",1,2\n";
  ExpectError(drift, "not uniform");
}

// The one-pass parser (csv_scan.h) reads numbers as strtod did: signs, exponents, CRLF line
// ends, quotes and spaces around fields, comment and blank lines, a last line without '\n'.
TEST(Csv, NumberFormsAndLineEndsAsBefore) {
  const IoRecord r = ParseIoRecordCsv(
      "# comment\r\n\"t\", u , y\r\n\r\n+0,-1.5e0,\"2\"\r\n# inside\r\n1.0,+.25,  -3E-1 \r\n2,1e2,4.");
  ASSERT_EQ(r.NumSamples(), 3);
  EXPECT_EQ(r.u(0, 0), -1.5);
  EXPECT_EQ(r.u(1, 0), 0.25);
  EXPECT_EQ(r.y(1, 0), -0.3);
  EXPECT_EQ(r.u(2, 0), 100.0);
  EXPECT_EQ(r.y(2, 0), 4.0);
  EXPECT_DOUBLE_EQ(r.sample_time, 1.0);
  // Out of range: strtod's ±HUGE_VAL, then named as Inf; "+-1" and "1.5x" are not numbers.
  ExpectError("t,u,y\n0,1,2\n1,1e999,2\n", "Inf in input column 'u' at sample 1");
  ExpectError("t,u,y\n0,1,2\n1,+-1,2\n", "line 3, column 'u': '+-1' is not a number");
  ExpectError("t,u,y\n0,1,2\n1,1.5x,2\n", "line 3, column 'u': '1.5x' is not a number");
  ExpectError("t,u,y\n0,1,2\n1,1,2,\n", "line 3 has 4 fields, the header has 3");
  // The same text from a file (one read) gives the same record.
  const std::string path = ::testing::TempDir() + "/csv_forms.csv";
  std::ofstream("" + path) << "t,u,y\n0,1,2\n0.5,3,4\n";
  const IoRecord f = ReadIoRecordCsv(path);
  EXPECT_EQ(f.NumSamples(), 2);
  EXPECT_EQ(f.y(1, 0), 4.0);
  std::remove(path.c_str());
}

// A rig's own column names (identify/gap diagnose --u --y --time): the named columns in the
// order given, other columns left out; without a selection such a header is refused.
TEST(Csv, ColumnsChosenByName) {
  const std::string text = "stamp,mode,valve_b,valve_a,level\n0,1,0.5,1,10\n0.5,1,0.25,2,11\n1,2,0,3,12\n";
  const CsvColumns rig{{"valve_a", "valve_b"}, {"level"}, "stamp"};
  const IoRecord r = ParseIoRecordCsv(text, "rig.csv", &rig);
  ASSERT_EQ(r.NumInputs(), 2);
  ASSERT_EQ(r.NumOutputs(), 1);
  EXPECT_DOUBLE_EQ(r.u(1, 0), 2.0);
  EXPECT_DOUBLE_EQ(r.u(1, 1), 0.25);
  EXPECT_DOUBLE_EQ(r.y(2, 0), 12.0);
  EXPECT_DOUBLE_EQ(r.sample_time, 0.5);
  EXPECT_EQ(r.input_names, (std::vector<std::string>{"valve_a", "valve_b"}));
  const CsvColumns fx{{"f"}, {"x"}, ""};
  const IoRecord t = ParseIoRecordCsv("Time,f,x\n0,1,2\n0.1,3,4\n", "t.csv", &fx);
  EXPECT_DOUBLE_EQ(t.sample_time, 0.1);
  auto message = [&](const CsvColumns& c) {
    try {
      ParseIoRecordCsv(text, "rig.csv", &c);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message({{"valve_a"}, {"lvl"}, "stamp"}),
            "rig.csv: no column 'lvl' (output) in the header; its columns: stamp, mode, valve_b, valve_a, level");
  EXPECT_EQ(message({{"valve_a"}, {"valve_a"}, "stamp"}), "rig.csv: column 'valve_a' is named twice (output)");
  EXPECT_EQ(message({{"valve_a"}, {"level"}, ""}), "rig.csv: no time column 't' in the header");
  EXPECT_NE(message({{"valve_a"}, {"level"}, "mode"}).find("not increasing"), std::string::npos);
  EXPECT_THROW(ParseIoRecordCsv(text, "rig.csv"), std::invalid_argument);
  EXPECT_EQ(SplitColumnNames(" a, b ", "--u"), (std::vector<std::string>{"a", "b"}));
  EXPECT_THROW(SplitColumnNames("a,,b", "--u"), std::invalid_argument);
}

TEST(CsvBadInput, UnreadableFile) {
  EXPECT_THROW(ReadIoRecordCsv("/nonexistent/dir/rec.csv"), std::invalid_argument);
}

TEST(ModelJson, RoundTripTfAndSs) {
  TransferFunction tf{Eigen::Vector2d(0.5, 1.0), Eigen::Vector4d(1, 2.5, 4, 1.5), 0.0, 0.3};
  const auto back = std::get<TransferFunction>(ModelFromJson(ModelToJson(tf)));
  EXPECT_EQ(back.num, tf.num);
  EXPECT_EQ(back.den, tf.den);
  EXPECT_DOUBLE_EQ(back.delay_s, 0.3);
  StateSpace ss{Eigen::MatrixXd::Identity(2, 2) * 0.5, Eigen::MatrixXd::Ones(2, 1), Eigen::MatrixXd::Ones(1, 2),
                Eigen::MatrixXd::Zero(1, 1), 0.1};
  const auto ss_back = std::get<StateSpace>(ModelFromJson(ModelToJson(ss)));
  EXPECT_EQ(ss_back.A, ss.A);
  EXPECT_DOUBLE_EQ(ss_back.sample_time, 0.1);
  // The issue's literal example is accepted.
  const auto parsed = ModelFromJson(nlohmann::json::parse(
      R"({"format":"idrig.model/1","kind":"tf","domain":"discrete","Ts":0.2,"num":[1],"den":[1,-0.5]})"));
  EXPECT_DOUBLE_EQ(std::get<TransferFunction>(parsed).sample_time, 0.2);
}

TEST(ModelJsonBadInput, UnreadableOrMalformedModelFiles) {
  const std::string dir = ::testing::TempDir();
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir + name) << text;
    return dir + name;
  };
  auto expect = [](const std::string& path, const std::string& fragment) {
    try {
      ReadModelFile(path);
      FAIL() << path;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  expect(dir + "missing.json", "cannot open");
  expect(write("trunc.json", R"({"format":"idrig.model/1","kind":"tf","num":[1)"), "not valid JSON");
  expect(write("fmt.json", R"({"format":"other","kind":"tf"})"), "\"format\"");
  expect(write("kind.json", R"({"format":"idrig.model/1","kind":"zpk"})"), "\"kind\"");
  expect(write("den.json", R"({"format":"idrig.model/1","kind":"tf","num":[1]})"), "missing \"den\"");
  expect(write("ts.json", R"({"format":"idrig.model/1","kind":"tf","domain":"discrete","num":[1],"den":[1,2]})"), "Ts");
  expect(write("rows.json", R"({"format":"idrig.model/1","kind":"ss","A":[[1,2],[3]],"B":[[1],[1]],"C":[[1,0]],"D":[[0]]})"), "rows have different lengths");
  expect(write("str.json", R"({"format":"idrig.model/1","kind":"tf","num":["a"],"den":[1,2]})"), "must be a number");
  // Found by tests/fuzz/fuzz_model_json (crash-101a1d30): a non-string "domain" threw
  // nlohmann's type_error instead of std::invalid_argument.
  expect(write("domain.json", R"({"format":"idrig.model/1","kind":"tf","domain":0,"num":[0.5,1],"den":[1,2.5,4,1.5],"delay_s":0})"),
         "\"domain\" must be");
}

}  // namespace
}  // namespace idrig
