/// The config table: every key of the schema with its type, unit, range and description, in the
/// order of the file (and of to_yaml and config/README.md). The command's keys come from the command
/// table (core/command_table.hpp), the transport's from the transport table (protocol/transport.hpp); the rest
/// are declared here. Defaults are read from Config{}.
#include "config/config.hpp"

#include "core/command_table.hpp"
#include "core/enum_names.hpp"
#include "protocol/samples.hpp"

namespace shapeform::config {
namespace {

namespace params = core::params;
using params::Type;
using P = params::Param<Config>;

/// Upper bound of every rate key, Hz: the fastest loop in use (the 1 kHz agents of the benchmarks).
/// No loop of the project does useful work faster; an unbounded rate would spin a core.
constexpr double kMaxRateHz = 1000.0;

constexpr params::Name<VehicleLink::Interface> kInterfaceNames[] = {{VehicleLink::Interface::Internal, "internal"},
                                                                    {VehicleLink::Interface::Ros2, "ros2"}};
constexpr params::Name<VehicleLink::CmdType> kCmdTypeNames[] = {{VehicleLink::CmdType::Twist, "twist"},
                                                                {VehicleLink::CmdType::TwistStamped, "twist_stamped"}};
constexpr params::Name<VehicleLink::PoseType> kPoseTypeNames[] = {
    {VehicleLink::PoseType::Odometry, "odometry"}, {VehicleLink::PoseType::PoseStamped, "pose_stamped"}};

/// agent.sync spellings.
constexpr params::Name<bool> kSyncNames[] = {{false, "free"}, {true, "lockstep"}};

template <class V, class Field>
P param(Type type, std::string key, std::string unit, params::Range range, std::string doc, Field field,
        std::string range_note = "") {
  return params::make<Config, V>(type, std::move(key), std::move(unit), range, std::move(doc), field,
                                 std::move(range_note));
}

template <class Field>
P real(std::string key, std::string unit, params::Range range, std::string doc, Field field) {
  return param<double>(Type::Real, std::move(key), std::move(unit), range, std::move(doc), field);
}

/// An angle key: written in degrees, stored in radians.
template <class Field>
P angle(std::string key, params::Range range, std::string doc, Field field) {
  P p = real(std::move(key), "degrees", range, std::move(doc), field);
  p.degrees = true;
  return p;
}

/// A text key with the rule it must follow (checked by the loader: check_vehicle in config.cpp).
template <class Field>
P text(std::string key, std::string doc, Field field, std::string rule) {
  return param<std::string>(Type::Text, std::move(key), "", {}, std::move(doc), field, std::move(rule));
}

/// The vehicle section's interface keys (docs/ROBOTS.md): how an agent reaches its vehicle.
void add_vehicle_link(std::vector<P>& t) {
  t.push_back(params::make_choice<Config>(
      "vehicle.interface",
      "`internal` = the agent integrates its vehicle model itself (today's behaviour); `ros2` = it drives a "
      "robot over ROS 2's topics: reads the robot's pose, publishes a velocity command every tick, integrates "
      "nothing (needs `vehicle.max_speed` > 0)",
      kInterfaceNames, [](auto& c) -> auto& { return c.vehicle_link.interface; }));
  t.push_back(text(
      "vehicle.namespace", "ros2: the robot's namespace; `{id}` is replaced by the agent's id",
      [](auto& c) -> auto& { return c.vehicle_link.ns; },
      "letters, digits, `_` and `/`, with `{id}` (each agent drives its own robot)"));
  t.push_back(text(
      "vehicle.cmd_topic", "ros2: the command topic, in the namespace (`/name`: absolute; `{id}`: the agent's id)",
      [](auto& c) -> auto& { return c.vehicle_link.cmd_topic; }, "letters, digits, `_` and `/`"));
  t.push_back(params::make_choice<Config>(
      "vehicle.cmd_type",
      "ros2: `twist` = geometry_msgs/Twist (most drivers); `twist_stamped` = geometry_msgs/TwistStamped (ROS 2 "
      "Jazzy's diff_drive_controller)",
      kCmdTypeNames, [](auto& c) -> auto& { return c.vehicle_link.cmd_type; }));
  t.push_back(text(
      "vehicle.pose_topic",
      "ros2: the pose topic, in the namespace (`/name`: absolute, e.g. `/vrpn_mocap/robot_{id}/pose`; `{id}`: the "
      "agent's id)",
      [](auto& c) -> auto& { return c.vehicle_link.pose_topic; }, "letters, digits, `_` and `/`"));
  t.push_back(params::make_choice<Config>(
      "vehicle.pose_type",
      "ros2: `odometry` = nav_msgs/Odometry (a driver's odom, localised into the swarm's frame); "
      "`pose_stamped` = geometry_msgs/PoseStamped (motion capture, localisation)",
      kPoseTypeNames, [](auto& c) -> auto& { return c.vehicle_link.pose_type; }));
  t.push_back(text(
      "vehicle.frame",
      "ros2: the frame every pose must be in (header.frame_id), one shared by the swarm (`map`, the motion "
      "capture's world); a pose in another frame is refused",
      [](auto& c) -> auto& { return c.vehicle_link.frame; }, "not empty"));
  t.push_back(real(
      "vehicle.pose_timeout_s", "s", params::Range{0, true, 10, false, false},
      "ros2: a pose older than this makes the agent command zero velocity at once (and say so) until poses "
      "return",
      [](auto& c) -> auto& { return c.vehicle_link.pose_timeout_s; }));
  t.push_back(real(
      "vehicle.pose_jump_m", "m", params::at_least(0),
      "ros2: a pose further than `max_speed` x (time since the last) + this from the last accepted one is "
      "refused and counted (noise, a relocalisation, a wrong robot)",
      [](auto& c) -> auto& { return c.vehicle_link.pose_jump_m; }));
  t.push_back(real(
      "vehicle_sim.pose_rate_hz", "Hz", params::above_up_to(0, kMaxRateHz),
      "shapeform_vehicle: pose publication and integration rate",
      [](auto& c) -> auto& { return c.vehicle_sim.pose_rate_hz; }));
  t.push_back(real(
      "vehicle_sim.response_s", "s", params::Range{0, false, 10, false, false},
      "shapeform_vehicle: first-order lag of the wheels (0: a command is taken at once)",
      [](auto& c) -> auto& { return c.vehicle_sim.response_s; }));
  t.push_back(real(
      "vehicle_sim.pose_noise_m", "m", params::Range{0, false, 1, false, false},
      "shapeform_vehicle: standard deviation of the Gaussian noise on each published position",
      [](auto& c) -> auto& { return c.vehicle_sim.pose_noise_m; }));
  t.push_back(real(
      "vehicle_sim.command_timeout_s", "s", params::Range{0, true, 10, false, false},
      "shapeform_vehicle: watchdog; a vehicle whose last command is older than this stops",
      [](auto& c) -> auto& { return c.vehicle_sim.command_timeout_s; }));
  t.push_back(text(
      "vehicle_sim.child_frame", "shapeform_vehicle: Odometry's child_frame_id, after the namespace",
      [](auto& c) -> auto& { return c.vehicle_sim.child_frame; }, "not empty"));
}

/// The vehicle section (core/vehicle.hpp, docs/VEHICLES.md): the robot each agent drives.
void add_vehicle(std::vector<P>& t) {
  t.push_back(params::make_choice<Config>(
      "vehicle.model",
      "what each agent drives: `integrator` = the point moves as the law steps it (the paper's model); "
      "`double_integrator` = a point mass whose velocity follows the law's, acceleration at most "
      "`vehicle.max_accel`; `unicycle` = a differential drive (forward speed, yaw rate) steered through the "
      "point `vehicle.offset` ahead of its axle, which is the position it publishes. Not on the wire: the "
      "robot's own",
      params::kVehicleModelNames, [](auto& c) -> auto& { return c.vehicle.model; }));
  t.push_back(params::make_choice<Config>(
      "vehicle.steering",
      "unicycle: `exact` = the forward speed and yaw rate held over a step whose arc carries the point exactly "
      "along the law's step (cut short along it when a limit binds); `linearised` = the classic feedback "
      "linearisation `[v; offset w] = R(-heading) u`, both scaled by one factor when a limit binds",
      params::kSteeringNames, [](auto& c) -> auto& { return c.vehicle.steering; }));
  t.push_back(real(
      "vehicle.max_speed", "m/s", params::at_least(0),
      "speed limit (0 = none): the point's speed (integrator, double integrator), the forward speed of the "
      "axle (unicycle)",
      [](auto& c) -> auto& { return c.vehicle.max_speed; }));
  t.push_back(real(
      "vehicle.max_yaw_rate", "rad/s", params::at_least(0), "unicycle: yaw rate limit (0 = none)",
      [](auto& c) -> auto& { return c.vehicle.max_yaw_rate; }));
  t.push_back(real(
      "vehicle.max_accel", "m/s^2", params::at_least(0),
      "double integrator: acceleration limit (0 = none; the unicycle is kinematic)",
      [](auto& c) -> auto& { return c.vehicle.max_accel; }));
  t.push_back(real(
      "vehicle.offset", "m", params::above(0),
      "unicycle: distance of the controlled (published) point ahead of the axle; the axle stays this far "
      "from where the law puts the point",
      [](auto& c) -> auto& { return c.vehicle.offset; }));
  t.push_back(real(
      "vehicle.seconds_per_model_time", "s", params::above(0),
      "seconds of the vehicle's time per unit of the law's model time: a step of `integration.dt` lasts "
      "`dt` times this, the law's velocity in shape units (m) per model time is this many times the "
      "vehicle's in m/s, and the limits apply to the latter",
      [](auto& c) -> auto& { return c.vehicle.seconds_per_model_time; }));
  t.push_back(angle(
      "vehicle.initial_heading_deg", params::any(),
      "every vehicle's heading at the start, counter-clockwise from the x1 axis (before the spread)",
      [](auto& c) -> auto& { return c.vehicle.initial_heading; }));
  t.push_back(angle(
      "vehicle.heading_spread_deg", params::Range{0, false, 180, false, false},
      "start headings uniform in `initial_heading_deg` +- this, drawn per agent from (`swarm.seed`, id) "
      "alone (180: any heading; the positions' draw is unchanged)",
      [](auto& c) -> auto& { return c.vehicle.heading_spread; }));
  add_vehicle_link(t);
}

std::vector<P> build() {
  std::vector<P> t;
  t.push_back(param<long long>(
      Type::Integer, "schema_version", "", params::integers(kSchemaVersion, kSchemaVersion),
      "version of this schema", [](auto& c) -> auto& { return c.schema_version; }));
  t.push_back(param<std::string>(
      Type::Text, "name", "", {}, "scenario name, free text", [](auto& c) -> auto& { return c.name; },
      "any string"));
  t.push_back(param<long long>(
      Type::Integer, "swarm.agents", "agents", params::integers(1, dds::kMaxAgentId + 1),
      "swarm size (at most one agent per id 0..9999)",
      [](auto& c) -> auto& { return c.swarm.agents; }));
  t.push_back(param<std::uint64_t>(
      Type::UInt64, "swarm.seed", "", {}, "seed of the uniform random start",
      [](auto& c) -> auto& { return c.swarm.seed; }));
  t.push_back(real(
      "swarm.init_half_width", "shape units", params::above(0), "agents start uniform in `[-w, w]^2`",
      [](auto& c) -> auto& { return c.swarm.init_half_width; }));
  for (const auto& p : params::command_table())
    t.push_back(params::lift<Config>(
        p, [](auto& c) -> auto& { return c.command; }));
  t.push_back(param<long long>(
      Type::Integer, "sim.steps", "steps", params::integers(0, 10'000'000), "number of integration steps",
      [](auto& c) -> auto& { return c.sim.steps; }));
  t.push_back(real(
      "agent.rate_hz", "Hz", params::above_up_to(0, kMaxRateHz),
      "control loop rate (at most 1 kHz: the benchmarks' fastest loop; a faster one would spin a core on "
      "its overruns)",
      [](auto& c) -> auto& { return c.agent.rate_hz; }));
  t.push_back(real(
      "agent.neighbour_timeout_periods", "periods", params::at_least(1),
      "drop a neighbour unheard for this many loop periods (a clean exit drops it at once, a participant "
      "lost to DDS after `transport.lease_s` at the latest). Lost samples alone must not: a pair losing a fraction q of its exchanges drops each other on "
      "(1 - q) q^k of its ticks; the default 40 keeps that below 1e-8 at q = 0.64 (40 % loss on both hosts) "
      "and keeps a silent agent 0.8 s at 50 Hz",
      [](auto& c) -> auto& { return c.agent.neighbour_timeout_periods; }));
  t.push_back(real(
      "agent.status_rate_hz", "Hz", params::above_up_to(0, kMaxRateHz),
      "agent status publication rate (once per loop tick at most, so at most `agent.rate_hz`)",
      [](auto& c) -> auto& { return c.agent.status_rate_hz; }));
  t.push_back(real(
      "agent.identity_grace_s", "s", params::Range{0, false, 10, false, false},
      "listening time before an agent's first publication: hearing its id from another participant "
      "meanwhile, it refuses to run (exit 2). Longer than discovery takes (well under 1 s on one host) and "
      "than the slowest neighbour's period; 0: no listening (two processes with one id then settle by "
      "their GUID prefixes, the higher exits)",
      [](auto& c) -> auto& { return c.agent.identity_grace_s; }));
  {
    P sync;
    sync.key = "agent.sync";
    sync.type = Type::Choice;
    sync.doc =
        "`free`: each agent steps on its own clock with the newest neighbour states (asynchronous, like real "
        "vehicles); `lockstep`: step k+1 waits until every neighbour on the same command has published step "
        "k and "
        "uses exactly those states, which is the simulator's synchronous update, so agent processes compute "
        "the "
        "simulator's numbers. An agent waits at most 5 s for a neighbour that is alive but does not advance, "
        "then "
        "runs free until it catches up. Tracking: free-running agents follow the supervisor's "
        "`TrackingTarget` "
        "(centre and velocity, extrapolated between samples; after 1 s without one, the command's own path "
        "on the "
        "agent's clock); in lockstep every agent computes C(t) from the command's path at its own step, as "
        "the "
        "simulator does. With feed-forward (`tracking.feedforward`) and a moving centre, a neighbour's state "
        "one step older or newer than the agent's own is seen where it would be at the agent's model time "
        "(moved by dC/dt per step), so the formation is the static one in the centre's frame";
    params::bind_choice(
        sync, kSyncNames, [](auto& c) -> auto& { return c.agent.lockstep; });
    t.push_back(std::move(sync));
  }
  t.push_back(param<bool>(
      Type::Bool, "agent.batch_state", "", {},
      "a process hosting several agents (`shapeform_agent_group`) publishes their states as one sample per "
      "tick on `shapeform/state_batch` (one AgentStateBatch carrying every hosted agent) instead of one "
      "AgentState per agent on `shapeform/state`: P processes put P samples per tick on the wire instead of N. "
      "A batch of 100 agents is about 13 KB; more than `agent.batch_max_states` agents go in several samples. "
      "Their statuses go the same way: one AgentStatusBatch per status period on `shapeform/status_batch` (250 "
      "agents at most per sample) instead of one AgentStatus per agent on `shapeform/status`. One-agent "
      "processes always publish `shapeform/state` and `shapeform/status`; every reader reads both topics of each",
      [](auto& c) -> auto& { return c.agent.batch_state; }));
  t.push_back(param<long long>(
      Type::Integer, "agent.batch_max_states", "states",
      params::integers(1, static_cast<long long>(dds::kMaxBatchStates)),
      "most agent states in one AgentStateBatch sample: a process hosting more publishes several per tick, "
      "each its own instance (keyed by its first id), cut into parts of nearly equal size. The default, "
      "500 states of about 128 bytes, keeps each sample in one UDP datagram; more is fragmented by Fast DDS, "
      "and best effort then loses the whole sample with any fragment (docs/BENCHMARKS.md, lever 17)",
      [](auto& c) -> auto& { return c.agent.batch_max_states; }));
  t.push_back(real(
      "agent.idle_rate_hz", "Hz", params::above_up_to(0, kMaxRateHz),
      "state publication rate before the agent's first command, at most `agent.rate_hz` (the default: the "
      "loop rate); until then a neighbour "
      "is dropped after `agent.neighbour_timeout_periods` periods of this rate. A large swarm's discovery then "
      "runs on a nearly idle host instead of beside N x (N - 1) x `agent.rate_hz` state deliveries, and the "
      "supervisor still sees every agent hear the others before it commands (`wait agents`). The launcher "
      "sets it from `config/large_swarm.sets`' size on",
      [](auto& c) -> auto& { return c.agent.idle_rate_hz; }));
  t.push_back(param<bool>(
      Type::Bool, "agent.leave_by_lease", "", {},
      "on a clean stop, dispose the agents' states and delete the endpoints (peers hear both at once) but "
      "send no participant goodbye: peers forget the participant when `transport.lease_s` ends. Fast DDS "
      "2.9 aborts a peer now and then when it processes a goodbye while that participant's lease timer "
      "fires (an assert in PDP.cpp), which a large swarm stopping at once makes likely (docs/BENCHMARKS.md, "
      "lever 11). The launcher sets it from `config/large_swarm.sets`' size on",
      [](auto& c) -> auto& { return c.agent.leave_by_lease; }));
  add_vehicle(t);
  t.push_back(real(
      "supervisor.metrics_rate_hz", "Hz", params::above_up_to(0, kMaxRateHz),
      "metrics computation / publication / recording rate (computed every round(target_rate_hz / "
      "metrics_rate_hz) ticks of the target loop, so at most `target_rate_hz`)",
      [](auto& c) -> auto& { return c.supervisor.metrics_rate_hz; }));
  t.push_back(real(
      "supervisor.target_rate_hz", "Hz", params::above_up_to(0, kMaxRateHz),
      "tracking target publication rate, the supervisor's loop rate (at most 1 kHz, the fastest agent loop: "
      "a faster one would only spin a core)",
      [](auto& c) -> auto& { return c.supervisor.target_rate_hz; }));
  t.push_back(real(
      "supervisor.agent_timeout_s", "s", params::above(0),
      "an agent unheard this long is shown dead (at least 3 periods of `agent.rate_hz`)",
      [](auto& c) -> auto& { return c.supervisor.agent_timeout_s; }));
  t.push_back(real(
      "supervisor.flush_s", "s", params::above(0), "recorder flush period",
      [](auto& c) -> auto& { return c.supervisor.flush_s; }));
  t.push_back(real(
      "supervisor.converge.band_abs", "shape units", params::at_least(0), "shape error band, absolute",
      [](auto& c) -> auto& { return c.supervisor.converge.band_abs; }));
  t.push_back(real(
      "supervisor.converge.band_rel", "", params::at_least(0), "shape error band, relative to its mean",
      [](auto& c) -> auto& { return c.supervisor.converge.band_rel; }));
  t.push_back(real(
      "supervisor.converge.gap_cv_max", "", params::above(0), "largest coefficient of variation of the gaps",
      [](auto& c) -> auto& { return c.supervisor.converge.gap_cv_max; }));
  t.push_back(real(
      "supervisor.converge.hold", "model time", params::at_least(0), "time the conditions must hold",
      [](auto& c) -> auto& { return c.supervisor.converge.hold; }));
  t.push_back(real(
      "supervisor.converge.on_shape_rel", "", params::at_least(0),
      "on the shape: mean shape error <= this times the shape's size (scale x r0, max(a, b), a, ...)",
      [](auto& c) -> auto& { return c.supervisor.converge.on_shape_rel; }));
  t.push_back(real(
      "supervisor.converge.on_shape_abs", "shape units", params::at_least(0),
      "on the shape: ... or this many shape units, whichever is larger",
      [](auto& c) -> auto& { return c.supervisor.converge.on_shape_abs; }));
  t.push_back(param<bool>(
      Type::Bool, "ros2.mirror", "", {},
      "the supervisor republishes the swarm for ROS 2 tools (`ros2 topic echo`, rviz2; docs/ROS2.md): every alive "
      "agent's pose on `rt/shapeform/agents` (geometry_msgs/PoseArray, ascending id) and markers on "
      "`rt/shapeform/markers` (visualization_msgs/MarkerArray: agents with their ids, the commanded outline, "
      "keep-out zones, fence, tracked centre, and with `vehicle.interface: ros2` each agent's velocity), in the "
      "frame `vehicle.frame`. Off: nothing is published on them",
      [](auto& c) -> auto& { return c.ros2.mirror; }));
  t.push_back(real(
      "ros2.rate_hz", "Hz", params::above_up_to(0, kMaxRateHz),
      "publication rate of the ROS 2 mirror's topics (at most `supervisor.target_rate_hz`: one per tick of its loop)",
      [](auto& c) -> auto& { return c.ros2.rate_hz; }));
  for (const auto& p : dds::transport_table())
    t.push_back(params::lift<Config>(
        p, [](auto& c) -> auto& { return c.transport; }));
  return t;
}

}  // namespace

const std::vector<core::params::Param<Config>>& config_table() {
  static const std::vector<P> table = build();
  return table;
}

}  // namespace shapeform::config
