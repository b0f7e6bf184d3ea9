#pragma once
/// The ROS 2 mirror's messages (docs/ROS2.md), built without DDS or clocks: the swarm as ROS 2 tools see
/// it, a geometry_msgs/PoseArray of the agents (rt/shapeform/agents) and a visualization_msgs/MarkerArray
/// (rt/shapeform/markers). The supervisor fills a MirrorScene from what it hears and publishes both.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/compiled_command.hpp"
#include "core/types.hpp"
#include "geometry_msgs/msg/PoseArray.h"
#include "visualization_msgs/msg/MarkerArray.h"

namespace shapeform::dds {

namespace ros2 {
using PoseArray = geometry_msgs::msg::dds_::PoseArray_;
using Marker = visualization_msgs::msg::dds_::Marker_;
using MarkerArray = visualization_msgs::msg::dds_::MarkerArray_;

/// visualization_msgs/Marker's constants used here (the .msg's; constants are not on the wire).
enum MarkerType : std::int32_t { kArrow = 0, kSphere = 2, kLineStrip = 4, kTextViewFacing = 9 };
enum MarkerAction : std::int32_t { kAdd = 0, kDelete = 2, kDeleteAll = 3 };
}  // namespace ros2

/// One agent as the mirror shows it.
struct MirrorAgent {
  std::int32_t id = 0;
  core::Vec2 x = core::Vec2::Zero();  ///< position, shape units (metres with vehicles), the frame's x, y
  core::Vec2 v = core::Vec2::Zero();  ///< velocity over its last step, shape units per model time
};

/// A polyline of the plane; `closed`: the last point joins the first.
struct Polyline {
  std::vector<core::Vec2> points;
  bool closed = false;
};

/// Everything the mirror publishes at one instant.
struct MirrorScene {
  std::int64_t stamp_ns = 0;         ///< header stamps: ns since the Unix epoch (ROS time = system clock)
  std::string frame_id = "map";      ///< every header's frame (vehicle.frame)
  std::vector<MirrorAgent> agents;   ///< alive agents, ascending id (build_* sort a copy otherwise)
  bool commands = false;             ///< draw each agent's velocity (agents that drive vehicles)
  std::optional<Polyline> outline;   ///< the commanded shape (core::outline)
  std::vector<Polyline> keep_out;    ///< keep-out zones (zone_outline), closed
  std::optional<Polyline> fence;     ///< the geofence polygon when the command has one, closed
  std::optional<core::Vec2> centre;  ///< the tracked centre C(t) when tracking
  double agent_diameter = 0.2;       ///< sphere diameter, shape units
  double line_width = 0.02;          ///< line strips' width, shape units
};

/// A keep-out zone as a closed polyline: a polygon's vertices, or a circle by `circle_points` points.
Polyline zone_outline(const core::KeepOutZone& z, int circle_points = 64);

/// The scene at model time t of the command in force (`cmd` null: none yet, the agents only): its outline
/// (core::outline, 240 points), keep-out zones, fence (when the command has a polygon: the workspace box
/// is not drawn), the tracked centre C(t) when tracking; spheres of diameter min_separation when it is
/// set (two agents touch at the least distance allowed), 0.2 otherwise.
MirrorScene mirror_scene(std::vector<MirrorAgent> agents, const core::CompiledCommand* cmd, double t,
                         std::int64_t stamp_ns, std::string frame_id, bool commands);

/// The scene's agents as a PoseArray: header (stamp, frame_id); one pose per agent in ascending id, the
/// position (x, y, 0) and the heading of its velocity as a rotation about z (identity when at rest). Pose
/// k is the k-th smallest id alive: the ids are the "agents" markers' ids (and their text), in the same
/// order.
void build_agents(const MirrorScene& s, ros2::PoseArray& out);

/// The scene as markers, every one stamped and framed as the scene, lifetime 0 (until replaced), in
/// this order: one DELETEALL (so agents gone and zones removed vanish), then per agent (ascending id) a
/// SPHERE "agents"/id and a TEXT_VIEW_FACING "agent_ids"/id reading the id above it; a LINE_STRIP
/// "outline"/0; one LINE_STRIP "keep_out"/k per zone; a LINE_STRIP "fence"/0; a SPHERE "centre"/0;
/// with `commands`, an ARROW "commands"/id per agent from its position to position + v (one model time
/// unit of its velocity). Closed polylines repeat their first point at the end.
void build_markers(const MirrorScene& s, ros2::MarkerArray& out);

}  // namespace shapeform::dds
