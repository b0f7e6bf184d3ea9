#include "frame_bus.hpp"

#include <atomic>
#include <catch2/catch.hpp>
#include <string>
#include <thread>

using shapeform::view::FrameBus;
using Frames = std::vector<std::string>;

namespace {

/// Publishes delta "dN" each time, with snapshot "sN" when one is wanted (the viewer's loop).
void tick(FrameBus& bus, int& n) {
  ++n;
  const bool want = bus.snapshot_wanted();
  bus.publish("d" + std::to_string(n),
              want ? std::optional<std::string>("s" + std::to_string(n)) : std::nullopt);
}

/// A loop publishing every millisecond until stopped.
struct Loop {
  FrameBus& bus;
  int& n;
  std::atomic<bool> stop{false};
  std::thread thread{[this] {
    while (!stop) {
      tick(bus, n);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }};
  ~Loop() {
    stop = true;
    thread.join();
  }
};

}  // namespace

TEST_CASE("FrameBus: a stream starts from a snapshot asked of the loop, then gets every delta in order") {
  FrameBus bus;
  int n = 0;
  tick(bus, n);  // d1: nobody asked for a snapshot
  CHECK_FALSE(bus.snapshot_wanted());
  std::uint64_t sent = 0;
  std::optional<Frames> got;
  std::thread stream([&] { got = bus.wait_newer(sent, 5.0); });
  while (!bus.snapshot_wanted()) std::this_thread::yield();  // the stream asked
  tick(bus, n);                                              // d2 with s2
  stream.join();
  CHECK(got == Frames{"s2"});
  CHECK(sent == 2);
  CHECK_FALSE(bus.snapshot_wanted());
  CHECK_FALSE(bus.wait_newer(sent, 0.01));  // nothing newer
  tick(bus, n);
  tick(bus, n);
  tick(bus, n);  // the stream was slow: it gets d3, d4, d5, none skipped
  CHECK(bus.wait_newer(sent, 0.01) == Frames{"d3", "d4", "d5"});
  CHECK(sent == 5);
}

TEST_CASE("FrameBus: a stream more than kKept deltas behind gets a snapshot again") {
  FrameBus bus;
  int n = 0;
  tick(bus, n);
  std::uint64_t sent = 1;  // as if it had sent d1
  for (std::size_t k = 0; k < FrameBus::kKept; ++k) tick(bus, n);
  auto got = bus.wait_newer(sent, 0.01);  // exactly kKept behind: every one
  REQUIRE(got);
  CHECK(got->size() == FrameBus::kKept);
  CHECK(got->front() == "d2");
  CHECK(got->back() == "d" + std::to_string(n));
  for (std::size_t k = 0; k <= FrameBus::kKept; ++k) tick(bus, n);
  {
    Loop loop{bus, n};
    got = bus.wait_newer(sent, 5.0);
  }
  REQUIRE(got);
  REQUIRE(got->size() == 1);
  CHECK(got->front()[0] == 's');
  CHECK(sent == std::stoul(got->front().substr(1)));
}

TEST_CASE("FrameBus: latest() is a snapshot of the newest frame; nothing before the first frame") {
  FrameBus bus;
  CHECK(bus.latest(0.01).empty());
  int n = 0;
  Loop loop{bus, n};
  const std::string s = bus.latest(5.0);
  REQUIRE_FALSE(s.empty());
  CHECK(s[0] == 's');
}

TEST_CASE("FrameBus: a waiting stream wakes on close with nothing") {
  FrameBus bus;
  std::uint64_t seen = 0;
  std::thread c([&] { bus.close(); });
  CHECK_FALSE(bus.wait_newer(seen, 5.0));
  c.join();
  CHECK(bus.closed());
}
