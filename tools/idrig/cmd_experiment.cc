// `idrig experiment start|status|stop`: experiments on a rig through idrig-excite.
#include <iostream>
#include <memory>

#include "core/transport/channels.h"
#include "core/transport/signing.h"
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
      for (;;) {
        client.Spin(200);
        const auto* ex = client.ExperimentStatus(args->rig, id, "excite");
        const auto* rs = client.ExperimentStatus(args->rig, id, "rig");
        const experiment_status_t* end =
            rs && rs->state >= experiment_status_t::STATE_DONE ? rs
            : ex && ex->state >= experiment_status_t::STATE_STOPPED ? ex
                                                                    : nullptr;
        if (!end) continue;
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
