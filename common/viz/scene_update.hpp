#pragma once
/// The swarm as Foxglove's 3-D panel draws it (Foxglove, Lichtblick): a snapshot of what is drawn and
/// the messages made of it, as JSON of Foxglove's own schemas (foxglove.SceneUpdate, foxglove.PosesInFrame,
/// https://docs.foxglove.dev/docs/visualization/message-schemas), frame "shapeform", shape units as
/// metres, z = 0. Pure: no DDS, no clock, no socket; the viewer's Foxglove server streams these
/// channels and a recording can store them as they are (Channel: topic, schema, encodings).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/types.hpp"

namespace shapeform::viz {

/// The frame every message is in: the shape's plane, x1 -> x, x2 -> y, shape units as metres.
inline constexpr std::string_view kFrameId = "shapeform";

/// One channel of Foxglove / MCAP: what a recording's Channel and Schema records and a Foxglove
/// server's advertise need.
struct Channel {
  std::string topic;             ///< "shapeform/scene"
  std::string schema_name;       ///< "foxglove.SceneUpdate"
  std::string schema_encoding;   ///< "jsonschema"
  std::string_view schema;       ///< the JSON Schema text
  std::string message_encoding;  ///< "json"
};

/// The channels of the scene, by index: kSceneChannel (foxglove.SceneUpdate), kPosesChannel
/// (foxglove.PosesInFrame: one pose per agent, what a team's own tools expect of "where is everyone").
const std::vector<Channel>& scene_channels();
inline constexpr std::size_t kSceneChannel = 0;
inline constexpr std::size_t kPosesChannel = 1;

enum class AgentLook { Alive, Stale, Dead };

struct AgentDraw {
  std::int32_t id = 0;
  core::Vec2 x = core::Vec2::Zero();  ///< shape units
  AgentLook look = AgentLook::Alive;
  std::optional<double> heading;  ///< rad, counter-clockwise from x1; nullopt: unknown (no arrow)
};

/// What is drawn at one instant.
struct SceneSnapshot {
  std::vector<AgentDraw> agents;
  std::vector<core::Vec2> outline;  ///< the commanded shape's points (empty: no command)
  bool outline_closed = false;
  std::vector<core::KeepOutZone> keep_out;  ///< the command's keep-out zones
  std::vector<core::Vec2> fence;     ///< the geofence polygon (convex, either orientation; empty: none drawn)
  double fence_margin = 0.0;         ///< shape units; > 0 draws the fence shrunk by it too
  std::optional<core::Vec2> centre;  ///< the tracked centre C(t)
};

/// Sizes of the drawing, shape units (metres in Foxglove).
struct SceneStyle {
  double agent_diameter = 0.12;
  double arrow_length = 0.2;
  double centre_diameter = 0.2;
  double line_width_px = 2.0;  ///< lines are scale-invariant (pixels)
  int circle_segments = 48;    ///< a keep-out circle is drawn as a closed line of this many points
};

/// Entity ids of the SceneUpdate; every one is sent in every message (empty when nothing to draw), so
/// each message replaces the last and nothing lingers.
inline constexpr std::string_view kEntities[] = {"agents",   "headings", "outline",
                                                 "keep_out", "fence",    "centre"};

/// RGBA of an agent's sphere: alive green, stale amber, dead grey (translucent).
struct Rgba {
  double r, g, b, a;
};
Rgba agent_colour(AgentLook look);

/// The foxglove.SceneUpdate of s at stamp_ns (ns, the entities' timestamp), as JSON text: entity "agents"
/// one sphere per agent coloured by its look; "headings" one arrow per agent whose heading is known;
/// "outline" one line (a loop when closed); "keep_out" a loop per zone; "fence" the fence's loop and,
/// with a margin, the shrunk one; "centre" a sphere. Non-finite numbers are written as 0.
std::string scene_update_json(const SceneSnapshot& s, std::uint64_t stamp_ns, const SceneStyle& style = {});

/// The foxglove.PosesInFrame of the agents (in s.agents' order; orientation from the heading, identity
/// when unknown), as JSON text.
std::string poses_json(const SceneSnapshot& s, std::uint64_t stamp_ns);

}  // namespace shapeform::viz
