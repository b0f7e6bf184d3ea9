#pragma once
/// shapeform configuration: YAML -> these plain structs. The one config loader of the project.
/// Each field's default is its initialiser here (or in core / dds); its key, type, unit, range and
/// description are declared once in the config table (config_table(), common/config/table.cpp).
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/compiled_command.hpp"
#include "core/metrics.hpp"
#include "core/params.hpp"
#include "core/vehicle.hpp"
#include "protocol/samples.hpp"
#include "protocol/transport.hpp"

namespace shapeform::config {

inline constexpr int kSchemaVersion = 1;

/// Largest config file load() reads, in bytes (1 MiB: the longest scenario is a few kB, so anything
/// bigger is a wrong path, e.g. a log or a device).
inline constexpr std::size_t kMaxFileBytes = std::size_t{1} << 20;

/// How agents start when no explicit start is given.
struct SwarmConfig {
  int agents = 12;              ///< swarm size
  std::uint64_t seed = 1;       ///< seed of the uniform start
  double init_half_width = 5.0; ///< start uniform in [-w, w]^2
};

/// Simulator-only settings.
struct SimConfig {
  long steps = 500;  ///< number of integration steps
};

/// Agent process settings.
struct AgentConfig {
  double rate_hz = 50.0;                  ///< control loop rate
  /// Drop a neighbour unheard for this many periods. Loss alone must not do it: a neighbour whose k
  /// states in a row are lost is dropped, which happens to a pair losing a fraction q of its exchanges
  /// (1 - q) q^k of its ticks; 40 periods keep that below 1e-8 at q = 0.64 (40 % loss on both hosts), so
  /// who is in the swarm does not change with loss (docs/RELIABILITY.md, "Loss on every host").
  double neighbour_timeout_periods = 40.0;
  double status_rate_hz = 1.0;            ///< agent status publication rate
  /// Listening time before the first publication, s: an agent that hears its id from another
  /// participant meanwhile refuses to run (exit 2) instead of joining as a duplicate.
  double identity_grace_s = 1.0;
  /// How agents step: false = free running (each on its own clock, using the newest neighbour states);
  /// true = lockstep (step k+1 waits for every neighbour's step k: the simulator's synchronous update).
  bool lockstep = false;
  /// AgentState rate before the first command, Hz, at most rate_hz (the default: the loop rate): a large
  /// swarm's discovery then runs on a nearly idle host instead of beside all-to-all state at the full rate
  /// (docs/BENCHMARKS.md, lever 10).
  double idle_rate_hz = 1000.0;
  /// The state rate before the first command: idle_rate_hz, at most the loop rate.
  double idle_state_rate_hz() const { return idle_rate_hz < rate_hz ? idle_rate_hz : rate_hz; }
  /// neighbour_timeout_periods of the loop, ns: how long a commanded agent keeps a silent neighbour.
  std::int64_t neighbour_timeout_ns() const {
    return static_cast<std::int64_t>(neighbour_timeout_periods / rate_hz * 1e9);
  }
  /// neighbour_timeout_periods at the state rate before the first command (idle_state_rate_hz), ns.
  std::int64_t idle_neighbour_timeout_ns() const {
    return static_cast<std::int64_t>(neighbour_timeout_periods / idle_state_rate_hz() * 1e9);
  }
  /// A process hosting several agents publishes their states as one AgentStateBatch per tick
  /// (shapeform/state_batch) instead of one AgentState per agent (shapeform/state).
  bool batch_state = true;
  /// Most states per AgentStateBatch sample: a process hosting more publishes several per tick, each
  /// its own instance keyed by its first id (dds::batch_ranges cuts them).
  long long batch_max_states = static_cast<long long>(dds::kBatchStatesPerDatagram);
  /// On a clean stop, leave without the participant's goodbye (dds::Node::exit_without_goodbye): peers
  /// drop it after transport.lease_s instead of racing Fast DDS 2.9's lease timer.
  bool leave_by_lease = false;
};

/// How an agent reaches the vehicle it drives (the vehicle.* keys beyond its model and limits): inside
/// its own process (`internal`), or a robot over ROS 2's topics (`ros2`: its pose read from
/// rt/<namespace>/<pose_topic>, its command written to rt/<namespace>/<cmd_topic>; docs/ROBOTS.md).
struct VehicleLink {
  enum class Interface { Internal, Ros2 };
  enum class CmdType { Twist, TwistStamped };
  enum class PoseType { Odometry, PoseStamped };
  Interface interface = Interface::Internal;
  std::string ns = "robot_{id}";  ///< the vehicle's namespace, {id} the agent's id
  std::string cmd_topic = "cmd_vel";
  CmdType cmd_type = CmdType::Twist;
  std::string pose_topic = "odom";
  PoseType pose_type = PoseType::Odometry;
  std::string frame = "map";     ///< the frame every pose must be in (shared by the swarm)
  double pose_timeout_s = 0.5;   ///< a pose older than this stops the vehicle
  double pose_jump_m = 0.5;      ///< a pose may move at most max_speed * elapsed + this from the last
  bool ros2() const { return interface == Interface::Ros2; }
  /// The namespace of agent id's vehicle: ns with every {id} replaced by the id, without a leading '/'
  /// (ROS 2 namespaces are absolute: "/robot_{id}" and "robot_{id}" name one, rt/robot_3/...).
  std::string namespace_of(std::int32_t id) const;
  /// A topic of agent id's vehicle (cmd_topic or pose_topic) with every {id} replaced (an absolute
  /// topic, "/vrpn_mocap/robot_{id}/pose", names each robot's own that way).
  static std::string with_id(const std::string& text, std::int32_t id);
};

/// shapeform_vehicle's settings: how the simulated robots answer their commands (docs/ROBOTS.md).
struct VehicleSimConfig {
  double pose_rate_hz = 50.0;      ///< pose publication and integration rate
  double response_s = 0.1;         ///< first-order lag of the wheels (core::BodyParams)
  double pose_noise_m = 0.0;       ///< standard deviation of the noise on each published position, m
  double command_timeout_s = 0.5;  ///< watchdog: a command older than this stops the vehicle
  std::string child_frame = "base_link";  ///< Odometry's child_frame_id (after the namespace)
};

/// Supervisor settings.
struct SupervisorConfig {
  double metrics_rate_hz = 10.0;      ///< metrics computation / publication / recording rate
  double target_rate_hz = 50.0;       ///< tracking target publication rate
  double agent_timeout_s = 1.0;       ///< an agent unheard for this long is shown dead
  core::ConvergenceDetector::Params converge;  ///< what "converged" means
  double flush_s = 1.0;               ///< recorder flush period
};

/// The ROS 2 mirror (docs/ROS2.md): the supervisor republishes the swarm on ROS 2 topics with ROS 2
/// types (rt/shapeform/agents, rt/shapeform/markers), stamped in `vehicle.frame`.
struct Ros2MirrorConfig {
  bool mirror = false;   ///< off by default: nothing is published on the rt/shapeform/ topics
  double rate_hz = 10.0; ///< publication rate of both topics
};

struct Config {
  int schema_version = kSchemaVersion;
  std::string name = "circle";  ///< scenario name (free text)
  SwarmConfig swarm;
  core::CompiledCommand command;  ///< shape, tracking, dynamics, integration; compiled by load
  SimConfig sim;
  AgentConfig agent;
  /// What each agent drives: the robot's own property, read by the agent process and the simulator,
  /// never part of the command (the wire does not carry it).
  core::VehicleParams vehicle;
  VehicleLink vehicle_link;        ///< the vehicle.* keys of the interface
  VehicleSimConfig vehicle_sim;
  SupervisorConfig supervisor;
  Ros2MirrorConfig ros2;
  dds::TransportConfig transport;  ///< filled and checked by dds::transport_problems
};

/// The config table: every key of the schema, in file order, with type, unit, range, description and
/// an accessor (defaults read from Config{}). The loader, --set, to_yaml and the key tables of
/// config/README.md are driven by it.
const std::vector<core::params::Param<Config>>& config_table();

/// Every problem found while loading or validating, one line each, e.g.
/// "dynamics.sigma: must be > 0, got -1 (line 7)". A problem longer than util::kLineMax characters
/// (it quotes much input) is shortened with util::excerpt.
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(std::vector<std::string> problems);
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  ConfigError(std::vector<std::string> bounded_problems, int);
  std::vector<std::string> problems_;
};

/// Loads a YAML file (empty path = defaults only), applies "dotted.key=value" overrides in order,
/// validates, and returns the result. Throws ConfigError naming every problem. The file must be a
/// regular file of at most kMaxFileBytes (a FIFO, a device or a directory is refused at once, without
/// reading it) holding one YAML document.
Config load(const std::string& path, const std::vector<std::string>& overrides = {});

/// Loads from YAML text (source_name is used in messages). A second YAML document is an error that
/// names its line.
Config load_string(const std::string& yaml_text, const std::vector<std::string>& overrides = {},
                   const std::string& source_name = "<string>");

/// The effective configuration as YAML (printed once at start-up by every executable).
std::string to_yaml(const Config& c);

/// Every command key of the config table (the sections shape, tracking, dynamics, integration and
/// safety, in table order) with the command's value spelled as `--set` takes it ("shape.r0" -> "1.5",
/// "shape.centre" -> "[0.0, 2.0]"), so that load("", {"key=value", ...}) rebuilds exactly this command.
/// What a recording's commands.csv holds (docs/RECORDING.md).
std::vector<std::pair<std::string, std::string>> command_settings(const core::Command& c);

/// The markdown key table of one top-level section ("" = the top-level keys, "swarm", ...,
/// "supervisor" with supervisor.converge): key, type, unit, default, range, description.
/// Throws std::invalid_argument for a section without keys.
std::string markdown_table(const std::string& section);

/// `text` (config/README.md) with the body of every block between
/// "<!-- BEGIN GENERATED keys: SECTION -->" and "<!-- END GENERATED -->" replaced by
/// markdown_table(SECTION) ("top" names the top-level keys). Everything else is kept as it is.
/// Throws std::invalid_argument for an unknown section or an unterminated block.
std::string regenerate_doc(const std::string& text);

/// config/default.yaml: every key of the config table with its default, as to_yaml writes it, and a
/// comment with its description, unit and range. It loads back to exactly Config{}.
std::string default_yaml();

}  // namespace shapeform::config
