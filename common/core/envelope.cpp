#include "envelope.hpp"

#include <algorithm>
#include <cmath>

#include "fence.hpp"
#include "params.hpp"

namespace shapeform::core {

namespace {

using params::format_number;

/// |v| without overflow (Eigen's norm() squares: 1e300 would read infinite).
double length(const Vec2& v) { return std::hypot(v.x(), v.y()); }

std::string pair_text(const Vec2& v) {
  return "(" + format_number(v.x()) + ", " + format_number(v.y()) + ")";
}

/// The key (and wire field) that sets the size of a shape of this kind.
std::pair<const char*, const char*> size_key(ShapeKind k) {
  switch (k) {
    case ShapeKind::Line:
      return {"shape.c", "c"};
    case ShapeKind::Circle:
      return {"shape.r0", "r0"};
    case ShapeKind::Ellipse:
    case ShapeKind::Square:
      return {"shape.a", "a"};
    case ShapeKind::Polar:
      return {"shape.r_expr", "r_expr"};
    case ShapeKind::Parametric:
      return {"shape.x_expr", "x_expr"};
    case ShapeKind::Implicit:
      return {"shape.f_expr", "f_expr"};
    case ShapeKind::Polygon:
      return {"shape.vertices", "vertices"};
  }
  return {"shape", "shape_kind"};
}

/// The value of the size key as text.
std::string size_value(const ShapeSpec& s) {
  switch (s.kind) {
    case ShapeKind::Line:
      return format_number(s.c);
    case ShapeKind::Circle:
      return format_number(s.r0);
    case ShapeKind::Ellipse:
    case ShapeKind::Square:
      return format_number(s.a);
    case ShapeKind::Polar:
      return "'" + s.r_expr + "'";
    case ShapeKind::Parametric:
      return "'" + s.x_expr + "'";
    case ShapeKind::Implicit:
      return "'" + s.f_expr + "'";
    case ShapeKind::Polygon:
      return std::to_string(s.vertices.size()) + " vertices";
  }
  return "?";
}

/// How far from the world origin the centre gets (the tracked path's farthest point; a line path
/// only at C(0): it leaves any bounded workspace in time, and the clamp of agent_step stops the
/// formation at the edge), with the key and wire field that set it.
struct CentreReach {
  double distance;
  std::string key, wire, value;
};
CentreReach centre_reach(const Command& cmd) {
  if (!cmd.tracking.enabled)
    return {length(cmd.shape.centre), "shape.centre", "cx", pair_text(cmd.shape.centre)};
  const CentrePath& p = cmd.tracking.path;
  switch (p.kind) {
    case CentrePath::Kind::Circle:
      return {length(p.origin) + p.radius, "tracking.origin", "path_ox",
              pair_text(p.origin) + " with tracking.radius = " + format_number(p.radius)};
    case CentrePath::Kind::Fixed:
    case CentrePath::Kind::Line:
      break;
  }
  return {length(p.point), "tracking.point", "path_px", pair_text(p.point)};
}

/// gain x dt x sigma^(-2 beta): the fraction of its distance one Euler step moves an agent that is
/// close to its target (or neighbour).
double step_gain(double gain, const Command& cmd) {
  return gain * cmd.dt * std::pow(cmd.gains.sigma, -2.0 * cmd.gains.beta);
}

}  // namespace

double shape_reach(const CompiledCommand& cmd) {
  const Curve& curve = cmd.curve();
  double local = 0.0;
  if (!std::isfinite(curve.length())) {
    local = length(curve.at(0.0));  // the line: its foot of the centre
  } else {
    // Sampled finely enough for a reach within a fraction of a percent (sampled curves hold 4096
    // points; their vertices between samples add at most the sagitta).
    constexpr int kReachSamples = 1024;
    const double len = curve.length();
    for (int k = 0; k <= kReachSamples; ++k)
      local = std::max(local, length(curve.at(len * k / kReachSamples)));
  }
  return cmd.shape.scale * local;
}

std::vector<EnvelopeProblem> envelope_problems(const CompiledCommand& cmd) {
  std::vector<EnvelopeProblem> out;
  const double w = cmd.workspace;
  const std::string where = ", outside the workspace (safety.workspace = " + format_number(w) + ")";
  // The shape: its centre (or the tracked path) and its reach about it.
  const CentreReach c = centre_reach(cmd);
  const double reach = shape_reach(cmd);
  if (!(c.distance <= w)) {
    out.push_back({c.key, c.wire,
                   c.key + " = " + c.value + ": the shape's centre gets " + format_number(c.distance) +
                       " units from the origin" + where});
  } else if (!(c.distance + reach <= w)) {
    const bool scaled = cmd.shape.scale != 1.0;
    const auto [key, wire] =
        scaled ? std::pair<const char*, const char*>{"shape.scale", "scale"} : size_key(cmd.shape.kind);
    const std::string value = scaled ? format_number(cmd.shape.scale) : size_value(cmd.shape);
    out.push_back({key, wire,
                   std::string(key) + " = " + value + ": the shape reaches " +
                       format_number(c.distance + reach) + " units from the origin" + where});
  }
  // The fence: convex and inside the workspace (fence.hpp).
  const std::vector<std::string> fence = fence_problems(cmd.fence, w);
  if (!fence.empty()) {
    std::string value;
    for (const Vec2& v : cmd.fence)
      value += (value.empty() ? "[[" : ", [") + format_number(v.x()) + ", " + format_number(v.y()) + "]";
    out.push_back({"safety.fence", "fence", "safety.fence = " + value + "]: " + params::join(fence, "; ")});
  }
  // The gains: one step must not overshoot beyond what the speed limit can hold.
  const double limit = cmd.max_speed > 0.0 ? kStepGainMaxLimited : kStepGainMaxFree;
  const std::string why =
      cmd.max_speed > 0.0
          ? " (a step overshoots its target " + format_number(limit - 1) +
                " times over: nothing a formation can follow)"
          : " without a speed limit (dynamics.max_speed = 0: every step overshoots further and "
            "the swarm leaves the workspace)";
  const auto gain = [&](const char* key, const char* wire, double value, double g, const char* formula) {
    if (value == 0.0 || g <= limit) return;  // a zero gain is off, whatever sigma^(-2 beta) is
    out.push_back({key, wire,
                   std::string(key) + " = " + format_number(value) + ": the step gain " + formula + " is " +
                       format_number(g) + ", must be <= " + format_number(limit) + why});
  };
  if (cmd.law == Law::Paper) {
    gain("dynamics.k1", "k1", cmd.gains.k1, step_gain(cmd.gains.k1, cmd), "k1 dt sigma^(-2 beta)");
    gain("dynamics.k2", "k2", cmd.gains.k2, step_gain(cmd.gains.k2, cmd), "k2 dt sigma^(-2 beta)");
  } else {
    gain("dynamics.k_normal", "k_normal", cmd.arc.k_normal, cmd.arc.k_normal * cmd.dt, "k_normal dt");
  }
  return out;
}

std::string envelope_text(const std::vector<EnvelopeProblem>& problems) {
  std::string s;
  for (const auto& p : problems) s += (s.empty() ? "" : "; ") + p.text;
  return s;
}

Vec2 keep_inside(const Vec2& next, double workspace, bool& clamped) {
  const Vec2 in = next.cwiseMax(Vec2(-workspace, -workspace)).cwiseMin(Vec2(workspace, workspace));
  clamped = in != next;
  return in;
}

}  // namespace shapeform::core
