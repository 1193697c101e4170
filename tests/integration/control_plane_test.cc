// Issue 14's findings, each reproduced against the services as real processes over udpm in a
// private network namespace, and shown refused or handled: unsigned and forged experiment
// starts and stops, forged, hijacking and forged-failure results, replays to restarted
// receivers, a rig killed mid-experiment, a logger killed and restarted, a request while the
// catalogue is down, and the command line's exit codes. Needs root (skipped otherwise).
#include <gtest/gtest.h>

#include <idrig/actuator_command_t.hpp>
#include <idrig/experiment_request_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/model_result_t.hpp>
#include <idrig/service_status_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <thread>

#include "core/catalog/catalog.h"
#include "core/catalog/experiment_store.h"
#include "core/transport/channels.h"
#include "tests/integration/process_harness.h"

namespace idrig {
namespace {

using namespace harness;
const auto* const kEnvironment = ::testing::AddGlobalTestEnvironment(new NetnsEnvironment);
const std::string kUrl = PrivateUdpmUrl(7731, 0);
const std::string kRig = "rig-c";

// A deployment in a directory: keys, configs, and the services started on demand.
struct Deployment {
  std::string dir = Dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
  Keys keys{dir};
  Child catalog, logger, rig, excite, worker;
  std::unique_ptr<Transport> t = MakeLcmTransport(kUrl);
  std::map<std::string, service_status_t> services;  // by service name
  std::map<std::pair<int64_t, std::string>, experiment_status_t> experiments;
  explicit Deployment(double worker_delay_s = 0.0, bool logger_lcmlog = false) {
    nlohmann::json roles = keys.Roles();
    nlohmann::json c = roles;
    c.update({{"db_path", dir + "/catalog.db"}, {"offer_period_s", 0.3}, {"lease_s", 2.0},
              {"state_dir", dir + "/state"}});
    WriteFile(dir + "/catalog.json", c.dump());
    WriteFile(dir + "/rig.json", nlohmann::json({{"rig_id", kRig},
                                                 {"key_file", keys.command},
                                                 {"noise_std", 0.001},
                                                 {"watchdog_s", 1.0},
                                                 {"block_samples", 20},
                                                 {"state_dir", dir + "/state/rig"},
                                                 {"model",
                                                  {{"format", "idrig.model/1"},
                                                   {"kind", "tf"},
                                                   {"domain", "continuous"},
                                                   {"Ts", 0.0},
                                                   {"num", {1.0}},
                                                   {"den", {1.0, 1.2, 1.0}}}}})
                                     .dump());
    WriteFile(dir + "/excite.json", nlohmann::json({{"rig_id", kRig},
                                                    {"key_file", keys.command},
                                                    {"operator_key_file", keys.operator_key},
                                                    {"state_dir", dir + "/state"},
                                                    {"max_duration_s", 600.0},
                                                    {"max_abs", 5.0}})
                                        .dump());
    nlohmann::json w = roles;
    w.update({{"renew_s", 0.25}, {"state_dir", dir + "/state"}, {"debug_delay_s", worker_delay_s}});
    WriteFile(dir + "/worker.json", w.dump());
    nlohmann::json l = {{"db_path", dir + "/experiments.db"}, {"recover_period_s", 0.3}};
    if (logger_lcmlog) l["lcmlog_path"] = dir + "/log.lcmlog";
    WriteFile(dir + "/logger.json", l.dump());
    t->Subscribe("IDRIG/STATUS/.*", [this](const std::string&, const uint8_t* d, size_t n) {
      service_status_t s;
      if (Decode(d, n, &s, nullptr)) services[s.service] = s;
    });
    t->Subscribe("IDRIG/" + kRig + "/EXP_STATUS",
                 [this](const std::string&, const uint8_t* d, size_t n) {
                   experiment_status_t s;
                   if (Decode(d, n, &s, nullptr)) experiments[{s.experiment_id, s.source}] = s;
                 });
  }
  void StartService(Child* child, const std::string& name) {
    static const std::map<std::string, std::string> programs = {
        {"catalog", "idrig-catalog"}, {"logger", "idrig-logger"}, {"rig", "idrig-rig-sim"},
        {"excite", "idrig-excite"},   {"worker", "idrig-worker"}};
    std::vector<std::string> args = {"--config", dir + "/" + name + ".json"};
    if (name == "worker") args.insert(args.end(), {"--id", "w1"});
    Start(child, programs.at(name), args, dir + "/" + name + ".log", kUrl);
  }
  // Starts the named services and waits until each has published its status.
  void Up(const std::vector<std::string>& names) {
    std::map<std::string, Child*> children = {{"catalog", &catalog}, {"logger", &logger},
                                              {"rig", &rig},         {"excite", &excite},
                                              {"worker", &worker}};
    static const std::map<std::string, std::string> status_names = {
        {"catalog", "catalog"}, {"logger", "logger"}, {"rig", "rig_sim"}, {"excite", "excite"},
        {"worker", "worker"}};
    for (const auto& n : names) {
      services.erase(status_names.at(n));
      StartService(children.at(n), n);
    }
    ASSERT_TRUE(Until(
        *t,
        [&] {
          for (const auto& n : names)
            if (!services.count(status_names.at(n))) return false;
          return true;
        },
        10.0))
        << "services did not start; logs in " << dir;
  }
  void Wait(double seconds) {
    Until(*t, [] { return false; }, seconds);
  }
  const experiment_status_t* Experiment(int64_t id, const std::string& source) {
    auto it = experiments.find({id, source});
    return it == experiments.end() ? nullptr : &it->second;
  }
  bool WaitEnd(int64_t id, double seconds) {
    return Until(
        *t,
        [&] {
          const auto* s = Experiment(id, "rig");
          return s && s->state >= experiment_status_t::STATE_DONE;
        },
        seconds);
  }
  CliResult Cli(std::vector<std::string> args) {
    args.insert(args.end(), {"--url", kUrl});
    return RunCli(args, dir + "/cli.out");
  }
  std::vector<std::string> Key() const { return {"--key-file", keys.operator_key}; }
  CliResult StartExperiment(int64_t id, const std::string& spec, double duration, double speed) {
    std::vector<std::string> args = {"experiment", "start", "--rig", kRig, "--signal", spec,
                                     "--fs", "20", "--duration", std::to_string(duration),
                                     "--speed", std::to_string(speed), "--experiment",
                                     std::to_string(id)};
    for (const auto& k : Key()) args.push_back(k);
    return Cli(args);
  }
};

experiment_request_t Request(int64_t id, int32_t action) {
  experiment_request_t r{};
  r.utime = NowMicros();
  r.request_id = NowMicros();
  r.rig_id = kRig;
  r.experiment_id = id;
  r.action = action;
  r.signal_spec = "prbs:bits=7,amp=4.9";
  r.sample_rate_hz = 20;
  r.duration_s = 6.35;
  r.speed = 5;
  return r;
}

model_result_t Result(int64_t request_id, int64_t experiment_id, const std::string& worker, bool ok) {
  model_result_t r{};
  r.utime = NowMicros();
  r.request_id = request_id;
  r.rig_id = kRig;
  r.experiment_id = experiment_id;
  r.worker_id = worker;
  r.attempt = 1;
  r.ok = ok;
  r.method = "arx";
  r.options_json = "{}";
  r.data_hash = std::string(64, '0');
  r.n_samples = 100;
  r.sample_time_s = 0.05;
  r.message = ok ? "" : "forged failure";
  r.report_json = ok ? R"({"fit_percent":99.9,"status":"ok","model":{"format":"idrig.model/1",
      "kind":"tf","domain":"continuous","Ts":0,"num":[1],"den":[1,1]}})"
                     : "{}";
  return r;
}

template <class T>
void PublishBare(Transport& t, const std::string& channel, const T& message) {
  t.PublishMessage(channel, message);
}

HmacKey AttackerKey() {
  HmacKey key(32);
  for (size_t i = 0; i < key.size(); ++i) key[i] = static_cast<uint8_t>(7 * i + 3);
  return key;
}

TEST(ControlPlane, UnsignedForgedAndHijackingMessagesAreRefused) {
  if (!NetnsReady()) GTEST_SKIP() << "needs root for a private network namespace";
  Deployment d(/*worker_delay_s=*/2.0);
  d.Up({"catalog", "logger", "rig", "excite", "worker"});
  EnvelopeSigner attacker(kOperatorRole, AttackerKey(), "cli:mallory@h");
  EnvelopeSigner attacker_service(kServiceRole, AttackerKey(), "attacker");
  // Finding 1a: an unsigned start (amplitude 4.9) and one signed with a key nobody gave out.
  PublishBare(*d.t, Channel(kRig, ChannelKind::kExperimentRequest),
              Request(11, experiment_request_t::ACTION_START));
  attacker.Publish(*d.t, Channel(kRig, ChannelKind::kExperimentRequest),
                   Request(12, experiment_request_t::ACTION_START));
  d.Wait(1.0);
  EXPECT_EQ(d.Experiment(11, "excite"), nullptr);
  EXPECT_EQ(d.Experiment(12, "excite"), nullptr);
  EXPECT_EQ(d.Experiment(11, "rig"), nullptr);
  EXPECT_GE(d.services["excite"].unsigned_count, 1);
  EXPECT_GE(d.services["excite"].forged, 1);
  // Finding 1b: a genuine experiment is not stopped by an unsigned or a forged stop.
  const CliResult started = d.StartExperiment(20, "prbs:bits=7,amp=1", 6.35, 4);
  ASSERT_EQ(started.code, 0) << started.output;
  d.Wait(0.3);
  PublishBare(*d.t, Channel(kRig, ChannelKind::kExperimentRequest),
              Request(20, experiment_request_t::ACTION_STOP));
  attacker.Publish(*d.t, Channel(kRig, ChannelKind::kExperimentRequest),
                   Request(20, experiment_request_t::ACTION_STOP));
  ASSERT_TRUE(d.WaitEnd(20, 10.0));
  EXPECT_EQ(d.Experiment(20, "rig")->state, experiment_status_t::STATE_DONE)
      << d.Experiment(20, "rig")->message;
  // Finding 1c: a result for a request nobody made, unsigned and signed with a wrong key.
  PublishBare(*d.t, Channel(kRig, ChannelKind::kResult), Result(777, 20, "attacker", true));
  attacker_service.Publish(*d.t, Channel(kRig, ChannelKind::kResult), Result(778, 20, "attacker", true));
  // Findings 1d and 1e: a real job (the worker takes 2 s more than needed); meanwhile someone
  // answers it first (unsigned; and with the real service key but without the lease) and marks
  // it failed.
  const CliResult requested = d.Cli({"models", "request", "--rig", kRig, "--experiment", "20",
                                     "--method", "arx", "--options", R"({"order":2})", "--key-file",
                                     d.keys.operator_key});
  ASSERT_EQ(requested.code, 0) << requested.output;
  const int64_t job = std::stoll(requested.output);
  EnvelopeSigner insider(kServiceRole, d.keys.Service(), "attacker");
  for (int i = 0; i < 3; ++i) {
    PublishBare(*d.t, Channel(kRig, ChannelKind::kResult), Result(job, 20, "attacker", true));
    PublishBare(*d.t, Channel(kRig, ChannelKind::kResult), Result(job, 20, "w1", false));
    insider.Publish(*d.t, Channel(kRig, ChannelKind::kResult), Result(job, 20, "attacker", true));
    d.Wait(0.2);
  }
  Catalog reader(d.dir + "/catalog.db");
  EXPECT_EQ(reader.Job(job)->state, "leased");  // not failed, not done by "attacker"
  ASSERT_TRUE(Until(
      *d.t, [&] { return reader.ModelForRequest(job).has_value(); }, 15.0));
  EXPECT_EQ(reader.ModelForRequest(job)->worker_id, "w1");
  EXPECT_EQ(reader.CountModels(), 1);
  EXPECT_FALSE(reader.Job(777).has_value());
  EXPECT_FALSE(reader.ModelForRequest(777).has_value());
  d.Wait(1.2);
  EXPECT_GE(d.services["catalog"].unsigned_count, 4);
  EXPECT_GE(d.services["catalog"].forged, 1);
  const auto details = nlohmann::json::parse(d.services["catalog"].details_json);
  EXPECT_GE(details["refused_results"].get<int64_t>(), 3);
  // Every refusal left a line in the services' logs.
  EXPECT_NE(ReadFile(d.dir + "/excite.log").find("refused a message on IDRIG/rig-c/EXP_REQ: unsigned"),
            std::string::npos);
  EXPECT_NE(ReadFile(d.dir + "/catalog.log").find("not attacker"), std::string::npos);
}

TEST(ControlPlane, RecordedRequestsAndCommandsAreRefusedByRestartedReceivers) {
  if (!NetnsReady()) GTEST_SKIP() << "needs root for a private network namespace";
  Deployment d;
  d.Up({"rig", "excite"});
  std::vector<std::vector<uint8_t>> commands;
  d.t->Subscribe(
      Channel(kRig, ChannelKind::kCommand),
      [&](const std::string&, const uint8_t* data, size_t n) { commands.emplace_back(data, data + n); },
      10000);
  EnvelopeSigner op(kOperatorRole, d.keys.Operator(), "cli:test");
  experiment_request_t start = Request(30, experiment_request_t::ACTION_START);
  start.signal_spec = "prbs:bits=6,amp=1";
  start.duration_s = 3.15;
  start.speed = 10;
  const std::vector<uint8_t> recorded = op.Seal(Channel(kRig, ChannelKind::kExperimentRequest), start);
  d.t->Publish(Channel(kRig, ChannelKind::kExperimentRequest), recorded.data(), recorded.size());
  ASSERT_TRUE(d.WaitEnd(30, 10.0));
  ASSERT_EQ(d.Experiment(30, "rig")->state, experiment_status_t::STATE_DONE);
  ASSERT_GT(commands.size(), 5u);
  d.Wait(0.5);  // the rig has taken every command (the last two repeat the final one)
  const std::vector<std::vector<uint8_t>> recorded_commands = commands;  // we hear our own replay
  d.excite.Kill(SIGKILL);
  d.rig.Kill(SIGKILL);
  d.experiments.clear();
  d.Up({"rig", "excite"});
  // The recorded request and commands, replayed to the restarted receivers.
  d.t->Publish(Channel(kRig, ChannelKind::kExperimentRequest), recorded.data(), recorded.size());
  for (const auto& c : recorded_commands)
    d.t->Publish(Channel(kRig, ChannelKind::kCommand), c.data(), c.size());
  Until(
      *d.t,
      [&] {
        return d.services["rig_sim"].replayed >= static_cast<int64_t>(recorded_commands.size()) &&
               d.services["excite"].replayed >= 1;
      },
      3.0);
  const auto* again = d.Experiment(30, "excite");
  EXPECT_TRUE(again == nullptr || again->state != experiment_status_t::STATE_RUNNING);
  EXPECT_EQ(d.services["excite"].replayed, 1);
  EXPECT_EQ(d.services["rig_sim"].replayed, static_cast<int64_t>(recorded_commands.size()))
      << d.services["rig_sim"].details_json << " unsigned " << d.services["rig_sim"].unsigned_count
      << " forged " << d.services["rig_sim"].forged;
  EXPECT_TRUE(nlohmann::json::parse(d.services["rig_sim"].details_json)["safe"].get<bool>());
  // A fresh request from the operator still works.
  ASSERT_EQ(d.StartExperiment(31, "step:amp=1", 2.0, 10).code, 0);
  ASSERT_TRUE(d.WaitEnd(31, 10.0));
  EXPECT_EQ(d.Experiment(31, "rig")->state, experiment_status_t::STATE_DONE);
}

TEST(ControlPlane, RigKilledMidExperimentEndsItInterruptedAndNothingSplicedIsStored) {
  if (!NetnsReady()) GTEST_SKIP() << "needs root for a private network namespace";
  Deployment d;
  d.Up({"catalog", "logger", "rig", "excite", "worker"});
  ASSERT_EQ(d.StartExperiment(40, "prbs:bits=8,amp=1", 12.75, 3).code, 0);  // 255 samples, ~4 s
  ASSERT_TRUE(Until(
      *d.t,
      [&] {
        const auto* s = d.Experiment(40, "rig");
        return s && s->samples_done >= 80;
      },
      10.0));
  d.rig.Kill(SIGKILL);
  d.Wait(0.3);
  d.Up({"rig"});
  ASSERT_TRUE(d.WaitEnd(40, 10.0));
  const experiment_status_t rig = *d.Experiment(40, "rig");
  EXPECT_EQ(rig.state, experiment_status_t::STATE_INTERRUPTED) << rig.message;
  EXPECT_GE(rig.samples_total, 80);
  EXPECT_LT(rig.samples_total, 255);
  EXPECT_NE(rig.message.find("samples from " + std::to_string(rig.samples_total) + " on missing"),
            std::string::npos)
      << rig.message;
  ASSERT_TRUE(Until(
      *d.t,
      [&] {
        const auto* e = d.Experiment(40, "excite");
        return e && e->state == experiment_status_t::STATE_INTERRUPTED;
      },
      5.0))
      << "excite did not end the experiment";
  Catalog reader(d.dir + "/catalog.db");
  ASSERT_TRUE(Until(
      *d.t,
      [&] {
        for (const auto& e : reader.Experiments(kRig))
          if (e.experiment_id == 40 && e.state == "interrupted") return true;
        return false;
      },
      5.0));
  for (const auto& e : reader.Experiments(kRig)) {
    if (e.experiment_id != 40) continue;
    EXPECT_EQ(e.samples_planned, 255);  // the catalogue names what is missing: samples_total..254
    EXPECT_EQ(e.samples_total, rig.samples_total);
    EXPECT_NE(e.message.find("missing (not measured)"), std::string::npos) << e.message;
  }
  // A model from the interrupted record: refused unless asked for what was measured.
  const CliResult refused = d.Cli({"models", "request", "--rig", kRig, "--experiment", "40",
                                   "--method", "arx", "--key-file", d.keys.operator_key});
  EXPECT_EQ(refused.code, 1) << refused.output;
  EXPECT_NE(refused.output.find("interrupted"), std::string::npos) << refused.output;
  const CliResult used = d.Cli({"models", "request", "--rig", kRig, "--experiment", "40",
                                "--method", "arx", "--options",
                                R"({"order":2,"segment":"longest_complete"})", "--wait",
                                "--key-file", d.keys.operator_key});
  ASSERT_EQ(used.code, 0) << used.output;
  ASSERT_EQ(reader.CountModels(), 1);
  const ModelRecord m = reader.Models(kRig).front();
  EXPECT_EQ(m.n_samples, rig.samples_total);  // only what was measured: nothing invented
  const auto report = nlohmann::json::parse(m.report_json);
  EXPECT_EQ(report["record"]["experiment_state"], "interrupted");
  EXPECT_EQ(report["record"]["samples_used"].get<int64_t>(), rig.samples_total);
  ExperimentStore store(d.dir + "/experiments.db");
  EXPECT_TRUE(store.MissingBlocks(kRig, 40).empty());
}

TEST(ControlPlane, LoggerKilledAndRestartedKeepsItsLogAndNamesTheCommandsItMissed) {
  if (!NetnsReady()) GTEST_SKIP() << "needs root for a private network namespace";
  Deployment d(0.0, /*logger_lcmlog=*/true);
  d.Up({"logger", "rig", "excite"});
  ASSERT_EQ(d.StartExperiment(50, "prbs:bits=8,amp=1", 12.75, 3).code, 0);
  ASSERT_TRUE(Until(
      *d.t,
      [&] {
        const auto* s = d.Experiment(50, "rig");
        return s && s->samples_done >= 60;
      },
      10.0));
  d.logger.Kill(SIGKILL);
  struct stat before {};
  ASSERT_EQ(stat((d.dir + "/log.lcmlog").c_str(), &before), 0);
  ASSERT_GT(before.st_size, 0);
  d.Wait(1.0);
  d.Up({"logger"});
  ASSERT_TRUE(d.WaitEnd(50, 10.0));
  ASSERT_EQ(d.Experiment(50, "rig")->state, experiment_status_t::STATE_DONE);
  // The blocks it missed are recovered from the rig; the commands it missed are named.
  nlohmann::json entry;
  ASSERT_TRUE(Until(
      *d.t,
      [&] {
        if (!d.services.count("logger")) return false;
        const nlohmann::json details = nlohmann::json::parse(d.services["logger"].details_json);
        for (const auto& e : details["experiments"])
          if (e["experiment_id"] == 50 && e["complete"].get<bool>()) entry = e;
        return !entry.is_null() && !entry["samples_without_command"].empty();
      },
      10.0))
      << d.services["logger"].details_json;
  const auto gap = entry["samples_without_command"][0];
  EXPECT_GT(gap[0].get<int64_t>(), 0);
  EXPECT_LT(gap[1].get<int64_t>(), 255);
  // The log of the first run is still there, and the second run appended to it.
  lcm::LogFile log(d.dir + "/log.lcmlog", "r");
  int64_t commands_from_zero = 0, events = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    ++events;
    actuator_command_t c;
    if (e->channel == Channel(kRig, ChannelKind::kCommand) && c.decode(e->data, 0, e->datalen) > 0 &&
        c.experiment_id == 50 && c.first_sample == 0)
      ++commands_from_zero;
  }
  EXPECT_EQ(commands_from_zero, 1);
  struct stat after {};
  ASSERT_EQ(stat((d.dir + "/log.lcmlog").c_str(), &after), 0);
  EXPECT_GT(after.st_size, before.st_size);
  EXPECT_GT(events, 20);
}

TEST(ControlPlane, ARequestWhileTheCatalogueIsDownIsRefusedAloudOrAcknowledgedLater) {
  if (!NetnsReady()) GTEST_SKIP() << "needs root for a private network namespace";
  Deployment d;
  d.Up({"catalog", "logger", "rig", "excite", "worker"});
  ASSERT_EQ(d.StartExperiment(60, "prbs:bits=6,amp=1", 3.15, 10).code, 0);
  ASSERT_TRUE(d.WaitEnd(60, 10.0));
  d.catalog.Kill(SIGKILL);
  const std::vector<std::string> request = {"models", "request", "--rig", kRig, "--experiment",
                                            "60", "--method", "arx", "--key-file",
                                            d.keys.operator_key};
  std::vector<std::string> short_wait = request;
  short_wait.insert(short_wait.end(), {"--timeout", "2"});
  const CliResult lost = d.Cli(short_wait);
  EXPECT_EQ(lost.code, 1) << lost.output;
  EXPECT_NE(lost.output.find("no answer from idrig-catalog"), std::string::npos) << lost.output;
  EXPECT_NE(lost.output.find("nothing was queued"), std::string::npos);
  EXPECT_LT(lost.seconds, 5.0);
  // The same request while the catalogue comes back 2 s later: re-sent until acknowledged.
  std::thread restart([&] {
    std::this_thread::sleep_for(std::chrono::seconds(2));
    d.StartService(&d.catalog, "catalog");
  });
  std::vector<std::string> long_wait = request;
  long_wait.insert(long_wait.end(), {"--timeout", "20", "--wait"});
  const CliResult later = d.Cli(long_wait);
  restart.join();
  ASSERT_EQ(later.code, 0) << later.output;
  EXPECT_NE(later.output.find("waiting for idrig-catalog to acknowledge"), std::string::npos);
  EXPECT_NE(later.output.find("stored as model"), std::string::npos) << later.output;
}

TEST(ControlPlane, CommandsExitNonZeroWithTheReason) {
  if (!NetnsReady()) GTEST_SKIP() << "needs root for a private network namespace";
  Deployment d;
  d.Up({"catalog", "logger", "rig", "excite", "worker"});
  auto expect = [&](std::vector<std::string> args, int code, const std::string& text, double max_s) {
    const CliResult r = d.Cli(args);
    EXPECT_EQ(r.code, code) << r.output;
    EXPECT_NE(r.output.find(text), std::string::npos) << r.output;
    EXPECT_LT(r.seconds, max_s) << r.output;
  };
  const std::vector<std::string> start = {"experiment", "start", "--rig", kRig, "--key-file",
                                          d.keys.operator_key};
  const std::string prbs = "prbs:bits=6,amp=1";
  auto with = [&](std::vector<std::string> base, std::vector<std::string> more) {
    base.insert(base.end(), more.begin(), more.end());
    return base;
  };
  expect(with(start, {"--signal", prbs, "--duration", "1e9"}), 1, "above this rig's maximum 600", 4.0);
  expect(with(start, {"--signal", prbs, "--fs", "1e-6"}), 1, "outside this rig's range", 4.0);
  expect(with(start, {"--signal", "step:amp=9"}), 1, "refused", 4.0);
  expect({"experiment", "start", "--rig", "nosuch", "--signal", "step", "--timeout", "3",
          "--key-file", d.keys.operator_key},
         1, "no answer from idrig-excite of rig nosuch", 5.0);
  expect({"experiment", "stop", "--rig", kRig, "--experiment", "12345", "--key-file",
          d.keys.operator_key},
         1, "is not running", 4.0);
  expect({"models", "request", "--rig", kRig, "--experiment", "999", "--method", "arx",
          "--key-file", d.keys.operator_key},
         1, "unknown to the catalogue", 6.0);
  // A job that fails on the worker: --wait exits 1 with the job's error.
  ASSERT_EQ(d.StartExperiment(70, "prbs:bits=6,amp=1", 3.15, 10).code, 0);
  ASSERT_TRUE(d.WaitEnd(70, 10.0));
  d.Wait(0.6);
  expect({"models", "request", "--rig", kRig, "--experiment", "70", "--method", "arx", "--options",
          R"({"order":400})", "--wait", "--key-file", d.keys.operator_key},
         1, "failed: identification failed", 20.0);
}

}  // namespace
}  // namespace idrig
