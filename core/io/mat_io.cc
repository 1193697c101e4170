#include "core/io/mat_io.h"

#include <matio.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace idrig {
namespace {

struct MatCloser {
  void operator()(mat_t* m) const { Mat_Close(m); }
};
struct VarFreer {
  void operator()(matvar_t* v) const { Mat_VarFree(v); }
};
using MatFile = std::unique_ptr<mat_t, MatCloser>;
using MatVar = std::unique_ptr<matvar_t, VarFreer>;

MatFile OpenForReading(const std::string& path) {
  MatFile mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!mat)
    throw std::invalid_argument(path + ": cannot be opened as a MATLAB .mat file (missing, "
                                "unreadable, or not MAT level 5/7.3; in Octave: save -v7 FILE vars)");
  return mat;
}

template <typename T>
void CopyAs(const matvar_t* v, Eigen::MatrixXd* out) {
  const T* data = static_cast<const T*>(v->data);
  for (Eigen::Index i = 0; i < out->size(); ++i) out->data()[i] = static_cast<double>(data[i]);
}

std::string Where(const std::string& path, const std::string& name) {
  return path + ": variable '" + name + "'";
}

std::vector<std::string> SplitNames(const std::string& names) {
  std::vector<std::string> out;
  std::stringstream s(names);
  std::string item;
  while (std::getline(s, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

// Columns of one or several variables, each a channel or an N×k block of channels.
Eigen::MatrixXd Channels(const std::string& path, const std::string& names, const char* role) {
  const auto list = SplitNames(names);
  if (list.empty())
    throw std::invalid_argument(path + ": no " + std::string(role) + " variable named (--" +
                                role + " NAME[,NAME...])");
  std::vector<Eigen::MatrixXd> parts;
  Eigen::Index rows = -1, cols = 0;
  for (const auto& name : list) {
    Eigen::MatrixXd m = ReadMatMatrix(path, name);
    if (m.rows() == 1) m.transposeInPlace();  // a row vector is one channel
    if (rows >= 0 && m.rows() != rows)
      throw std::invalid_argument(Where(path, name) + " has " + std::to_string(m.rows()) +
                                  " samples, but '" + list.front() + "' has " +
                                  std::to_string(rows));
    rows = m.rows();
    cols += m.cols();
    parts.push_back(std::move(m));
  }
  Eigen::MatrixXd out(rows, cols);
  Eigen::Index c = 0;
  for (const auto& p : parts) {
    out.middleCols(c, p.cols()) = p;
    c += p.cols();
  }
  return out;
}

bool HasVariable(const std::vector<std::string>& names, const std::string& name) {
  for (const auto& n : names)
    if (n == name) return true;
  return false;
}

class MatWriter {
 public:
  explicit MatWriter(const std::string& path) : path_(path) {
    mat_.reset(Mat_CreateVer(path.c_str(), "MATLAB 5.0 MAT-file, written by idrig", MAT_FT_MAT5));
    if (!mat_) throw std::runtime_error("cannot create '" + path + "' (directory missing or not writable?)");
  }
  void Matrix(const std::string& name, const Eigen::MatrixXd& m) { Write(MakeMatrix(name, m)); }
  void Scalar(const std::string& name, double v) { Matrix(name, Eigen::MatrixXd::Constant(1, 1, v)); }
  void Text(const std::string& name, const std::string& text) { Write(MakeText(name, text)); }
  // A 1×1 struct with one field per key of a flat JSON object.
  void Struct(const std::string& name, const nlohmann::json& fields) {
    std::vector<std::string> keys;
    for (auto it = fields.begin(); it != fields.end(); ++it) keys.push_back(it.key());
    std::vector<const char*> key_ptrs;
    for (const auto& k : keys) key_ptrs.push_back(k.c_str());
    size_t dims[2] = {1, 1};
    matvar_t* s = Mat_VarCreateStruct(name.c_str(), 2, dims, key_ptrs.data(),
                                      static_cast<unsigned>(key_ptrs.size()));
    if (!s) throw std::runtime_error("cannot create struct '" + name + "' in " + path_);
    for (const auto& k : keys) {
      const auto& v = fields[k];
      matvar_t* field = nullptr;
      if (v.is_number() || v.is_boolean())
        field = MakeMatrix(k, Eigen::MatrixXd::Constant(1, 1, v.is_boolean() ? v.get<bool>() : v.get<double>()));
      else
        field = MakeText(k, v.is_string() ? v.get<std::string>() : v.dump());
      Mat_VarSetStructFieldByName(s, k.c_str(), 0, field);  // the struct owns the field now
    }
    Write(s);
  }

 private:
  matvar_t* MakeMatrix(const std::string& name, const Eigen::MatrixXd& m) {
    size_t dims[2] = {static_cast<size_t>(m.rows()), static_cast<size_t>(m.cols())};
    // MAT_F_DONT_COPY_DATA is not used: matio copies, so `m` may go out of scope.
    matvar_t* v = Mat_VarCreate(name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims,
                                const_cast<double*>(m.data()), 0);
    if (!v) throw std::runtime_error("cannot create variable '" + name + "' in " + path_);
    return v;
  }
  matvar_t* MakeText(const std::string& name, const std::string& text) {
    size_t dims[2] = {1, text.size()};
    matvar_t* v = Mat_VarCreate(name.c_str(), MAT_C_CHAR, MAT_T_UINT8, 2, dims,
                                const_cast<char*>(text.data()), 0);
    if (!v) throw std::runtime_error("cannot create text variable '" + name + "' in " + path_);
    return v;
  }
  void Write(matvar_t* v) {
    MatVar owned(v);
    if (Mat_VarWrite(mat_.get(), v, MAT_COMPRESSION_NONE) != 0)
      throw std::runtime_error("cannot write variable '" + std::string(v->name) + "' to " + path_);
  }
  std::string path_;
  MatFile mat_;
};

Eigen::MatrixXd Row(const Eigen::VectorXd& v) { return v.transpose(); }

}  // namespace

std::vector<std::string> MatVariableNames(const std::string& path) {
  MatFile mat = OpenForReading(path);
  std::vector<std::string> names;
  while (matvar_t* v = Mat_VarReadNextInfo(mat.get())) {
    MatVar owned(v);
    if (v->name) names.push_back(v->name);
  }
  return names;
}

Eigen::MatrixXd ReadMatMatrix(const std::string& path, const std::string& name) {
  MatFile mat = OpenForReading(path);
  MatVar v(Mat_VarRead(mat.get(), name.c_str()));
  if (!v) {
    std::string list;
    for (const auto& n : MatVariableNames(path)) list += (list.empty() ? "" : ", ") + n;
    throw std::invalid_argument(Where(path, name) + " not found (the file has: " +
                                (list.empty() ? "no variables" : list) + ")");
  }
  if (v->rank != 2)
    throw std::invalid_argument(Where(path, name) + " has " + std::to_string(v->rank) +
                                " dimensions; expected a vector or a matrix");
  if (v->isComplex)
    throw std::invalid_argument(Where(path, name) + " is complex; expected real samples");
  const Eigen::Index rows = static_cast<Eigen::Index>(v->dims[0]),
                     cols = static_cast<Eigen::Index>(v->dims[1]);
  if (rows == 0 || cols == 0) throw std::invalid_argument(Where(path, name) + " is empty");
  Eigen::MatrixXd out(rows, cols);  // column-major, as MATLAB stores it
  switch (v->class_type) {
    case MAT_C_DOUBLE: CopyAs<double>(v.get(), &out); break;
    case MAT_C_SINGLE: CopyAs<float>(v.get(), &out); break;
    case MAT_C_INT8: CopyAs<int8_t>(v.get(), &out); break;
    case MAT_C_UINT8: CopyAs<uint8_t>(v.get(), &out); break;
    case MAT_C_INT16: CopyAs<int16_t>(v.get(), &out); break;
    case MAT_C_UINT16: CopyAs<uint16_t>(v.get(), &out); break;
    case MAT_C_INT32: CopyAs<int32_t>(v.get(), &out); break;
    case MAT_C_UINT32: CopyAs<uint32_t>(v.get(), &out); break;
    case MAT_C_INT64: CopyAs<int64_t>(v.get(), &out); break;
    case MAT_C_UINT64: CopyAs<uint64_t>(v.get(), &out); break;
    default: {
      const char* kind = v->class_type == MAT_C_CHAR     ? "text (char)"
                         : v->class_type == MAT_C_STRUCT ? "a struct"
                         : v->class_type == MAT_C_CELL   ? "a cell array"
                         : v->class_type == MAT_C_SPARSE ? "sparse"
                                                         : "not a numeric array";
      throw std::invalid_argument(Where(path, name) + " is " + kind +
                                  "; expected a real numeric vector or matrix");
    }
  }
  if (v->data_type == MAT_T_UTF8 || !v->data)
    throw std::invalid_argument(Where(path, name) + " has no numeric data");
  return out;
}

IoRecord ReadMatRecord(const std::string& path, const std::string& u_names,
                       const std::string& y_names, double ts) {
  const Eigen::MatrixXd u = Channels(path, u_names, "u");
  const Eigen::MatrixXd y = Channels(path, y_names, "y");
  if (u.rows() != y.rows())
    throw std::invalid_argument(path + ": the inputs (" + u_names + ") have " +
                                std::to_string(u.rows()) + " samples, the outputs (" + y_names +
                                ") " + std::to_string(y.rows()));
  if (!(ts >= 0) || !std::isfinite(ts))
    throw std::invalid_argument("--ts must be a positive sample time in seconds");
  const auto names = MatVariableNames(path);
  std::string ts_source = ts > 0 ? "--ts" : "";
  if (ts == 0) {
    for (const char* n : {"Ts", "ts", "dt"})
      if (HasVariable(names, n)) {
        const Eigen::MatrixXd m = ReadMatMatrix(path, n);
        if (m.size() != 1) throw std::invalid_argument(Where(path, n) + " must be a scalar sample time [s]");
        ts = m(0, 0);
        ts_source = Where(path, n);
        break;
      }
  }
  Eigen::VectorXd t;
  for (const char* n : {"t", "time"})
    if (HasVariable(names, n)) {
      Eigen::MatrixXd m = ReadMatMatrix(path, n);
      if (m.rows() == 1) m.transposeInPlace();
      if (m.cols() == 1 && m.rows() == u.rows() && ts_source != "--ts") {
        t = m.col(0);
        if (ts == 0 && t.size() > 1) {
          ts = (t(t.size() - 1) - t(0)) / static_cast<double>(t.size() - 1);
          ts_source = Where(path, n) + " (mean step)";
        }
      }
      break;
    }
  if (ts == 0)
    throw std::invalid_argument(path + ": no sample time: give --ts S, or store a scalar Ts or a "
                                "time vector t in the file");
  if (!(ts > 0) || !std::isfinite(ts))
    throw std::invalid_argument(ts_source + ": the sample time must be positive, got " +
                                std::to_string(ts));
  IoRecord record = MakeIoRecord(u, y, ts);
  if (t.size() == record.t.size() && ts_source != "--ts") record.t = t;  // --ts wins over t
  for (Eigen::Index c = 0; c < u.cols(); ++c) record.input_names.push_back("u" + std::to_string(c + 1));
  for (Eigen::Index c = 0; c < y.cols(); ++c) record.output_names.push_back("y" + std::to_string(c + 1));
  try {
    ValidateIoRecord(record);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return record;
}

void WriteMatRecord(const IoRecord& record, const std::string& path,
                    const std::map<std::string, std::string>& text) {
  MatWriter w(path);
  w.Matrix("t", record.t);
  w.Matrix("u", record.u);
  w.Matrix("y", record.y);
  w.Scalar("Ts", record.sample_time);
  for (const auto& [name, value] : text) w.Text(name, value);
}

void WriteMatModel(const LtiModel& model, const std::string& path, const nlohmann::json& lineage,
                   const OperatingPoint& operating_point) {
  MatWriter w(path);
  double ts = 0, delay = 0;
  if (const auto* tf = std::get_if<TransferFunction>(&model)) {
    w.Text("kind", "tf");
    w.Matrix("num", Row(tf->num));
    w.Matrix("den", Row(tf->den));
    ts = tf->sample_time;
    delay = tf->delay_s;
  } else {
    const auto& ss = std::get<StateSpace>(model);
    w.Text("kind", "ss");
    w.Matrix("A", ss.A);
    w.Matrix("B", ss.B);
    w.Matrix("C", ss.C);
    w.Matrix("D", ss.D);
    ts = ss.sample_time;
    delay = ss.delay_s;
  }
  w.Text("domain", ts > 0 ? "discrete" : "continuous");
  w.Scalar("Ts", ts);
  // MATLAB's InputDelay: seconds for continuous models, samples for discrete ones.
  w.Scalar("delay", ts > 0 ? delay / ts : delay);
  w.Scalar("delay_s", delay);
  if (!operating_point.empty()) {
    w.Matrix("u0", operating_point.u);
    w.Matrix("y0", operating_point.y);
  }
  if (lineage.is_object() && !lineage.empty()) w.Struct("lineage", lineage);
}

}  // namespace idrig
