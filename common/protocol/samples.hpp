#pragma once
/// What the messages carry, as plain structs the pure code (agent logic, supervisor monitor) takes:
/// dds::to_msg / dds::from_msg (dds/convert.hpp) convert each both ways. No Fast DDS here.
/// ShapeCommand <-> core::Command and SwarmMetrics <-> core::Metrics need no struct of their own.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "core/compiled_command.hpp"
#include "core/types.hpp"
#include "util/rate_loop.hpp"
#include "util/stats.hpp"

namespace shapeform::dds {

/// Who wrote a sample: the GUID prefix of the writer's participant (12 bytes, unique per participant
/// for its lifetime). Orders and compares bytewise; all zeros = unknown.
struct SourceId {
  std::array<std::uint8_t, 12> prefix{};
  bool known() const {
    for (const auto b : prefix)
      if (b != 0) return true;
    return false;
  }
  // Compared for every state received (its command's issuer): two loads a side, no call to memcmp.
  friend bool operator==(const SourceId& a, const SourceId& b) {
    std::uint64_t a8 = 0, b8 = 0;
    std::uint32_t a4 = 0, b4 = 0;
    std::memcpy(&a8, a.prefix.data(), 8);
    std::memcpy(&b8, b.prefix.data(), 8);
    std::memcpy(&a4, a.prefix.data() + 8, 4);
    std::memcpy(&b4, b.prefix.data() + 8, 4);
    return a8 == b8 && a4 == b4;
  }
  friend bool operator!=(const SourceId& a, const SourceId& b) { return !(a == b); }
  friend bool operator<(const SourceId& a, const SourceId& b) { return a.prefix < b.prefix; }
};

/// As Fast DDS prints a GUID prefix: 12 lower-case hex bytes separated by dots ("01.0f.2a...").
inline std::string to_string(const SourceId& s) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(35);
  for (std::size_t i = 0; i < s.prefix.size(); ++i) {
    if (i > 0) out += '.';
    out += kHex[s.prefix[i] >> 4];
    out += kHex[s.prefix[i] & 0xf];
  }
  return out;
}

/// Which command: its epoch and its issuer, the participant that published it first (a re-offered copy
/// keeps both). Commands are totally ordered by (epoch, issuer bytewise), so every receiver that sees
/// the same two commands follows the same one, even when two commanders publish one epoch at once.
/// Epochs are 64-bit: a counter that steps by one per command never wraps. epoch 0 = no command.
struct CommandId {
  std::uint64_t epoch = 0;
  SourceId issuer;
  CommandId() = default;
  /// An epoch of an unknown (all-zero) issuer: what a bare epoch number names.
  CommandId(std::uint64_t e, SourceId i = {}) : epoch(e), issuer(i) {}  // NOLINT: implicit on purpose
  bool none() const { return epoch == 0; }
  friend bool operator==(const CommandId& a, const CommandId& b) { return a.epoch == b.epoch && a.issuer == b.issuer; }
  friend bool operator!=(const CommandId& a, const CommandId& b) { return !(a == b); }
  friend bool operator<(const CommandId& a, const CommandId& b) {
    return a.epoch != b.epoch ? a.epoch < b.epoch : a.issuer < b.issuer;
  }
  friend bool operator>(const CommandId& a, const CommandId& b) { return b < a; }
};

/// A received ShapeCommand: the compiled command, which one it is, and who issued it (in words, as
/// the issuer announced itself; at most kIssuerNameMax printable characters, empty when unknown).
struct CommandSample {
  core::CompiledCommand command;
  CommandId id;
  std::string issuer_name;
};
inline constexpr std::size_t kIssuerNameMax = 120;

/// "NAME [GUID prefix]", or the GUID prefix alone when the issuer gave no name.
inline std::string describe_issuer(const std::string& name, const SourceId& issuer) {
  return name.empty() ? to_string(issuer) : name + " [" + to_string(issuer) + "]";
}

/// Largest |x|, |y| and speed accepted in a received AgentState or TrackingTarget (and as an agent's
/// start): beyond it a sample is absurd and refused.
inline constexpr double kStateLimit = 1e6;

/// Largest agent id: ids are 0..kMaxAgentId, unique in the swarm. A received sample with another id
/// is refused (and counted) like any absurd value, so a rogue publisher cannot add agents that way.
inline constexpr std::int32_t kMaxAgentId = 9999;

/// Most states one AgentStateBatch may carry (shapeform_agent_group hosts at most this many agents;
/// agent.batch_max_states cuts them into samples of fewer).
inline constexpr std::size_t kMaxBatchStates = 1000;

/// States per AgentStateBatch sample that keep it in one UDP datagram: about 128 bytes of CDR each,
/// 500 x 128 = 64,000 bytes plus the RTPS headers, under Fast DDS's 65,500-byte message (the
/// default of agent.batch_max_states; more is fragmented).
inline constexpr std::size_t kBatchStatesPerDatagram = 500;

/// Statuses per AgentStatusBatch sample that keep it in one UDP datagram: 232 bytes of CDR each,
/// 250 x 232 = 58,000 bytes plus the RTPS headers. A process hosting more publishes several samples per
/// status period, cut by dds::batch_ranges; one batch carries at most kMaxBatchStates statuses.
inline constexpr std::size_t kBatchStatusesPerDatagram = 250;

/// Largest model time accepted in a received AgentState (model time is >= 0: it starts at 0 when a
/// command is adopted). 1e9 lasts 28 hours at the extreme integration.dt 10 and 1 kHz, and years at
/// any configured pace; beyond it a sample is absurd.
inline constexpr double kModelTimeLimit = 1e9;

/// AgentState: one agent's state after a step (see idl/AgentState.idl).
struct StateSample {
  std::int32_t id = 0;
  std::uint64_t seq = 0;       ///< +1 per publication
  std::int64_t stamp_ns = 0;   ///< sender's steady clock at publication, ns
  CommandId command;           ///< the command followed (epoch 0: none yet)
  double model_time = 0.0;     ///< after the step
  core::Vec2 x = core::Vec2::Zero();
  core::Vec2 v = core::Vec2::Zero();  ///< velocity over the last step
  std::optional<double> arc;          ///< arc length along the followed shape, when the sender shares it
  core::Vec2 prev_x = core::Vec2::Zero();  ///< the state one step earlier
  std::optional<double> prev_arc;          ///< travels only with arc (nullopt when arc is)
};

/// TrackingTarget: the tracked centre C and its velocity at the supervisor's model time.
struct TargetSample {
  CommandId command;  ///< the command whose path this is
  double model_time = 0.0;
  core::Vec2 centre = core::Vec2::Zero();
  core::Vec2 velocity = core::Vec2::Zero();
  std::int64_t stamp_ns = 0;  ///< supervisor's steady clock at publication, ns
};

/// How an agent's vehicle is (AgentStatus.vehicle).
enum class VehicleHealth : std::uint8_t {
  Internal = 0,  ///< integrated by the agent itself (vehicle.interface internal)
  Driving = 1,   ///< a robot over ROS 2, its pose fresh
  NoPose = 2,    ///< a robot whose first pose has not come yet
  PoseLost = 3,  ///< a robot whose pose is older than vehicle.pose_timeout_s: commanding zero
};
/// "internal", "driving", "no_pose", "pose_lost".
inline const char* to_string(VehicleHealth h) {
  switch (h) {
    case VehicleHealth::Internal: return "internal";
    case VehicleHealth::Driving: return "driving";
    case VehicleHealth::NoPose: return "no_pose";
    case VehicleHealth::PoseLost: return "pose_lost";
  }
  return "?";
}

/// AgentStatus: an agent's health (see idl/AgentStatus.idl for each field's meaning).
struct StatusSample {
  std::int32_t id = 0;
  std::int64_t stamp_ns = 0;
  std::uint64_t ticks = 0;
  std::uint64_t overruns = 0;
  double lateness_max_us = 0.0;
  double lateness_p99_us = 0.0;
  int neighbours_heard = 0;
  std::uint64_t stale_dropped = 0;
  std::uint64_t samples_rejected = 0;
  std::uint64_t samples_received = 0;
  std::uint64_t samples_lost = 0;
  double age_p50_us = -1.0;  ///< -1: no sample in the period
  double age_p99_us = -1.0;
  double cpu_percent = 0.0;
  double rss_mb = 0.0;
  std::uint64_t epoch = 0;
  VehicleHealth vehicle = VehicleHealth::Internal;
  std::uint64_t poses_refused = 0;
  std::uint64_t commands_saturated = 0;
  double control_latency_p50_us = -1.0;  ///< -1: no command in the period
  double control_latency_p99_us = -1.0;
  // The safety filter, since the command followed (agent::SafetyFigures)
  double min_gap = -1.0;  ///< -1: none
  double min_gap_time = 0.0;
  std::uint64_t filter_interventions = 0;
  std::uint64_t deadlock_sidesteps = 0;
  std::uint64_t promises_broken = 0;
  bool blocked = false;
  std::int32_t blocked_by = -1;
  bool beyond_fence = false;
  std::uint64_t fence_breaches = 0;
};

/// A velocity command to a vehicle as geometry_msgs/Twist carries it: the body frame of REP 103 (x along
/// the heading, y to its left), m/s and rad/s; only the plane's components (linear z, angular x and y
/// are sent as 0). TwistStamped adds the stamp and the frame.
struct VelocitySample {
  double vx = 0.0;
  double vy = 0.0;
  double wz = 0.0;
  std::int64_t stamp_ns = 0;  ///< TwistStamped's header.stamp, ns since the sender's clock's epoch
  std::string frame_id;       ///< TwistStamped's header.frame_id (the robot's base)
};

/// A vehicle's pose as nav_msgs/Odometry or geometry_msgs/PoseStamped carry it, in the plane.
struct PoseSample {
  core::Vec2 x = core::Vec2::Zero();  ///< pose.position (x, y), m; z is not used
  double yaw = 0.0;                   ///< rad in [-pi, pi]: the orientation's rotation about z
  std::string frame_id;               ///< header.frame_id: the frame the pose is in
  std::int64_t stamp_ns = 0;          ///< header.stamp, ns
  /// Odometry only: its twist (child_frame_id's frame, REP 103), and that frame.
  bool has_twist = false;
  double vx = 0.0;
  double vy = 0.0;
  double wz = 0.0;
  std::string child_frame_id;
};

/// Longest frame name a received pose or command may carry (longer is refused).
inline constexpr std::size_t kFrameIdMax = 256;

/// The process-wide part of a status sample, as of stamp_ns: the loop's timing, the data ages of the
/// period (ages_us is reordered), CPU and memory. The per-agent counters are the caller's to fill.
inline StatusSample process_status(std::int64_t stamp_ns, const util::LoopStats& ls, std::vector<double>& ages_us,
                                   double cpu_percent, double rss_mb) {
  StatusSample st;
  st.stamp_ns = stamp_ns;
  st.ticks = ls.ticks;
  st.overruns = ls.overruns;
  st.lateness_max_us = ls.lateness_max_us;
  st.lateness_p99_us = ls.lateness_p99_us;
  st.age_p50_us = util::percentile(ages_us, 50).value_or(-1);
  st.age_p99_us = util::percentile(ages_us, 99).value_or(-1);
  st.cpu_percent = cpu_percent;
  st.rss_mb = rss_mb;
  return st;
}

}  // namespace shapeform::dds
