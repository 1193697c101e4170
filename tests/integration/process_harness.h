#pragma once
// Shared by the process tests: the test binary enters one private network namespace for all its
// tests (unshare(CLONE_NEWNET), lo with multicast; needs root, else the tests skip), starts the
// services as real processes over udpm (ttl=0), and runs the `idrig` command line.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sched.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/transport/auth.h"
#include "core/transport/signing.h"
#include "core/transport/transport.h"

namespace idrig {
namespace harness {

inline bool& NetnsReady() {
  static bool ready = false;
  return ready;
}

class NetnsEnvironment : public ::testing::Environment {
 public:
  void SetUp() override {
    if (geteuid() != 0) return;
    if (unshare(CLONE_NEWNET) != 0) return;
    NetnsReady() =
        std::system("ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo") == 0;
  }
};

struct Child {
  pid_t pid = -1;
  ~Child() { Kill(SIGKILL); }
  void Kill(int signal) {
    if (pid <= 0) return;
    kill(pid, signal);
    int status = 0;
    waitpid(pid, &status, 0);
    pid = -1;
  }
};

inline std::string Dir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/" + name + "_" + std::to_string(getpid());
  std::system(("rm -rf '" + dir + "'").c_str());
  mkdir(dir.c_str(), 0755);
  return dir;
}

inline void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Starts IDRIG_BIN_DIR/program with args + --url url, stdout and stderr appended to log.
inline void Start(Child* child, const std::string& program, std::vector<std::string> args,
                  const std::string& log, const std::string& url) {
  args.insert(args.begin(), std::string(IDRIG_BIN_DIR) + "/" + program);
  args.push_back("--url");
  args.push_back(url);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    execv(argv[0], argv.data());
    _exit(127);
  }
  child->pid = pid;
}

template <class Predicate>
bool Until(Transport& t, Predicate done, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    t.Handle(10);
    if (done()) return true;
  }
  return false;
}

// The three deployment keys of a test directory, and the config keys naming them.
struct Keys {
  std::string command, operator_key, service;
  explicit Keys(const std::string& dir)
      : command(dir + "/hmac.key"), operator_key(dir + "/operator.key"), service(dir + "/service.key") {
    for (const auto& k : {command, operator_key, service}) WriteNewKeyFile(k);
  }
  nlohmann::json Roles() const {
    return {{"operator_key_file", operator_key}, {"service_key_file", service}};
  }
  HmacKey Operator() const { return ReadKeyFile(operator_key); }
  HmacKey Service() const { return ReadKeyFile(service); }
};

struct CliResult {
  int code = -1;
  std::string output;  // stdout and stderr
  double seconds = 0;
};

// Runs IDRIG_BIN_DIR/idrig args... and waits for it.
inline CliResult RunCli(std::vector<std::string> args, const std::string& log) {
  args.insert(args.begin(), std::string(IDRIG_BIN_DIR) + "/idrig");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::remove(log.c_str());
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  CliResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.output = ReadFile(log);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace harness
}  // namespace idrig
