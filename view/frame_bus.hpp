#pragma once
/// Hands the newest frame from the viewer's loop to every open event stream (one HTTP thread each).
/// A stream that falls behind skips to the newest frame: a browser never receives a backlog.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>

namespace shapeform::view {

class FrameBus {
 public:
  /// Makes `frame` the newest one and wakes every waiting stream.
  void publish(std::string frame) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      frame_ = std::move(frame);
      ++seq_;
    }
    cv_.notify_all();
  }

  /// Waits up to timeout_s for a frame newer than `seen` (0: none seen yet): that frame, with `seen`
  /// moved to it; nullopt on timeout or once closed.
  std::optional<std::string> wait_newer(std::uint64_t& seen, double timeout_s) {
    std::unique_lock<std::mutex> lock(mutex_);
    const bool got = cv_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                                  [&] { return closed_ || seq_ > seen; });
    if (!got || closed_) return std::nullopt;
    seen = seq_;
    return frame_;
  }

  /// The newest frame ("" before the first).
  std::string latest() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return frame_;
  }

  /// Ends every stream (the program stops).
  void close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    cv_.notify_all();
  }
  bool closed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return closed_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::string frame_;
  std::uint64_t seq_ = 0;
  bool closed_ = false;
};

}  // namespace shapeform::view
