#include "viz/scene_update.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/fence.hpp"

namespace shapeform::viz {
namespace {

using nlohmann::json;

// ---- The JSON Schemas, written from Foxglove's message definitions (foxglove.SceneUpdate and what it
// holds, foxglove.PosesInFrame), field for field, each object inline (Foxglove reads no $ref).

json number(const char* d) { return {{"type", "number"}, {"description", d}}; }
json integer(const char* d, long long min) {
  return {{"type", "integer"}, {"minimum", min}, {"description", d}};
}
json text(const char* d) { return {{"type", "string"}, {"description", d}}; }
json boolean(const char* d) { return {{"type", "boolean"}, {"description", d}}; }
json object(const char* title, const char* d, json properties) {
  return {{"title", title}, {"description", d}, {"type", "object"}, {"properties", std::move(properties)}};
}
json array(const char* d, json items) {
  return {{"type", "array"}, {"description", d}, {"items", std::move(items)}};
}
json time(const char* d) {
  return {{"type", "object"},
          {"title", "time"},
          {"description", d},
          {"properties",
           {{"sec", integer("Seconds", 0)},
            {"nsec", {{"type", "integer"}, {"minimum", 0}, {"maximum", 999999999}}}}}};
}
json duration(const char* d) {
  return {{"type", "object"},
          {"title", "duration"},
          {"description", d},
          {"properties",
           {{"sec", {{"type", "integer"}}},
            {"nsec", {{"type", "integer"}, {"minimum", 0}, {"maximum", 999999999}}}}}};
}
json xyz(const char* title, const char* d, const char* what) {
  return object(title, d, {{"x", number(what)}, {"y", number(what)}, {"z", number(what)}});
}
json quaternion() {
  return object("foxglove.Quaternion", "Quaternion rotation",
                {{"x", number("x value")},
                 {"y", number("y value")},
                 {"z", number("z value")},
                 {"w", number("w value")}});
}
json pose(const char* d) {
  return object(
      "foxglove.Pose", d,
      {{"position", xyz("foxglove.Vector3", "Point denoting position in 3D space", "coordinate length")},
       {"orientation", quaternion()}});
}
json color(const char* d) {
  return object("foxglove.Color", d,
                {{"r", number("Red value between 0 and 1")},
                 {"g", number("Green value between 0 and 1")},
                 {"b", number("Blue value between 0 and 1")},
                 {"a", number("Alpha value between 0 and 1")}});
}
json point3(const char* d) { return xyz("foxglove.Point3", d, "coordinate length"); }
json uint32s(const char* d) { return array(d, {{"type", "integer"}, {"minimum", 0}}); }

json scene_update_schema() {
  const json size = xyz("foxglove.Vector3", "Size (diameter) along each axis", "length");
  const json sphere =
      object("foxglove.SpherePrimitive", "A primitive representing a sphere or ellipsoid",
             {{"pose", pose("Position of the center of the sphere and orientation of the sphere")},
              {"size", size},
              {"color", color("Color of the sphere")}});
  const json cube = object("foxglove.CubePrimitive", "A primitive representing a cube or rectangular prism",
                           {{"pose", pose("Position of the center of the cube and orientation of the cube")},
                            {"size", size},
                            {"color", color("Color of the cube")}});
  const json cylinder =
      object("foxglove.CylinderPrimitive",
             "A primitive representing a cylinder, elliptic cylinder, or truncated cone",
             {{"pose", pose("Position of the center of the cylinder and orientation of the cylinder")},
              {"size", size},
              {"bottom_scale", number("0-1, ratio of the diameter of the cylinder's bottom face")},
              {"top_scale", number("0-1, ratio of the diameter of the cylinder's top face")},
              {"color", color("Color of the cylinder")}});
  const json arrow =
      object("foxglove.ArrowPrimitive", "A primitive representing an arrow",
             {{"pose", pose("Position of the arrow's tail and orientation of the arrow (along +x)")},
              {"shaft_length", number("Length of the arrow shaft")},
              {"shaft_diameter", number("Diameter of the arrow shaft")},
              {"head_length", number("Length of the arrow head")},
              {"head_diameter", number("Diameter of the arrow head")},
              {"color", color("Color of the arrow")}});
  const json line_type = {
      {"title", "foxglove.LineType"},
      {"description", "An enumeration indicating how input points should be interpreted to create lines"},
      {"oneOf",
       {{{"title", "LINE_STRIP"},
         {"const", 0},
         {"description", "Connected line segments: 0-1, 1-2, ..., (n-1)-n"}},
        {{"title", "LINE_LOOP"},
         {"const", 1},
         {"description", "Closed polygon: 0-1, 1-2, ..., (n-1)-n, n-0"}},
        {{"title", "LINE_LIST"},
         {"const", 2},
         {"description", "Individual line segments: 0-1, 2-3, 4-5, ..."}}}}};
  const json line = object(
      "foxglove.LinePrimitive", "A primitive representing a series of points connected by lines",
      {{"type", line_type},
       {"pose", pose("Origin of lines relative to reference frame")},
       {"thickness", number("Line thickness")},
       {"scale_invariant",
        boolean("Indicates whether `thickness` is a fixed size in screen pixels (true), or specified in "
                "world coordinates and scales with distance from the camera (false)")},
       {"points", array("Points along the line", point3("A point"))},
       {"color",
        color("Solid color to use for the whole line. One of `color` or `colors` must be provided.")},
       {"colors",
        array("Per-point colors (if specified, must have the same length as `points`)", color("A color"))},
       {"indices", uint32s("Indices into the `points` and `colors` attribute arrays")}});
  const json triangles = object(
      "foxglove.TriangleListPrimitive",
      "A primitive representing a set of triangles or a surface tiled by triangles",
      {{"pose", pose("Origin of triangles relative to reference frame")},
       {"points", array("Vertices to use for triangles, interpreted as a list of triples (0-1-2, 3-4-5, ...)",
                        point3("A point"))},
       {"color", color("Solid color to use for the whole shape")},
       {"colors", array("Per-vertex colors", color("A color"))},
       {"indices", uint32s("Indices into the `points` and `colors` attribute arrays")}});
  const json text_primitive = object(
      "foxglove.TextPrimitive", "A primitive representing a text label",
      {{"pose", pose("Position of the center of the text box and orientation of the text")},
       {"billboard",
        boolean(
            "Whether the text should respect `pose.orientation` (false) or always face the camera (true)")},
       {"font_size", number("Font size (height of one line of text)")},
       {"scale_invariant", boolean("Indicates whether `font_size` is a fixed size in screen pixels (true), "
                                   "or specified in world coordinates")},
       {"color", color("Color of the text")},
       {"text", text("Text")}});
  const json model = object(
      "foxglove.ModelPrimitive",
      "A primitive representing a 3D model file loaded from an external URL or embedded data",
      {{"pose", pose("Origin of model relative to reference frame")},
       {"scale", xyz("foxglove.Vector3", "Scale factor to apply to the model along each axis", "scale")},
       {"color", color("Solid color to use for the whole model if `override_color` is true")},
       {"override_color", boolean("Whether to use the color specified in `color` instead of any materials "
                                  "embedded in the original model")},
       {"url", text("URL pointing to model file")},
       {"media_type", text("Model's media type")},
       {"data", {{"type", "string"}, {"contentEncoding", "base64"}, {"description", "Embedded model"}}}});
  const json entity =
      object("foxglove.SceneEntity",
             "A visual element in a 3D scene. An entity may be composed of multiple primitives which all "
             "share the same frame of reference.",
             {{"timestamp", time("Timestamp of the entity")},
              {"frame_id", text("Frame of reference")},
              {"id", text("Identifier for the entity. A entity will replace any prior entity on the same "
                          "topic with the same `id`.")},
              {"lifetime", duration("Length of time (relative to `timestamp`) after which the entity should "
                                    "be automatically removed. Zero value indicates the entity should remain "
                                    "visible until it is replaced or deleted.")},
              {"frame_locked",
               boolean("Whether the entity should keep its location in the fixed frame (false) or follow the "
                       "frame specified in `frame_id` as it moves relative to the fixed frame (true)")},
              {"metadata", array("Additional user-provided metadata associated with the entity",
                                 object("foxglove.KeyValuePair", "A key with its associated value",
                                        {{"key", text("Key")}, {"value", text("Value")}}))},
              {"arrows", array("Arrow primitives", arrow)},
              {"cubes", array("Cube primitives", cube)},
              {"spheres", array("Sphere primitives", sphere)},
              {"cylinders", array("Cylinder primitives", cylinder)},
              {"lines", array("Line primitives", line)},
              {"triangles", array("Triangle list primitives", triangles)},
              {"texts", array("Text primitives", text_primitive)},
              {"models", array("Model primitives", model)}});
  const json deletion_type = {
      {"title", "foxglove.SceneEntityDeletionType"},
      {"description", "An enumeration indicating which entities should match a SceneEntityDeletion command"},
      {"oneOf",
       {{{"title", "MATCHING_ID"},
         {"const", 0},
         {"description", "Delete the existing entity on the same topic that has the provided `id`"}},
        {{"title", "ALL"},
         {"const", 1},
         {"description", "Delete all existing entities on the same topic"}}}}};
  const json deletion =
      object("foxglove.SceneEntityDeletion", "Command to remove previously published entities",
             {{"timestamp", time("Timestamp of the deletion. Only matching entities earlier than this "
                                 "timestamp will be deleted.")},
              {"type", deletion_type},
              {"id", text("Identifier which must match if `type` is `MATCHING_ID`.")}});
  return object("foxglove.SceneUpdate", "An update to the entities displayed in a 3D scene",
                {{"deletions", array("Scene entities to delete", deletion)},
                 {"entities", array("Scene entities to add or replace", entity)}});
}

json poses_in_frame_schema() {
  return object(
      "foxglove.PosesInFrame", "An array of timestamped poses for an object or reference frame in 3D space",
      {{"timestamp", time("Timestamp of pose")},
       {"frame_id", text("Frame of reference for pose position and orientation")},
       {"poses", array("Poses in 3D space",
                       pose("A position and orientation for an object or reference frame in 3D space"))}});
}

// ---- The messages, written straight as text: 1000 agents in well under a millisecond (a JSON tree
// would allocate a node per number).

class Writer {
 public:
  explicit Writer(std::size_t reserve) { out_.reserve(reserve); }
  Writer& raw(std::string_view s) {
    out_.append(s);
    return *this;
  }
  Writer& num(double v) {
    if (!std::isfinite(v)) v = 0.0;
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);  // shortest text that reads back exactly
    out_.append(buf, r.ptr);
    return *this;
  }
  Writer& uint(std::uint64_t v) {
    char buf[24];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    out_.append(buf, r.ptr);
    return *this;
  }
  Writer& xyz(double x, double y, double z) {
    return raw("{\"x\":").num(x).raw(",\"y\":").num(y).raw(",\"z\":").num(z).raw("}");
  }
  /// A pose at (x, y, 0), not turned.
  Writer& pose(double x, double y) {
    return raw("{\"position\":{\"x\":")
        .num(x)
        .raw(",\"y\":")
        .num(y)
        .raw(",\"z\":0},\"orientation\":{\"x\":0,\"y\":0,\"z\":0,\"w\":1}}");
  }
  /// A pose at (x, y, 0) turned by yaw about z.
  Writer& pose(double x, double y, double yaw) {
    raw("{\"position\":").xyz(x, y, 0.0).raw(",\"orientation\":{\"x\":0,\"y\":0,\"z\":");
    return num(std::sin(0.5 * yaw)).raw(",\"w\":").num(std::cos(0.5 * yaw)).raw("}}");
  }
  Writer& colour(const Rgba& c) {
    return raw("{\"r\":")
        .num(c.r)
        .raw(",\"g\":")
        .num(c.g)
        .raw(",\"b\":")
        .num(c.b)
        .raw(",\"a\":")
        .num(c.a)
        .raw("}");
  }
  Writer& time(std::uint64_t ns) {
    return raw("{\"sec\":").uint(ns / 1000000000u).raw(",\"nsec\":").uint(ns % 1000000000u).raw("}");
  }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

constexpr Rgba kOutline{0.25, 0.55, 1.0, 1.0};
constexpr Rgba kKeepOut{0.9, 0.2, 0.2, 1.0};
constexpr Rgba kFence{1.0, 0.8, 0.1, 1.0};
constexpr Rgba kFenceMargin{1.0, 0.8, 0.1, 0.4};
constexpr Rgba kCentre{0.85, 0.25, 0.85, 1.0};
constexpr Rgba kHeading{1.0, 1.0, 1.0, 0.9};

/// One LinePrimitive (type 0 strip, 1 loop) through pts at z = 0.
void line(Writer& w, bool& first, const std::vector<core::Vec2>& pts, bool loop, const Rgba& c,
          const SceneStyle& style) {
  if (pts.size() < 2) return;
  w.raw(first ? "{" : ",{");
  first = false;
  w.raw("\"type\":")
      .raw(loop ? "1" : "0")
      .raw(",\"pose\":")
      .pose(0.0, 0.0)
      .raw(",\"thickness\":")
      .num(style.line_width_px);
  w.raw(",\"scale_invariant\":true,\"points\":[");
  for (std::size_t i = 0; i < pts.size(); ++i) w.raw(i ? "," : "").xyz(pts[i].x(), pts[i].y(), 0.0);
  w.raw("],\"color\":").colour(c).raw(",\"colors\":[],\"indices\":[]}");
}

/// The fence moved inwards by margin: the corners of its shrunk half-planes (core::fence_half_planes),
/// each the meeting of two consecutive edges; empty when the margin leaves nothing.
std::vector<core::Vec2> shrunk_fence(const std::vector<core::Vec2>& fence, double margin) {
  core::Command cmd;
  cmd.fence = fence;
  cmd.fence_margin = margin;
  const auto planes = core::fence_half_planes(cmd);
  std::vector<core::Vec2> out;
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const core::HalfPlane& a = planes[i];
    const core::HalfPlane& b = planes[(i + 1) % planes.size()];
    const double det = a.n.x() * b.n.y() - a.n.y() * b.n.x();
    if (std::abs(det) < 1e-12) continue;
    const core::Vec2 p((a.b * b.n.y() - b.b * a.n.y()) / det, (a.n.x() * b.b - b.n.x() * a.b) / det);
    for (const auto& h : planes) {
      if (!h.contains(p, 1e-9)) return {};  // the margin swallowed this corner: nothing left to draw
    }
    out.push_back(p);
  }
  return out;
}

/// Opens entity `id` (everything before its primitive arrays).
void open_entity(Writer& w, bool first, std::string_view id, std::uint64_t stamp_ns) {
  w.raw(first ? "{" : ",{")
      .raw("\"timestamp\":")
      .time(stamp_ns)
      .raw(",\"frame_id\":\"")
      .raw(kFrameId)
      .raw("\",\"id\":\"")
      .raw(id);
  w.raw("\",\"lifetime\":{\"sec\":0,\"nsec\":0},\"frame_locked\":false,\"metadata\":[]");
}

/// Closes an entity: the primitive arrays it did not write, empty.
void close_entity(Writer& w, std::initializer_list<std::string_view> written) {
  for (const std::string_view a :
       {"arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models"}) {
    bool done = false;
    for (const auto& x : written) done = done || x == a;
    if (!done) w.raw(",\"").raw(a).raw("\":[]");
  }
  w.raw("}");
}

}  // namespace

const std::vector<Channel>& scene_channels() {
  static const std::string scene_schema = scene_update_schema().dump();
  static const std::string poses_schema = poses_in_frame_schema().dump();
  static const std::vector<Channel> channels = {
      {"shapeform/scene", "foxglove.SceneUpdate", "jsonschema", scene_schema, "json"},
      {"shapeform/agent_poses", "foxglove.PosesInFrame", "jsonschema", poses_schema, "json"},
  };
  return channels;
}

Rgba agent_colour(AgentLook look) {
  switch (look) {
    case AgentLook::Alive:
      return {0.2, 0.8, 0.3, 1.0};
    case AgentLook::Stale:
      return {1.0, 0.65, 0.0, 1.0};
    case AgentLook::Dead:
      return {0.5, 0.5, 0.5, 0.5};
  }
  return {1.0, 0.0, 1.0, 1.0};
}

std::string scene_update_json(const SceneSnapshot& s, std::uint64_t stamp_ns, const SceneStyle& style) {
  Writer w(1024 + 260 * s.agents.size() + 80 * s.outline.size());
  w.raw("{\"deletions\":[],\"entities\":[");
  const double d = style.agent_diameter;
  // Each sphere's size and colour, written once per look: only the position changes per agent.
  std::string tail[3];
  for (const AgentLook look : {AgentLook::Alive, AgentLook::Stale, AgentLook::Dead}) {
    Writer t(160);
    t.raw(",\"size\":").xyz(d, d, d).raw(",\"color\":").colour(agent_colour(look)).raw("}");
    tail[static_cast<int>(look)] = t.take();
  }
  open_entity(w, true, "agents", stamp_ns);
  w.raw(",\"spheres\":[");
  for (std::size_t i = 0; i < s.agents.size(); ++i) {
    const AgentDraw& a = s.agents[i];
    w.raw(i ? ",{\"pose\":" : "{\"pose\":").pose(a.x.x(), a.x.y()).raw(tail[static_cast<int>(a.look)]);
  }
  w.raw("]");
  close_entity(w, {"spheres"});

  open_entity(w, false, "headings", stamp_ns);
  w.raw(",\"arrows\":[");
  bool first = true;
  const double len = style.arrow_length;
  for (const AgentDraw& a : s.agents) {
    if (!a.heading) continue;
    w.raw(first ? "{\"pose\":" : ",{\"pose\":").pose(a.x.x(), a.x.y(), *a.heading);
    first = false;
    w.raw(",\"shaft_length\":")
        .num(0.65 * len)
        .raw(",\"shaft_diameter\":")
        .num(0.15 * len)
        .raw(",\"head_length\":")
        .num(0.35 * len);
    w.raw(",\"head_diameter\":").num(0.35 * len).raw(",\"color\":").colour(kHeading).raw("}");
  }
  w.raw("]");
  close_entity(w, {"arrows"});

  open_entity(w, false, "outline", stamp_ns);
  w.raw(",\"lines\":[");
  first = true;
  line(w, first, s.outline, s.outline_closed, kOutline, style);
  w.raw("]");
  close_entity(w, {"lines"});

  open_entity(w, false, "keep_out", stamp_ns);
  w.raw(",\"lines\":[");
  first = true;
  for (const core::KeepOutZone& z : s.keep_out) {
    if (z.kind == core::KeepOutZone::Kind::Polygon) {
      line(w, first, z.vertices, true, kKeepOut, style);
      continue;
    }
    std::vector<core::Vec2> ring;
    const int n = std::max(8, style.circle_segments);
    for (int k = 0; k < n; ++k) {
      const double phi = 2.0 * M_PI * k / n;
      ring.emplace_back(z.centre.x() + z.radius * std::cos(phi), z.centre.y() + z.radius * std::sin(phi));
    }
    line(w, first, ring, true, kKeepOut, style);
  }
  w.raw("]");
  close_entity(w, {"lines"});

  open_entity(w, false, "fence", stamp_ns);
  w.raw(",\"lines\":[");
  first = true;
  line(w, first, s.fence, true, kFence, style);
  if (s.fence.size() >= 3 && s.fence_margin > 0.0)
    line(w, first, shrunk_fence(s.fence, s.fence_margin), true, kFenceMargin, style);
  w.raw("]");
  close_entity(w, {"lines"});

  open_entity(w, false, "centre", stamp_ns);
  w.raw(",\"spheres\":[");
  if (s.centre) {
    const double c = style.centre_diameter;
    w.raw("{\"pose\":")
        .pose(s.centre->x(), s.centre->y())
        .raw(",\"size\":")
        .xyz(c, c, c)
        .raw(",\"color\":")
        .colour(kCentre)
        .raw("}");
  }
  w.raw("]");
  close_entity(w, {"spheres"});
  w.raw("]}");
  return w.take();
}

std::string poses_json(const SceneSnapshot& s, std::uint64_t stamp_ns) {
  Writer w(128 + 110 * s.agents.size());
  w.raw("{\"timestamp\":").time(stamp_ns).raw(",\"frame_id\":\"").raw(kFrameId).raw("\",\"poses\":[");
  for (std::size_t i = 0; i < s.agents.size(); ++i) {
    const AgentDraw& a = s.agents[i];
    w.raw(i ? "," : "");
    if (a.heading)
      w.pose(a.x.x(), a.x.y(), *a.heading);
    else
      w.pose(a.x.x(), a.x.y());
  }
  w.raw("]}");
  return w.take();
}

}  // namespace shapeform::viz
