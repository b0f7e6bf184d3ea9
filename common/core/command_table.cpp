#include "command_table.hpp"

#include "envelope.hpp"
#include "enum_names.hpp"

namespace shapeform::core::params {

namespace {

using P = Param<Command>;

/// A number field of the command.
template <class Field>
P real(std::string key, std::string wire, std::string unit, Range range, std::string doc, Field field) {
  return make<Command, double>(Type::Real, std::move(key), std::move(unit), range, std::move(doc), field, {},
                               {std::move(wire)});
}

template <class V, class Field>
P plain(Type type, std::string key, std::vector<std::string> wire, std::string unit, std::string doc,
        std::string range_note, Field field) {
  return make<Command, V>(type, std::move(key), std::move(unit), {}, std::move(doc), field, std::move(range_note),
                          std::move(wire));
}

template <class Field>
P vec2(std::string key, std::string wx, std::string wy, std::string unit, std::string doc, Field field) {
  return plain<Vec2>(Type::Vec2, std::move(key), {std::move(wx), std::move(wy)}, std::move(unit),
                     std::move(doc), "", field);
}

template <class Field>
P flag(std::string key, std::string wire, std::string doc, Field field) {
  return plain<bool>(Type::Bool, std::move(key), {std::move(wire)}, "", std::move(doc), "", field);
}

template <class Field>
P text(std::string key, std::string wire, std::string unit, std::string doc, std::string range_note,
       Field field) {
  return plain<std::string>(Type::Text, std::move(key), {std::move(wire)}, std::move(unit), std::move(doc),
                            std::move(range_note), field);
}

template <class E, std::size_t N, class Field>
P choice(std::string key, std::string wire, std::string doc, const Name<E> (&table)[N], Field field) {
  P p = make_choice<Command>(std::move(key), std::move(doc), table, field);
  p.wire = {std::move(wire)};
  return p;
}

std::vector<P> build_command_table() {
  const std::string su = "shape units";
  const std::string speed = "shape units / model time";
  std::vector<P> t;
  // shape
  t.push_back(choice(
      "shape.kind", "shape_kind", "which shape", kShapeKindNames,
      [](auto& c) -> auto& { return c.shape.kind; }));
  t.push_back(real(
      "shape.m", "m", "", any(), "line `x2 = m x1 + c`: slope", [](auto& c) -> auto& { return c.shape.m; }));
  t.push_back(real(
      "shape.c", "c", su, any(), "line: intercept", [](auto& c) -> auto& { return c.shape.c; }));
  t.push_back(real(
      "shape.r0", "r0", su, above(0), "circle radius", [](auto& c) -> auto& { return c.shape.r0; }));
  t.push_back(real(
      "shape.a", "a", su, above(0), "ellipse semi-axis along x1, or square half side",
      [](auto& c) -> auto& { return c.shape.a; }));
  t.push_back(real(
      "shape.b", "b", su, above(0), "ellipse semi-axis along x2",
      [](auto& c) -> auto& { return c.shape.b; }));
  t.push_back(vec2(
      "shape.centre", "cx", "cy", su,
      "where the shape's local origin is placed: the centre of closed shapes (the line, drawn in the "
      "local frame too, is shifted by it); `tracking` replaces it by C(t)",
      [](auto& c) -> auto& { return c.shape.centre; }));
  {
    P rot = real(
        "shape.rotation_deg", "rotation", "degrees", any(),
        "counter-clockwise rotation about the centre (every kind); stored as radians (and sent as "
        "radians in ShapeCommand.rotation)",
        [](auto& c) -> auto& { return c.shape.rotation; });
    rot.degrees = true;
    t.push_back(std::move(rot));
  }
  t.push_back(real(
      "shape.scale", "scale", "", above(0), "uniform scale about the centre (every kind)",
      [](auto& c) -> auto& { return c.shape.scale; }));
  t.push_back(text(
      "shape.r_expr", "r_expr", su,
      "polar: `r(phi)`, radius as a function of the angle `phi` in `[0, 2 pi)`; radial projection",
      "expression in `phi`, finite and `> 0` for every `phi`",
      [](auto& c) -> auto& { return c.shape.r_expr; }));
  t.push_back(text(
      "shape.x_expr", "x_expr", su, "parametric: `x(s)`, `s` in `[0, 1]`; closest-point projection",
      "expression in `s`", [](auto& c) -> auto& { return c.shape.x_expr; }));
  t.push_back(text(
      "shape.y_expr", "y_expr", su, "parametric: `y(s)`", "expression in `s`",
      [](auto& c) -> auto& { return c.shape.y_expr; }));
  t.push_back(text(
      "shape.f_expr", "f_expr", "", "implicit: the curve `f(x, y) = 0`; Newton projection along grad f",
      "expression in `x`, `y`, with real zeros in `[-20, 20]^2` (shape-local)",
      [](auto& c) -> auto& { return c.shape.f_expr; }));
  t.push_back(plain<std::vector<Vec2>>(
      Type::Vec2List, "shape.vertices", {"vertices"}, su,
      "polygon: vertices `[[x, y], ...]` in order; closest-point projection (on the wire flattened x0, y0, "
      "x1, "
      "y1, ...)",
      "finite pairs; closed: `>= 3` not all collinear, open: `>= 2`; no two consecutive equal",
      [](auto& c) -> auto& { return c.shape.vertices; }));
  t.push_back(flag(
      "shape.closed", "closed", "parametric, polygon: the last point joins the first",
      [](auto& c) -> auto& { return c.shape.closed; }));
  // tracking
  t.push_back(flag(
      "tracking.enabled", "tracking", "draw the shape around C(t) instead of `shape.centre`",
      [](auto& c) -> auto& { return c.tracking.enabled; }));
  t.push_back(choice(
      "tracking.path", "path_kind", "kind of path", kPathKindNames,
      [](auto& c) -> auto& { return c.tracking.path.kind; }));
  t.push_back(vec2(
      "tracking.point", "path_px", "path_py", su, "fixed: the centre; line: C(0)",
      [](auto& c) -> auto& { return c.tracking.path.point; }));
  t.push_back(vec2(
      "tracking.velocity", "path_vx", "path_vy", speed, "line: dC/dt",
      [](auto& c) -> auto& { return c.tracking.path.velocity; }));
  t.push_back(vec2(
      "tracking.origin", "path_ox", "path_oy", su, "circle: centre of the circular path",
      [](auto& c) -> auto& { return c.tracking.path.origin; }));
  t.push_back(real(
      "tracking.radius", "path_radius", su, at_least(0), "circle: path radius",
      [](auto& c) -> auto& { return c.tracking.path.radius; }));
  t.push_back(real(
      "tracking.period", "path_period", "model time", above(0), "circle: time per revolution",
      [](auto& c) -> auto& { return c.tracking.path.period; }));
  t.push_back(real(
      "tracking.phase", "path_phase", "rad", any(), "circle: angle of C(0) about the origin",
      [](auto& c) -> auto& { return c.tracking.path.phase; }));
  t.push_back(flag(
      "tracking.feedforward", "feedforward", "add dC/dt to every agent's velocity",
      [](auto& c) -> auto& { return c.tracking.feedforward; }));
  // dynamics: the paper's gains, the speed limit, the law and the arc law's parameters
  t.push_back(real(
      "dynamics.k1", "k1", "", at_least(0), "cohesion (foraging) gain",
      [](auto& c) -> auto& { return c.gains.k1; }));
  t.push_back(real(
      "dynamics.k2", "k2", "", at_least(0), "attraction-to-shape gain",
      [](auto& c) -> auto& { return c.gains.k2; }));
  t.push_back(real(
      "dynamics.sigma", "sigma", su, above(0), "softening length",
      [](auto& c) -> auto& { return c.gains.sigma; }));
  t.push_back(real(
      "dynamics.beta", "beta", "", at_least(0), "decay exponent",
      [](auto& c) -> auto& { return c.gains.beta; }));
  t.push_back(real(
      "dynamics.r", "r", speed, at_least(0), "nearest-neighbour repulsion magnitude (0 = off)",
      [](auto& c) -> auto& { return c.gains.r; }));
  t.push_back(real(
      "dynamics.max_speed", "max_speed", speed, at_least(0),
      "speed limit, both laws (0 = none; then the step gains must be <= 2 instead of 10)",
      [](auto& c) -> auto& { return c.max_speed; }));
  t.push_back(choice(
      "dynamics.law", "law",
      "control law: `paper` = eq. 2 with the gains above; `arc` = arc-length slots (docs/LAW.md)", kLawNames,
      [](auto& c) -> auto& { return c.law; }));
  t.push_back(real(
      "dynamics.k_normal", "k_normal", "1 / model time", above_up_to(0, 10),
      "arc law: rate toward the curve point ahead; keep `k_normal * dt <= 1`",
      [](auto& c) -> auto& { return c.arc.k_normal; }));
  t.push_back(real(
      "dynamics.k_tangent", "k_tangent", "", above_up_to(0, 1),
      "arc law: fraction of the slot error taken per step along the curve",
      [](auto& c) -> auto& { return c.arc.k_tangent; }));
  t.push_back(real(
      "dynamics.spacing", "spacing", su, above(0),
      "arc law: gap between neighbours on an unbounded curve (the line)",
      [](auto& c) -> auto& { return c.arc.spacing; }));
  t.push_back(flag(
      "dynamics.hold", "hold",
      "every agent keeps its position and model time stands still (the console's `hold` / `stop` set "
      "it, `resume` clears it)",
      [](auto& c) -> auto& { return c.hold; }));
  // integration
  t.push_back(choice(
      "integration.integrator", "integrator", "integration scheme", kIntegratorNames,
      [](auto& c) -> auto& { return c.integrator; }));
  // Larger steps make either law meaningless (the paper's iteration is dt = 1).
  t.push_back(real(
      "integration.dt", "dt", "model time", above_up_to(0, 10),
      "model time per step (one paper iteration = 1)", [](auto& c) -> auto& { return c.dt; }));
  // safety: the envelope every command is checked against (core/envelope.hpp)
  t.push_back(real(
      "safety.workspace", "workspace", su, above_up_to(0, kWorkspaceMax),
      "half-width of the workspace `[-w, w]^2` centred on the origin: a command whose shape, centre, path or "
      "gains could carry agents outside is refused, and no agent steps outside",
      [](auto& c) -> auto& { return c.workspace; }));
  t.push_back(real(
      "safety.min_separation", "min_separation", su, at_least(0),
      "smallest distance two agents keep at every step, not only at the end: each agent's step is moved as "
      "little as possible into its buffered Voronoi cell (core/safety.hpp; docs/SAFETY.md); 0 = off, the law's "
      "steps bit for bit",
      [](auto& c) -> auto& { return c.min_separation; }));
  t.push_back(plain<std::vector<KeepOutZone>>(
      Type::ZoneList, "safety.keep_out", {"keep_out_circles", "keep_out_polygons"}, su,
      "regions no agent enters: `[{circle: [cx, cy, r]}, {polygon: [[x, y], ...]}]` (circles first, as they "
      "travel; on the wire the circles flattened cx, cy, r, ... and each polygon as its vertex count then its "
      "x, y pairs)",
      "circles: finite, `r > 0`; polygons: `>= 3` finite vertices, no two consecutive equal, not all collinear, "
      "edges that do not cross (convex or not)",
      [](auto& c) -> auto& { return c.keep_out; }));
  t.push_back(plain<std::vector<Vec2>>(
      Type::Vec2List, "safety.fence", {"fence"}, su,
      "the geofence: a convex polygon `[[x, y], ...]` (either way round) the agents stay inside; empty: the "
      "workspace box `[-w, w]^2` is the fence. Every step is kept `safety.fence_margin` inside it "
      "(core/fence.hpp); an agent found beyond it takes `safety.breach_action` (docs/SAFETY.md, Geofence). "
      "On "
      "the wire flattened x0, y0, x1, y1, ...",
      "empty, or `>= 3` finite vertices, no two consecutive equal, not all collinear, simple and convex (cut "
      "a "
      "dent out with `safety.keep_out` instead), every vertex inside `[-w, w]^2`",
      [](auto& c) -> auto& { return c.fence; }));
  t.push_back(real(
      "safety.fence_margin", "fence_margin", su, at_least(0),
      "how far inside the fence the safety filter keeps every step (an agent beyond the fence itself is a "
      "breach, not one within the margin); in a fence thinner than twice the margin no step goes further out "
      "and `return` aims at its deepest points",
      [](auto& c) -> auto& { return c.fence_margin; }));
  t.push_back(choice(
      "safety.breach_action", "breach_action",
      "what an agent found beyond the fence (its own position, or its vehicle's pose) does, checked every "
      "step: `hold` = it stops and the supervisor holds the whole swarm (as the console's `hold`; `resume` "
      "releases it); `stop` = that agent stops until the next command; `return` = it heads straight back to "
      "the nearest point `safety.fence_margin` inside the fence through the safety filter, then follows the "
      "law again. After a new command an agent still outside first returns inside",
      kBreachActionNames, [](auto& c) -> auto& { return c.breach_action; }));
  return t;
}

}  // namespace

const std::vector<Param<Command>>& command_table() {
  static const std::vector<Param<Command>> table = build_command_table();
  return table;
}

const Param<Command>* find_key(std::string_view key) {
  for (const auto& p : command_table())
    if (p.key == key) return &p;
  return nullptr;
}

const Param<Command>* find_wire(std::string_view wire) {
  for (const auto& p : command_table())
    for (const auto& w : p.wire)
      if (w == wire) return &p;
  return nullptr;
}

}  // namespace shapeform::core::params
