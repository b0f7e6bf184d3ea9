#pragma once
/// Hands the viewer's frames from its loop to every open event stream (one HTTP thread each). The loop
/// publishes one delta per tick (Scene::delta), and a snapshot (Scene::snapshot) beside it when a stream
/// asked for one. A stream that joins, or fell more than kKept deltas behind, gets a snapshot and goes on
/// with the deltas after it; one a few deltas behind gets each of them in order: a page never misses a
/// change and never receives an unbounded backlog.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace shapeform::view {

class FrameBus {
 public:
  /// Deltas kept for streams that fell behind (2 s at 15 frames/s).
  static constexpr std::size_t kKept = 32;

  /// Makes `delta` the newest frame (numbered one more than the previous) and, when given, `snapshot`
  /// the state that the next delta applies to; wakes every waiting stream.
  void publish(std::string delta, std::optional<std::string> snapshot = std::nullopt) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++seq_;
      deltas_.push_back(std::move(delta));
      if (deltas_.size() > kKept) deltas_.pop_front();
      if (snapshot) {
        snapshot_ = std::move(*snapshot);
        snapshot_seq_ = seq_;
        snapshot_wanted_ = false;
      }
    }
    cv_.notify_all();
  }

  /// A stream asked for a snapshot: the loop publishes one with its next delta.
  bool snapshot_wanted() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return snapshot_wanted_;
  }

  /// For a stream that has sent everything up to frame `sent` (0: nothing yet): waits up to timeout_s
  /// for newer frames and returns what to send next, in order: the deltas after `sent` when they are
  /// all kept, else the newest snapshot (asked of the loop and waited for). `sent` moves to the last
  /// frame returned. nullopt on timeout or once closed.
  std::optional<std::vector<std::string>> wait_newer(std::uint64_t& sent, double timeout_s) {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto until = deadline(timeout_s);
    if (!cv_.wait_until(lock, until, [&] { return closed_ || seq_ > sent; }) || closed_) return std::nullopt;
    if (sent > 0 && seq_ - sent <= deltas_.size()) {
      std::vector<std::string> out(deltas_.end() - static_cast<std::ptrdiff_t>(seq_ - sent), deltas_.end());
      sent = seq_;
      return out;
    }
    if (!snapshot_current(lock, until)) return std::nullopt;
    sent = snapshot_seq_;
    return std::vector<std::string>{snapshot_};
  }

  /// The newest snapshot, asked of the loop and waited for up to timeout_s ("" before the first frame
  /// or on timeout).
  std::string latest(double timeout_s = 2.0) {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto until = deadline(timeout_s);
    if (!cv_.wait_until(lock, until, [&] { return closed_ || seq_ > 0; }) || closed_) return "";
    return snapshot_current(lock, until) ? snapshot_ : "";
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
  static std::chrono::steady_clock::time_point deadline(double timeout_s) {
    return std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                  std::chrono::duration<double>(timeout_s));
  }

  /// Makes snapshot_ one of the newest frame (asking the loop for one unless it is): false on timeout
  /// or once closed.
  bool snapshot_current(std::unique_lock<std::mutex>& lock, std::chrono::steady_clock::time_point until) {
    if (snapshot_seq_ == seq_) return true;
    snapshot_wanted_ = true;
    const std::uint64_t after = seq_;
    return cv_.wait_until(lock, until, [&] { return closed_ || snapshot_seq_ > after; }) && !closed_;
  }

  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::string> deltas_;  ///< the newest kKept deltas, the last one numbered seq_
  std::uint64_t seq_ = 0;
  std::string snapshot_;
  std::uint64_t snapshot_seq_ = 0;
  bool snapshot_wanted_ = false;
  bool closed_ = false;
};

}  // namespace shapeform::view
