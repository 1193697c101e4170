// idrig example: writes a reproducible record of seed 001's plant (and the plant's model), so
// that `idrig identify` can be tried at once. idrig simulate: a model's response to a record.
#include <iostream>
#include <memory>
#include <random>

#include "core/io/csv.h"
#include "core/io/model_json.h"
#include "core/numeric/signal/excitation.h"
#include "tools/idrig/commands.h"

namespace idrig {

void RegisterExampleCommand(CLI::App& app) {
  struct Args {
    std::string out = "example.csv", model_out;
    int samples = 2000;
    double sample_time = 0.2, noise = 0.01;
    std::uint64_t seed = 1;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "example", "write a record of seed 001's plant W(p) = (0.5p + 1)/(p^3 + 2.5p^2 + 4p + 1.5) "
                 "under a +-1 maximum-length PRBS, with white output noise");
  cmd->add_option("--out", args->out, "CSV file to write (t,u,y)");
  cmd->add_option("--model-out", args->model_out, "also write the true plant as idrig.model/1 JSON");
  cmd->add_option("--samples", args->samples, "number of samples")->check(CLI::Range(10, 100000000));
  cmd->add_option("--ts", args->sample_time, "sample time [s]")->check(CLI::PositiveNumber);
  cmd->add_option("--noise", args->noise, "output noise standard deviation")->check(CLI::NonNegativeNumber);
  cmd->add_option("--seed", args->seed, "random seed");
  cmd->callback([args] {
    TransferFunction plant;
    plant.num = Eigen::Vector2d(0.5, 1.0);
    plant.den = Eigen::Vector4d(1.0, 2.5, 4.0, 1.5);
    // ±1 maximum-length PRBS clocked at Ts (11-bit register: period 2047 samples).
    const ExcitationSpec spec = ParseExcitationSpec("prbs:bits=11,amp=1");
    const double fs = 1.0 / args->sample_time;
    Eigen::MatrixXd u = GenerateExcitation(spec, fs, args->samples);
    std::mt19937_64 rng(args->seed);
    Eigen::MatrixXd y = Simulate(plant, u, args->sample_time);
    std::normal_distribution<double> noise(0.0, args->noise > 0 ? args->noise : 1.0);
    if (args->noise > 0)
      for (int k = 0; k < args->samples; ++k) y(k, 0) += noise(rng);
    WriteIoRecordCsv(MakeIoRecord(u, y, args->sample_time), args->out);
    if (!args->model_out.empty()) WriteModelFile(plant, args->model_out);
    std::cerr << "wrote " << args->out << " (" << args->samples << " samples, Ts " << args->sample_time
              << " s, noise sigma " << args->noise << ")\n";
  });
}

void RegisterSimulateCommand(CLI::App& app) {
  struct Args {
    std::string model, data, out;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("simulate", "simulate a model (idrig.model/1) on the inputs of a record (exact ZOH; about the model's operating point when it has one)");
  cmd->add_option("--model", args->model, "model JSON")->required();
  cmd->add_option("--data", args->data, "record whose input columns drive the model")->required();
  cmd->add_option("--out", args->out, "CSV to write (t, inputs, simulated outputs); default stdout");
  cmd->callback([args] {
    const nlohmann::json model = ReadModelJsonFile(args->model);
    IoRecord record = ReadIoRecordCsv(args->data);
    // From rest at the model's operating point when it has one: y0 + G(u − u0).
    const Eigen::MatrixXd y = SimulateModelJson(model, record.u, record.sample_time);
    record.y = y;
    record.output_names.clear();
    if (args->out.empty()) std::cout << FormatIoRecordCsv(record);
    else WriteIoRecordCsv(record, args->out);
  });
}

}  // namespace idrig
