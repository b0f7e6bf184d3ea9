#include <catch2/catch.hpp>
#include <thread>

#include "frame_bus.hpp"

using shapeform::view::FrameBus;

TEST_CASE("FrameBus: a stream gets the newest frame once, skipping those it missed") {
  FrameBus bus;
  std::uint64_t seen = 0;
  CHECK_FALSE(bus.wait_newer(seen, 0.01));
  bus.publish("a");
  bus.publish("b");
  CHECK(bus.wait_newer(seen, 0.01) == std::optional<std::string>("b"));
  CHECK_FALSE(bus.wait_newer(seen, 0.01));
  CHECK(bus.latest() == "b");
}

TEST_CASE("FrameBus: a waiting stream wakes on publish, and on close with nothing") {
  FrameBus bus;
  std::uint64_t seen = 0;
  std::thread t([&] { bus.publish("x"); });
  CHECK(bus.wait_newer(seen, 5.0) == std::optional<std::string>("x"));
  t.join();
  std::thread c([&] { bus.close(); });
  CHECK_FALSE(bus.wait_newer(seen, 5.0));
  c.join();
  CHECK(bus.closed());
}
