#include "services/rig_sim/rig_journal.h"

#include "core/transport/service_util.h"

#include <dirent.h>
#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace idrig {

RigJournal::RigJournal(std::string dir) : dir_(std::move(dir)) {
  if (dir_.empty()) return;
  MakeDirectories(dir_);
  struct stat info {};
  if (stat(dir_.c_str(), &info) != 0 || !S_ISDIR(info.st_mode))
    throw std::invalid_argument("rig state_dir '" + dir_ + "' is not a directory");
}

RigJournal::~RigJournal() {
  if (fd_ >= 0) close(fd_);
}

std::string RigJournal::Path(int64_t experiment_id, const char* suffix) const {
  return dir_ + "/exp-" + std::to_string(experiment_id) + suffix;
}

void RigJournal::Begin(int64_t experiment_id) {
  if (!enabled()) return;
  if (fd_ >= 0) close(fd_);
  open_id_ = experiment_id;
  fd_ = open(Path(experiment_id, ".blocks").c_str(), O_WRONLY | O_CREAT | O_APPEND, 0600);
  if (fd_ < 0) spdlog::error("cannot open the rig journal in '{}': blocks not kept", dir_);
}

void RigJournal::Append(int64_t experiment_id, const std::vector<uint8_t>& block) {
  if (fd_ < 0 || experiment_id != open_id_) return;
  std::vector<uint8_t> record(4 + block.size());
  const uint32_t n = static_cast<uint32_t>(block.size());
  for (int i = 0; i < 4; ++i) record[i] = static_cast<uint8_t>(n >> (24 - 8 * i));
  std::copy(block.begin(), block.end(), record.begin() + 4);
  if (write(fd_, record.data(), record.size()) != static_cast<ssize_t>(record.size()))
    spdlog::error("rig journal: write of a block of experiment {} failed", experiment_id);
}

void RigJournal::End(int64_t experiment_id, const std::string& message) {
  if (!enabled()) return;
  if (experiment_id == open_id_ && fd_ >= 0) {
    close(fd_);
    fd_ = -1;
  }
  std::ofstream(Path(experiment_id, ".end"), std::ios::trunc) << message << "\n";
}

std::vector<RigJournal::Experiment> RigJournal::Load() const {
  std::vector<Experiment> out;
  if (!enabled()) return out;
  DIR* d = opendir(dir_.c_str());
  if (!d) return out;
  while (dirent* entry = readdir(d)) {
    const std::string name = entry->d_name;
    long long id = 0;
    char tail[16] = {0};
    if (std::sscanf(name.c_str(), "exp-%lld.%15s", &id, tail) != 2 || std::string(tail) != "blocks")
      continue;
    Experiment e;
    e.experiment_id = id;
    std::ifstream in(dir_ + "/" + name, std::ios::binary);
    std::vector<uint8_t> header(4);
    while (in.read(reinterpret_cast<char*>(header.data()), 4)) {
      const uint32_t n = (uint32_t(header[0]) << 24) | (uint32_t(header[1]) << 16) |
                         (uint32_t(header[2]) << 8) | header[3];
      std::vector<uint8_t> block(n);
      if (n > (1u << 20) || !in.read(reinterpret_cast<char*>(block.data()), n)) break;  // torn
      e.blocks.push_back(std::move(block));
    }
    e.ended = access(Path(id, ".end").c_str(), F_OK) == 0;
    out.push_back(std::move(e));
  }
  closedir(d);
  std::sort(out.begin(), out.end(),
            [](const Experiment& a, const Experiment& b) { return a.experiment_id < b.experiment_id; });
  return out;
}

void RigJournal::Prune(int keep) const {
  const std::vector<Experiment> all = Load();
  for (size_t i = 0; i + static_cast<size_t>(std::max(keep, 1)) < all.size(); ++i) {
    std::remove(Path(all[i].experiment_id, ".blocks").c_str());
    std::remove(Path(all[i].experiment_id, ".end").c_str());
  }
}

}  // namespace idrig
