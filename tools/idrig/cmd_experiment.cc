// `idrig experiment start|status|stop`: experiments on a rig through idrig-excite;
// `idrig experiment list|export`: recorded experiments from the catalogue and the logger's store.
#include <unistd.h>

#include <iomanip>
#include <iostream>
#include <memory>

#include "core/transport/channels.h"
#include "core/transport/signing.h"
#include "tools/idrig/catalog_views.h"
#include "tools/idrig/commands.h"
#include "tools/idrig/service_client.h"

namespace idrig {

void RegisterExperimentCommands(CLI::App& app) {
  // ---- experiment start|status|stop
  {
    auto* group = app.add_subcommand("experiment", "start, watch or stop experiments on a rig");
    group->require_subcommand(1);
    struct Args {
      std::string url = DefaultLcmUrl(), rig = "sim1", signal, key_file;
      double fs = 10, duration = 10, speed = 1, max_abs = 0, seconds = 1.5, timeout = 5.0;
      int64_t experiment = 0;
      bool wait = false;
    };
    auto args = std::make_shared<Args>();
    auto* start =
        group->add_subcommand("start", "publish an experiment request (prints the experiment id)");
    auto* status =
        group->add_subcommand("status", "listen for experiment status and print the latest");
    auto* stop =
        group->add_subcommand("stop", "stop a running experiment (the rig goes to its safe input)");
    for (auto* c : {start, status, stop}) {
      c->add_option("--url", args->url, "LCM URL (default $LCM_DEFAULT_URL or udpm ttl=0)");
      c->add_option("--rig", args->rig, "rig id");
    }
    for (auto* c : {start, stop}) {
      c->add_option("--key-file", args->key_file, "operator key (default $IDRIG_KEY_FILE)");
      c->add_option("--timeout", args->timeout, "seconds to wait for idrig-excite's answer")
          ->check(CLI::PositiveNumber);
    }
    start->add_option("--signal", args->signal, "excitation SPEC (docs/excitation.md)")->required();
    start->add_option("--fs", args->fs, "sample rate [Hz]")->check(CLI::PositiveNumber);
    start->add_option("--duration", args->duration, "experiment length [s]")
        ->check(CLI::PositiveNumber);
    start->add_option("--speed", args->speed, "experiment time / wall time (simulated rigs)")
        ->check(CLI::PositiveNumber);
    start->add_option("--max-abs", args->max_abs, "lower |u| limit for this experiment")
        ->check(CLI::NonNegativeNumber);
    start->add_option("--experiment", args->experiment, "experiment id (default: from the clock)");
    start->add_flag("--wait", args->wait, "wait until the rig reports the end");
    status->add_option("--experiment", args->experiment, "only this experiment");
    status->add_option("--seconds", args->seconds, "how long to listen");
    stop->add_option("--experiment", args->experiment, "experiment id")->required();
    start->callback([args] {
      ValidateRigId(args->rig);
      ServiceClient client(args->url, OperatorKeyPath(args->key_file));
      const int64_t id = args->experiment > 0 ? args->experiment : NewId();
      const int64_t request_id = NewId();
      // Re-sent until idrig-excite answers: accepted, or refused with the reason (a limit).
      const request_reply_t& reply = client.AwaitReply(
          request_id, "excite", "idrig-excite of rig " + args->rig,
          [&] {
            client.StartExperiment(args->rig, id, args->signal, args->fs, args->duration,
                                   args->speed, args->max_abs, request_id);
          },
          args->timeout, {request_reply_t::STATE_ACCEPTED});
      std::cout << id << "\n" << std::flush;
      std::cerr << "experiment " << id << " accepted: " << reply.message << "\n";
      if (!args->wait) return;
      for (int polls = 0;;) {
        client.Spin(200);
        const auto* ex = client.ExperimentStatus(args->rig, id, "excite");
        const auto* rs = client.ExperimentStatus(args->rig, id, "rig");
        const experiment_status_t* end =
            rs && rs->state >= experiment_status_t::STATE_DONE ? rs
            : ex && ex->state >= experiment_status_t::STATE_STOPPED ? ex
                                                                    : nullptr;
        if (!end) {
          if (rs && ++polls % 25 == 0)  // progress every 5 s
            std::cerr << "  experiment " << id << ": " << rs->samples_done << "/" << rs->samples_total
                      << " samples (" << (rs->samples_total ? 100 * rs->samples_done / rs->samples_total : 0)
                      << " %)\n";
          continue;
        }
        std::cerr << "experiment " << id << " " << ExperimentStateName(end->state) << ": "
                  << end->samples_total << " samples"
                  << (end == rs ? ", " + std::to_string(rs->blocks_total) + " blocks" : "") << " "
                  << end->message << "\n";
        if (end->state != experiment_status_t::STATE_DONE)
          throw CommandFailure("experiment " + std::to_string(id) + " " +
                               ExperimentStateName(end->state) + ": " + end->message);
        return;
      }
    });
    status->callback([args] {
      ServiceClient client(args->url);
      client.Spin(static_cast<int>(args->seconds * 1000));
      int shown = 0;
      for (const auto& [key, s] : client.experiments()) {
        if (s.rig_id != args->rig || (args->experiment && s.experiment_id != args->experiment))
          continue;
        std::cout << s.rig_id << " experiment " << s.experiment_id << " [" << s.source << "] "
                  << ExperimentStateName(s.state) << " " << s.samples_done << "/" << s.samples_total
                  << " samples"
                  << (s.source == "rig" ? ", " + std::to_string(s.blocks_total) + " blocks" : "")
                  << (s.signal_spec.empty() ? "" : ", " + s.signal_spec)
                  << (s.message.empty() ? "" : " — " + s.message) << "\n";
        ++shown;
      }
      if (!shown)
        std::cout << "no experiment status heard on rig " << args->rig << " within "
                  << args->seconds << " s\n";
    });
    // ---- experiment list|export: what the catalogue and the logger's store hold (read-only).
    struct StoreArgs {
      std::string db = "idrig-demo/catalog.db", store = "idrig-demo/experiments.db", rig = "sim1", out;
      int64_t id = 0;
    };
    auto store_args = std::make_shared<StoreArgs>();
    auto* list = group->add_subcommand("list", "experiments in the catalogue and the experiment store");
    auto* export_cmd = group->add_subcommand("export", "write a recorded experiment as CSV (t,u,y) or MATLAB .mat (t, u, y, Ts)");
    for (auto* c : {list, export_cmd}) {
      c->add_option("--db", store_args->db, "catalogue (idrig-catalog's db_path)");
      c->add_option("--experiments", store_args->store, "experiment store (idrig-logger's db_path)");
    }
    export_cmd->add_option("id", store_args->id, "experiment id (idrig experiment list)")->required();
    export_cmd->add_option("--rig", store_args->rig, "rig id");
    export_cmd->add_option("--out", store_args->out, "FILE.csv or FILE.mat")->required();
    list->callback([store_args] {
      std::unique_ptr<Catalog> catalog;
      if (access(store_args->db.c_str(), R_OK) == 0) catalog = std::make_unique<Catalog>(store_args->db, true);
      if (!catalog && access(store_args->store.c_str(), R_OK) != 0)
        throw std::invalid_argument("neither the catalogue '" + store_args->db + "' nor the store '" +
                                    store_args->store + "' exists (--db, --experiments)");
      const auto rows = ExperimentsJson(catalog.get(), store_args->store);
      std::cout << std::left << std::setw(8) << "rig" << std::setw(19) << "experiment" << std::setw(9) << "state"
                << std::setw(9) << "samples" << std::setw(8) << "fs Hz" << std::setw(14) << "blocks" << std::setw(21)
                << "started (UTC)" << "signal\n";
      for (const auto& e : rows) {
        const std::string blocks = e.value("in_store", false)
            ? std::to_string(e.value("blocks_stored", 0)) + "/" + std::to_string(e.value("blocks_total", 0)) +
                  (e.value("missing_blocks", 0) ? " (" + std::to_string(e.value("missing_blocks", 0)) + " lost)" : "")
            : "not stored";
        std::cout << std::left << std::setw(8) << e.value("rig_id", "") << std::setw(19)
                  << e.value("experiment_id", int64_t{0}) << std::setw(9) << e.value("state", "") << std::setw(9)
                  << e.value("samples_total", int64_t{0}) << std::setw(8) << e.value("sample_rate_hz", 0.0)
                  << std::setw(14) << blocks << std::setw(21) << e.value("start_utc", "-") << e.value("signal_spec", "")
                  << "\n";
      }
      if (rows.empty()) std::cout << "no experiment recorded\n";
    });
    export_cmd->callback([store_args] {
      std::string spec;
      const IoRecord r = LoadExperimentRecord(store_args->store, store_args->rig, store_args->id, &spec);
      WriteRecordFile(r, store_args->out, {{"rig_id", store_args->rig}, {"experiment_id", std::to_string(store_args->id)},
                                           {"signal_spec", spec}});
      std::cerr << "wrote experiment " << store_args->id << " (" << spec << "): " << r.NumSamples()
                << " samples at Ts " << r.sample_time << " s to " << store_args->out << "\n";
    });
    stop->callback([args] {
      ValidateRigId(args->rig);
      ServiceClient client(args->url, OperatorKeyPath(args->key_file));
      const int64_t request_id = NewId();
      const request_reply_t& reply = client.AwaitReply(
          request_id, "excite", "idrig-excite of rig " + args->rig,
          [&] { client.StopExperiment(args->rig, args->experiment, request_id); }, args->timeout,
          {request_reply_t::STATE_ACCEPTED});
      std::cerr << "experiment " << args->experiment << ": " << reply.message << "\n";
    });
  }
}

}  // namespace idrig
