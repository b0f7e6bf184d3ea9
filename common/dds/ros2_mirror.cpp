#include "dds/ros2_mirror.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "dds/convert_ros2.hpp"

namespace shapeform::dds {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<MirrorAgent> sorted(const std::vector<MirrorAgent>& agents) {
  std::vector<MirrorAgent> out = agents;
  std::stable_sort(out.begin(), out.end(),
                   [](const MirrorAgent& a, const MirrorAgent& b) { return a.id < b.id; });
  return out;
}

geometry_msgs::msg::dds_::Point_ point(const core::Vec2& x, double z = 0.0) {
  geometry_msgs::msg::dds_::Point_ p;
  p.x(x.x());
  p.y(x.y());
  p.z(z);
  return p;
}

std_msgs::msg::dds_::ColorRGBA_ colour(float r, float g, float b, float a = 1.0f) {
  std_msgs::msg::dds_::ColorRGBA_ c;
  c.r(r);
  c.g(g);
  c.b(b);
  c.a(a);
  return c;
}

/// A marker with the scene's header, identity orientation, lifetime 0.
ros2::Marker marker(const MirrorScene& s, const char* ns, std::int32_t id, std::int32_t type) {
  ros2::Marker m;
  m.header(header_msg(s.stamp_ns, s.frame_id));
  m.ns(ns);
  m.id(id);
  m.type(type);
  m.action(ros2::kAdd);
  m.pose().orientation().w(1.0);
  return m;
}

ros2::Marker line_strip(const MirrorScene& s, const char* ns, std::int32_t id, const Polyline& line,
                        const std_msgs::msg::dds_::ColorRGBA_& c) {
  ros2::Marker m = marker(s, ns, id, ros2::kLineStrip);
  m.scale().x(s.line_width);  // LINE_STRIP: scale.x is the width
  m.color(c);
  for (const core::Vec2& p : line.points) m.points().push_back(point(p));
  if (line.closed && line.points.size() > 1) m.points().push_back(point(line.points.front()));
  return m;
}

}  // namespace

Polyline zone_outline(const core::KeepOutZone& z, int circle_points) {
  Polyline out;
  out.closed = true;
  if (z.kind == core::KeepOutZone::Kind::Polygon) {
    out.points = z.vertices;
    return out;
  }
  const int n = std::max(circle_points, 3);
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * kPi * k / n;
    out.points.push_back(z.centre + z.radius * core::Vec2(std::cos(a), std::sin(a)));
  }
  return out;
}

MirrorScene mirror_scene(std::vector<MirrorAgent> agents, const core::CompiledCommand* cmd, double t,
                         std::int64_t stamp_ns, std::string frame_id, bool commands) {
  MirrorScene s;
  s.stamp_ns = stamp_ns;
  s.frame_id = std::move(frame_id);
  s.agents = std::move(agents);
  s.commands = commands;
  if (!cmd) return s;
  Polyline outline;
  outline.points = core::outline(*cmd, t, outline.closed);
  s.outline = std::move(outline);
  for (const core::KeepOutZone& z : cmd->keep_out) s.keep_out.push_back(zone_outline(z));
  if (!cmd->fence.empty()) s.fence = Polyline{cmd->fence, true};
  if (cmd->tracking.enabled) s.centre = core::centre_at(cmd->tracking.path, t);
  if (cmd->min_separation > 0) s.agent_diameter = cmd->min_separation;
  return s;
}

void build_agents(const MirrorScene& s, ros2::PoseArray& out) {
  out.header(header_msg(s.stamp_ns, s.frame_id));
  out.poses().clear();
  for (const MirrorAgent& a : sorted(s.agents)) {
    geometry_msgs::msg::dds_::Pose_ p;
    p.position(point(a.x));
    const double yaw = a.v.squaredNorm() > 0.0 ? std::atan2(a.v.y(), a.v.x()) : 0.0;
    p.orientation().z(std::sin(yaw / 2.0));
    p.orientation().w(std::cos(yaw / 2.0));
    out.poses().push_back(p);
  }
}

void build_markers(const MirrorScene& s, ros2::MarkerArray& out) {
  auto& ms = out.markers();
  ms.clear();
  ros2::Marker clear = marker(s, "", 0, ros2::kSphere);
  clear.action(ros2::kDeleteAll);
  ms.push_back(clear);
  const std::vector<MirrorAgent> agents = sorted(s.agents);
  for (const MirrorAgent& a : agents) {
    ros2::Marker m = marker(s, "agents", a.id, ros2::kSphere);
    m.pose().position(point(a.x));
    m.scale().x(s.agent_diameter);
    m.scale().y(s.agent_diameter);
    m.scale().z(s.agent_diameter);
    m.color(colour(0.2f, 0.5f, 1.0f));
    ms.push_back(m);
    ros2::Marker t = marker(s, "agent_ids", a.id, ros2::kTextViewFacing);
    t.pose().position(point(a.x, s.agent_diameter));  // above the sphere
    t.scale().z(s.agent_diameter);                    // TEXT_VIEW_FACING: scale.z is the height of a capital
    t.color(colour(1.0f, 1.0f, 1.0f));
    t.text(std::to_string(a.id));
    ms.push_back(t);
  }
  if (s.outline) ms.push_back(line_strip(s, "outline", 0, *s.outline, colour(0.2f, 0.9f, 0.3f)));
  for (std::size_t k = 0; k < s.keep_out.size(); ++k)
    ms.push_back(
        line_strip(s, "keep_out", static_cast<std::int32_t>(k), s.keep_out[k], colour(1.0f, 0.2f, 0.2f)));
  if (s.fence) ms.push_back(line_strip(s, "fence", 0, *s.fence, colour(1.0f, 0.6f, 0.0f)));
  if (s.centre) {
    ros2::Marker c = marker(s, "centre", 0, ros2::kSphere);
    c.pose().position(point(*s.centre));
    c.scale().x(s.agent_diameter / 2);
    c.scale().y(s.agent_diameter / 2);
    c.scale().z(s.agent_diameter / 2);
    c.color(colour(1.0f, 0.2f, 1.0f));
    ms.push_back(c);
  }
  if (s.commands) {
    for (const MirrorAgent& a : agents) {
      ros2::Marker m = marker(s, "commands", a.id, ros2::kArrow);
      // ARROW with two points: from the first to the second; scale.x shaft, scale.y head diameter.
      m.points().push_back(point(a.x));
      m.points().push_back(point(a.x + a.v));
      m.scale().x(s.line_width);
      m.scale().y(2 * s.line_width);
      m.color(colour(1.0f, 0.9f, 0.1f));
      ms.push_back(m);
    }
  }
}

}  // namespace shapeform::dds
