#include "core/transport/transport.h"

#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>
#include <stdexcept>

namespace idrig {

int64_t NowMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string PrivateUdpmUrl(int port, int ttl) {
  return "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=" + std::to_string(ttl) +
         "&recv_buf_size=4194304";
}

namespace {

class LcmTransport : public Transport {
 public:
  explicit LcmTransport(const std::string& url) : lcm_(url) {
    if (!lcm_.good())
      throw std::runtime_error("cannot start LCM on '" + url +
                               "' (for udpm: is there a multicast route? see docs/services.md)");
  }

  int Publish(const std::string& channel, const void* data, size_t size) override {
    std::lock_guard<std::mutex> lock(publish_mutex_);
    const int rc = lcm_.publish(channel, data, static_cast<unsigned int>(size));
    if (rc == 0)
      ++counters_.published;
    else
      ++counters_.publish_errors;
    return rc;
  }

  void Subscribe(const std::string& channel_regex, RawHandler handler,
                 int queue_capacity) override {
    auto holder = std::make_unique<Holder>();
    holder->handler = std::move(handler);
    holder->counters = &counters_;
    lcm::Subscription* sub = lcm_.subscribe(channel_regex, &Holder::Receive, holder.get());
    if (sub && queue_capacity > 0) sub->setQueueCapacity(queue_capacity);
    holders_.push_back(std::move(holder));
  }

  int Handle(int timeout_ms) override {
    int handled = 0;
    int rc = lcm_.handleTimeout(timeout_ms);
    if (rc < 0) return -1;
    handled += rc > 0 ? 1 : 0;
    // Drain what is already queued without waiting again.
    while (handled < 10000 && (rc = lcm_.handleTimeout(0)) > 0) ++handled;
    return rc < 0 ? -1 : handled;
  }

 private:
  struct Holder {
    RawHandler handler;
    TransportCounters* counters = nullptr;
    void Receive(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
      ++counters->received;
      try {
        handler(channel, static_cast<const uint8_t*>(rbuf->data), rbuf->data_size);
      } catch (const std::exception& e) {  // LCM calls us from C: nothing may escape.
        ++counters->handler_errors;
        spdlog::error("handler of a message on {} failed: {}", channel, e.what());
      } catch (...) {
        ++counters->handler_errors;
        spdlog::error("handler of a message on {} failed", channel);
      }
    }
  };
  lcm::LCM lcm_;
  std::mutex publish_mutex_;
  std::vector<std::unique_ptr<Holder>> holders_;
};

class LossyTransport : public Transport {
 public:
  LossyTransport(std::unique_ptr<Transport> inner, double loss, uint64_t seed)
      : inner_(std::move(inner)), loss_(loss), rng_(seed) {}
  int Publish(const std::string& channel, const void* data, size_t size) override {
    const int rc = inner_->Publish(channel, data, size);
    if (rc == 0) ++counters_.published;
    return rc;
  }
  void Subscribe(const std::string& channel_regex, RawHandler handler,
                 int queue_capacity) override {
    inner_->Subscribe(
        channel_regex,
        [this, handler](const std::string& channel, const uint8_t* data, size_t size) {
          // Uniform in [0, 1) from the raw engine output (no implementation-defined distribution).
          const double draw = static_cast<double>(rng_() >> 11) * 0x1.0p-53;
          if (draw < loss_) return;
          ++counters_.received;
          handler(channel, data, size);
        },
        queue_capacity);
  }
  int Handle(int timeout_ms) override { return inner_->Handle(timeout_ms); }

 private:
  std::unique_ptr<Transport> inner_;
  double loss_;
  std::mt19937_64 rng_;
};

}  // namespace

std::unique_ptr<Transport> MakeLcmTransport(const std::string& url) {
  return std::make_unique<LcmTransport>(url);
}

std::unique_ptr<Transport> MakeLossyTransport(std::unique_ptr<Transport> inner, double loss,
                                              uint64_t seed) {
  if (!(loss >= 0.0 && loss < 1.0))
    throw std::invalid_argument("loss must be in [0, 1), got " + std::to_string(loss));
  return std::make_unique<LossyTransport>(std::move(inner), loss, seed);
}

}  // namespace idrig
