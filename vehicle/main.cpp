// shapeform_vehicle: simulated robots that behave as ROS 2 robot drivers do (pose out on odom, velocity
// commands in on cmd_vel, a watchdog), so that agents with vehicle.interface ros2 are tested here.
#include <string>
#include <vector>

#include <algorithm>

#include "app/app.hpp"
#include "core/swarm.hpp"
#include "protocol/samples.hpp"
#include "vehicle_node.hpp"

int main(int argc, char** argv) {
  using namespace shapeform;
  app::App app("shapeform_vehicle",
               "shapeform_vehicle: simulated robots, one or many in one process, each behaving as a ROS 2 robot "
               "driver: it publishes its pose (nav_msgs/Odometry on rt/<vehicle.namespace>/odom, or PoseStamped) "
               "at vehicle_sim.pose_rate_hz, follows the velocity commands of rt/<namespace>/cmd_vel within the "
               "vehicle.* model and limits with a first-order lag (vehicle_sim.response_s), and stops when the "
               "newest command is older than vehicle_sim.command_timeout_s. Robot i starts where agent i starts "
               "(its seeded start and heading). docs/ROBOTS.md");
  std::string ids_text, seed;
  vehicle::VehicleOptions opt;
  app.cli()
      .add_option("--ids", ids_text, "robot ids hosted here: 0-11, or 0,3,5, or 0-9,20-29 (the agents' ids)")
      ->required();
  app.add_config_options();
  app.cli().add_option("--seed", seed, "seeded starts: robot i starts where agent i of swarm.agents starts");
  app.cli().add_option("--record", opt.record_dir, "write DIR/vehicles.csv: every robot's pose at 10 Hz");
  app.cli().add_flag("--json", opt.json, "machine output: JSON lines on stdout (status, watchdog, resumed)");
  if (const auto rc = app.parse(argc, argv)) return *rc;
  std::vector<std::int32_t> ids;
  std::string error;
  if (!app::parse_id_list(ids_text, dds::kMaxAgentId, 1000, ids, error)) return app.usage_error("--ids: " + error);
  const auto cfg = app.load_config(app.given("--seed") ? std::vector<std::string>{"swarm.seed=" + seed}
                                                        : std::vector<std::string>{});
  if (!cfg) return app::kExitUsage;
  // Where the agents start (agent::seeded_start): position id of the seeded uniform start.
  const int n = std::max(cfg->swarm.agents, *std::max_element(ids.begin(), ids.end()) + 1);
  const std::vector<core::Vec2> all = core::uniform_start(n, cfg->swarm.seed, cfg->swarm.init_half_width);
  std::vector<core::Vec2> starts;
  for (const auto id : ids) starts.push_back(all[static_cast<std::size_t>(id)]);
  return vehicle::run_vehicles(ids, starts, *cfg, opt);
}
