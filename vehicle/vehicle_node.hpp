#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "config/config.hpp"

namespace shapeform::vehicle {

struct VehicleOptions {
  /// Machine output on stdout, one JSON object per line with an "event" key: "start" (ids, topics),
  /// "status" once a second per robot (its controlled point x, y, base, heading, commands,
  /// watchdog_stops, stopped), "watchdog" when a robot's commands stop (it is stopped) and "resumed"
  /// when they come back, "rejected" for a refused command (throttled), "stop".
  bool json = false;
  /// Non-empty: write DIR/vehicles.csv, every robot's pose at 10 Hz (docs/RECORDING.md).
  std::string record_dir;
};

/// Runs the simulated robots `ids` until SIGINT/SIGTERM: each starts with its controlled point where
/// the agent of the same id starts (its seeded start, or `starts` when given, one per id) and heading
/// (core::start_heading), publishes its pose on rt/<vehicle.namespace>/<vehicle.pose_topic> at
/// vehicle_sim.pose_rate_hz and follows the commands of rt/<namespace>/<vehicle.cmd_topic>.
/// Returns the exit status (0 clean stop, 1 runtime failure such as a participant that cannot be made).
int run_vehicles(const std::vector<std::int32_t>& ids, const std::vector<core::Vec2>& starts,
                 const config::Config& cfg, const VehicleOptions& opt);

}  // namespace shapeform::vehicle
