#include "core/io/model_json.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace idrig {
namespace {

using nlohmann::json;

json VectorToJson(const Eigen::VectorXd& v) {
  json out = json::array();
  for (int i = 0; i < v.size(); ++i) out.push_back(v(i));
  return out;
}

json MatrixToJson(const Eigen::MatrixXd& m) {
  json out = json::array();
  for (int r = 0; r < m.rows(); ++r) {
    json row = json::array();
    for (int c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    out.push_back(row);
  }
  return out;
}

double Number(const json& j, const std::string& where) {
  if (!j.is_number()) throw std::invalid_argument("model JSON: " + where + " must be a number");
  return j.get<double>();
}

Eigen::VectorXd JsonToVector(const json& j, const std::string& key) {
  if (!j.is_array() || j.empty())
    throw std::invalid_argument("model JSON: \"" + key + "\" must be a non-empty array of numbers");
  Eigen::VectorXd v(j.size());
  for (size_t i = 0; i < j.size(); ++i) v(i) = Number(j[i], "\"" + key + "\"[" + std::to_string(i) + "]");
  return v;
}

Eigen::MatrixXd JsonToMatrix(const json& j, const std::string& key) {
  if (!j.is_array())
    throw std::invalid_argument("model JSON: \"" + key + "\" must be an array of rows");
  const size_t rows = j.size();
  size_t cols = 0;
  for (size_t r = 0; r < rows; ++r) {
    if (!j[r].is_array())
      throw std::invalid_argument("model JSON: \"" + key + "\" row " + std::to_string(r) + " is not an array");
    if (r == 0) cols = j[r].size();
    else if (j[r].size() != cols)
      throw std::invalid_argument("model JSON: \"" + key + "\" rows have different lengths");
  }
  Eigen::MatrixXd m(rows, cols);
  for (size_t r = 0; r < rows; ++r)
    for (size_t c = 0; c < cols; ++c)
      m(r, c) = Number(j[r][c], "\"" + key + "\"[" + std::to_string(r) + "][" + std::to_string(c) + "]");
  return m;
}

void PutTiming(json* out, double sample_time, double delay_s) {
  (*out)["domain"] = sample_time > 0.0 ? "discrete" : "continuous";
  (*out)["Ts"] = sample_time;
  (*out)["delay_s"] = delay_s;
}

}  // namespace

json ModelToJson(const TransferFunction& tf) {
  json out = {{"format", kModelFormat}, {"kind", "tf"}};
  PutTiming(&out, tf.sample_time, tf.delay_s);
  out["num"] = VectorToJson(tf.num);
  out["den"] = VectorToJson(tf.den);
  return out;
}

json ModelToJson(const StateSpace& ss) {
  json out = {{"format", kModelFormat}, {"kind", "ss"}};
  PutTiming(&out, ss.sample_time, ss.delay_s);
  out["A"] = MatrixToJson(ss.A);
  out["B"] = MatrixToJson(ss.B);
  out["C"] = MatrixToJson(ss.C);
  out["D"] = MatrixToJson(ss.D);
  return out;
}

json ModelToJson(const LtiModel& model) {
  return std::visit([](const auto& m) { return ModelToJson(m); }, model);
}

LtiModel ModelFromJson(const json& j) {
  if (!j.is_object()) throw std::invalid_argument("model JSON: expected an object");
  if (!j.contains("format") || j["format"] != kModelFormat)
    throw std::invalid_argument(std::string("model JSON: \"format\" must be \"") + kModelFormat + "\"");
  if (!j.contains("kind") || !j["kind"].is_string())
    throw std::invalid_argument("model JSON: \"kind\" must be \"tf\" or \"ss\"");
  const std::string kind = j["kind"];
  // A "domain" that is not a string threw nlohmann's type_error from j.value() (fuzz_model_json).
  if (j.contains("domain") && !j["domain"].is_string())
    throw std::invalid_argument("model JSON: \"domain\" must be \"continuous\" or \"discrete\"");
  const std::string domain = j.value("domain", "continuous");
  if (domain != "continuous" && domain != "discrete")
    throw std::invalid_argument("model JSON: \"domain\" must be \"continuous\" or \"discrete\", got \"" + domain + "\"");
  double sample_time = j.contains("Ts") ? Number(j["Ts"], "\"Ts\"") : 0.0;
  if (domain == "continuous") sample_time = 0.0;
  else if (!(sample_time > 0.0))
    throw std::invalid_argument("model JSON: a discrete model needs \"Ts\" > 0");
  const double delay_s = j.contains("delay_s") ? Number(j["delay_s"], "\"delay_s\"") : 0.0;
  auto require = [&](const char* key) -> const json& {
    if (!j.contains(key)) throw std::invalid_argument(std::string("model JSON: missing \"") + key + "\"");
    return j[key];
  };
  if (kind == "tf") {
    TransferFunction tf;
    tf.num = JsonToVector(require("num"), "num");
    tf.den = JsonToVector(require("den"), "den");
    tf.sample_time = sample_time;
    tf.delay_s = delay_s;
    Validate(tf);
    return tf;
  }
  if (kind == "ss") {
    StateSpace ss;
    ss.A = JsonToMatrix(require("A"), "A");
    ss.B = JsonToMatrix(require("B"), "B");
    ss.C = JsonToMatrix(require("C"), "C");
    ss.D = JsonToMatrix(require("D"), "D");
    ss.sample_time = sample_time;
    ss.delay_s = delay_s;
    Validate(ss);
    return ss;
  }
  throw std::invalid_argument("model JSON: \"kind\" must be \"tf\" or \"ss\", got \"" + kind + "\"");
}

json ReadModelJsonFile(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw std::invalid_argument(path + ": cannot open the model file");
  json j;
  try {
    file >> j;
  } catch (const json::parse_error& e) {
    throw std::invalid_argument(path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  try {
    ModelFromJson(j);
    OperatingPointFromModelJson(j);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return j;
}

LtiModel ReadModelFile(const std::string& path) { return ModelFromJson(ReadModelJsonFile(path)); }

void WriteModelFile(const LtiModel& model, const std::string& path) {
  std::ofstream file(path);
  if (!file) throw std::runtime_error(path + ": cannot open for writing");
  file << ModelToJson(model).dump(2) << "\n";
}

json OperatingPointToJson(const OperatingPoint& op) {
  return {{"u", VectorToJson(op.u)}, {"y", VectorToJson(op.y)}};
}

OperatingPoint OperatingPointFromModelJson(const json& model) {
  OperatingPoint op;
  if (!model.is_object() || !model.contains("operating_point")) return op;
  const json& j = model["operating_point"];
  if (!j.is_object() || !j.contains("u") || !j.contains("y"))
    throw std::invalid_argument("model JSON: \"operating_point\" must be an object {\"u\":[…],\"y\":[…]}");
  op.u = JsonToVector(j["u"], "operating_point.u");
  op.y = JsonToVector(j["y"], "operating_point.y");
  const StateSpace ss = ToStateSpace(ModelFromJson(model));
  if (op.u.size() != ss.NumInputs() || op.y.size() != ss.NumOutputs())
    throw std::invalid_argument("model JSON: \"operating_point\" has " + std::to_string(op.u.size()) +
                                " input and " + std::to_string(op.y.size()) + " output values for a model with " +
                                std::to_string(ss.NumInputs()) + " inputs and " + std::to_string(ss.NumOutputs()) +
                                " outputs");
  return op;
}

Eigen::MatrixXd SimulateModelJson(const json& model, const Eigen::MatrixXd& u, double sample_time) {
  const LtiModel m = ModelFromJson(model);
  const OperatingPoint op = OperatingPointFromModelJson(model);
  if (op.empty()) return Simulate(m, u, sample_time);
  if (u.cols() != op.u.size())
    throw std::invalid_argument("simulation: " + std::to_string(u.cols()) + " input columns for a model with " +
                                std::to_string(op.u.size()) + " inputs");
  Eigen::MatrixXd du = u;
  du.rowwise() -= op.u.transpose();
  Eigen::MatrixXd y = Simulate(m, du, sample_time);
  y.rowwise() += op.y.transpose();
  return y;
}

}  // namespace idrig
