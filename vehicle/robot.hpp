#pragma once
/// One simulated robot as its driver behaves, without DDS or clocks: it takes velocity commands,
/// stops by its watchdog when the newest is older than the timeout, and moves as core::body_step says
/// (the vehicle model's limits and a first-order lag). shapeform_vehicle (vehicle_node.cpp) wires it to
/// ROS 2's topics.
#include <cstdint>
#include <random>

#include "core/vehicle.hpp"
#include "protocol/samples.hpp"

namespace shapeform::vehicle {

class Robot {
 public:
  /// A robot at rest whose controlled point (core::controlled_point) is `point`, heading `heading`;
  /// command_timeout_ns: the watchdog; noise_m: the standard deviation of each published position's
  /// noise, drawn from `seed`.
  Robot(const core::VehicleParams& p, const core::BodyParams& b, const core::Vec2& point, double heading,
        std::int64_t command_timeout_ns, double noise_m, std::uint64_t seed);

  /// A command received at now_ns (the newest wins).
  void on_command(const dds::VelocitySample& v, std::int64_t now_ns);
  /// Moves h seconds on from now_ns, under the newest command while it is fresh, else under zero.
  /// Returns true when the watchdog stopped it in this call (its command just went stale).
  bool step(std::int64_t now_ns, double h);
  /// Whether the watchdog holds it (no command yet, or the newest older than the timeout).
  bool stopped_by_watchdog(std::int64_t now_ns) const;
  /// The pose a driver publishes: its base and heading, with noise on the position, and its velocity
  /// (body frame) in the twist.
  dds::PoseSample pose();
  const core::Body& body() const { return body_; }
  /// The controlled point now (no noise).
  core::Vec2 point() const { return core::controlled_point(params_, body_.base, body_.heading); }
  std::uint64_t commands() const { return commands_; }
  std::uint64_t watchdog_stops() const { return watchdog_stops_; }

 private:
  core::VehicleParams params_;
  core::BodyParams body_params_;
  core::Body body_;
  std::int64_t timeout_ns_;
  double noise_m_;
  std::mt19937_64 rng_;
  core::Twist command_;
  std::int64_t command_ns_ = -1;  ///< when the newest command came; -1: none yet
  bool held_ = true;              ///< the watchdog held it at the last step
  std::uint64_t commands_ = 0;
  std::uint64_t watchdog_stops_ = 0;
};

}  // namespace shapeform::vehicle
