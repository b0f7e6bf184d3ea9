// ShapeCommand <-> core::Command through the command table: one loop each way over the bound fields.
#include "dds/convert_command.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/envelope.hpp"
#include "core/params.hpp"
#include "core/safety.hpp"
#include "dds/convert.hpp"
#include "shapes/shapes.hpp"
#include "util/text.hpp"

/// X(field) per ShapeCommand field that carries a core::Command field, in IDL order: every field of
/// idl/ShapeCommand.idl but epoch, issuer and issuer_name. The IDL name is all a row says; the
/// command-table entry naming it in its `wire` says the rest (command_wire() checks that they agree).
// clang-format off
#define SHAPEFORM_COMMAND_WIRE(X)                                                                     \
  X(shape_kind) X(m) X(c) X(r0) X(a) X(b) X(cx) X(cy) X(rotation) X(scale)                            \
  X(r_expr) X(x_expr) X(y_expr) X(f_expr) X(vertices) X(closed)                                       \
  X(tracking) X(path_kind) X(path_px) X(path_py) X(path_vx) X(path_vy) X(path_ox) X(path_oy)          \
  X(path_radius) X(path_period) X(path_phase) X(feedforward)                                          \
  X(k1) X(k2) X(sigma) X(beta) X(r) X(max_speed)                                                      \
  X(integrator) X(dt) X(law) X(k_normal) X(k_tangent) X(spacing) X(hold) X(workspace)        \
  X(min_separation) X(keep_out_circles) X(keep_out_polygons) X(fence) X(fence_margin) X(breach_action)
// clang-format on

namespace shapeform::dds {
namespace {

namespace params = core::params;
using Param = params::Param<core::Command>;

/// A field's name and accessors, before it is matched to its entry.
struct Accessors {
  std::string_view name;
  WireValue (*get)(const msg::ShapeCommand&);
  void (*set)(msg::ShapeCommand&, WireValue&&);
};

// The generated accessors are overloaded (getter, copy and move setters), hence lambdas rather than
// member pointers. The setter takes the alternative of the field's own type.
#define SHAPEFORM_WIRE_ACCESSORS(field)                                              \
  Accessors{#field, [](const msg::ShapeCommand& m) { return WireValue(m.field()); }, \
            [](msg::ShapeCommand& m, WireValue&& v) {                                \
              m.field(std::get<std::decay_t<decltype(m.field())>>(std::move(v)));    \
            }},
constexpr Accessors kAccessors[] = {SHAPEFORM_COMMAND_WIRE(SHAPEFORM_WIRE_ACCESSORS)};
#undef SHAPEFORM_WIRE_ACCESSORS

/// A value of the alternative an entry of p's type travels as.
WireValue wire_form(const Param& p) {
  switch (p.type) {
    case params::Type::Real:
    case params::Type::Vec2:
      return 0.0;
    case params::Type::Bool:
      return false;
    case params::Type::Text:
    case params::Type::Choice:
      return std::string();
    case params::Type::Vec2List:
    case params::Type::ZoneList:
      return std::vector<double>();
    default:
      throw std::logic_error("command table entry " + p.key + ": its type has no ShapeCommand form");
  }
}

/// kAccessors matched to the command table, checked both ways (command_wire()'s contract).
std::vector<CommandWireField> bind_command_wire() {
  std::vector<CommandWireField> out;
  const msg::ShapeCommand probe;
  for (const Accessors& a : kAccessors) {
    const std::string name(a.name);
    const Param* p = params::find_wire(name);
    if (p == nullptr)
      throw std::logic_error("ShapeCommand field '" + name + "' is in no command table entry");
    if (a.get(probe).index() != wire_form(*p).index())
      throw std::logic_error("ShapeCommand field '" + name + "' does not have the type of " + p->key);
    const auto k =
        static_cast<std::size_t>(std::find(p->wire.begin(), p->wire.end(), name) - p->wire.begin());
    out.push_back({a.name, a.get, a.set, p, k});
  }
  for (const Param& p : params::command_table()) {
    for (const std::string& w : p.wire) {
      if (std::count_if(out.begin(), out.end(), [&w](const CommandWireField& f) { return f.name == w; }) != 1)
        throw std::logic_error(p.key + ": ShapeCommand field '" + w +
                               "' must be bound once in dds/convert_command.cpp");
    }
  }
  return out;
}

/// Component k of a table value as its ShapeCommand field carries it (polygon vertices flattened x0,
/// y0, x1, y1, ...).
struct ToWire {
  std::size_t k;
  WireValue operator()(double v) const { return v; }
  WireValue operator()(bool v) const { return v; }
  WireValue operator()(const std::string& v) const { return v; }
  WireValue operator()(const core::Vec2& v) const { return v[static_cast<Eigen::Index>(k)]; }
  WireValue operator()(const std::vector<core::Vec2>& v) const {
    std::vector<double> flat;
    flat.reserve(2 * v.size());
    for (const core::Vec2& p : v) {
      flat.push_back(p.x());
      flat.push_back(p.y());
    }
    return flat;
  }
  /// Keep-out zones: component 0 the circles (cx, cy, r, ...), 1 the polygons (each n, x0, y0, ...).
  WireValue operator()(const std::vector<core::KeepOutZone>& zones) const {
    std::vector<double> flat;
    for (const core::KeepOutZone& z : zones) {
      const bool circle = z.kind == core::KeepOutZone::Kind::Circle;
      if (circle && k == 0) flat.insert(flat.end(), {z.centre.x(), z.centre.y(), z.radius});
      if (!circle && k == 1) {
        flat.push_back(static_cast<double>(z.vertices.size()));
        for (const core::Vec2& p : z.vertices) flat.insert(flat.end(), {p.x(), p.y()});
      }
    }
    return flat;
  }
  // Integers and text lists: no command-table entry of the wire holds one (bind_command_wire refuses it).
  template <class Other>
  WireValue operator()(const Other&) const {
    throw std::logic_error("a command table value with no ShapeCommand form");
  }
};

/// The problems of one received command, "command.<field>: <problem>", in the order found.
class CommandProblems {
 public:
  void add(const std::string& field, const std::string& problem) {
    list_.push_back("command." + field + ": " + problem);
  }
  /// A number: finite and within the command table's range.
  void number(const std::string& field, double v, const params::Range& range) {
    if (!std::isfinite(v))
      add(field, "must be finite, got " + util::format_g10(v));
    else if (!range.contains(v))
      add(field, range.text() + ", got " + util::format_g10(v));
  }
  bool empty() const { return list_.empty(); }
  std::string joined() const { return params::join(list_, "; "); }

 private:
  std::vector<std::string> list_;
};

/// A number field: a Real entry, or one component of a Vec2 entry.
void read_number(const CommandWireField& f, double v, core::Command& c, CommandProblems& p) {
  p.number(std::string(f.name), v, f.param->range);
  if (f.param->type != params::Type::Vec2) return f.param->set(c, params::Value(v));
  core::Vec2 xy = std::get<core::Vec2>(f.param->get(c));
  xy[static_cast<Eigen::Index>(f.component)] = v;
  f.param->set(c, params::Value(xy));
}

/// A name field (a Choice entry): one of its choices, else "unknown shape \"x\" (line|circle|...)",
/// the noun being the field's name without "_kind".
void read_choice(const CommandWireField& f, std::string name, core::Command& c, CommandProblems& p) {
  const std::vector<std::string>& choices = f.param->choices;
  if (std::find(choices.begin(), choices.end(), name) != choices.end())
    return f.param->set(c, params::Value(std::move(name)));
  std::string_view noun = f.name;
  if (noun.size() > 5 && noun.substr(noun.size() - 5) == "_kind") noun.remove_suffix(5);
  p.add(std::string(f.name), "unknown " + std::string(noun) + " \"" + util::excerpt(name) + "\" (" +
                                 params::join(choices, "|") + ")");
}

/// The polygon's vertices, flattened x0, y0, x1, y1, ...: pairs of numbers within the entry's range.
void read_vertices(const CommandWireField& f, const std::vector<double>& flat, core::Command& c,
                   CommandProblems& p) {
  const std::string name(f.name);
  if (flat.size() % 2 != 0)
    return p.add(name,
                 "must hold x, y pairs (an even count), got " + std::to_string(flat.size()) + " numbers");
  std::vector<core::Vec2> vertices;
  vertices.reserve(flat.size() / 2);
  for (std::size_t i = 0; i < flat.size(); ++i)
    p.number(name + "[" + std::to_string(i) + "]", flat[i], f.param->range);
  for (std::size_t i = 0; i + 1 < flat.size(); i += 2) vertices.emplace_back(flat[i], flat[i + 1]);
  f.param->set(c, params::Value(std::move(vertices)));
}

/// Keep-out zones: the circles (component 0: cx, cy, r triples) or the polygons (component 1: each its
/// vertex count, then its x, y pairs); each zone checked by core::keep_out_problems. The zones of the
/// other component are kept (circles come first).
void read_zones(const CommandWireField& f, const std::vector<double>& flat, core::Command& c, CommandProblems& p) {
  const std::string name(f.name);
  const auto at = [&name](std::size_t i) { return name + "[" + std::to_string(i) + "]"; };
  std::vector<core::KeepOutZone> zones;
  bool ok = true;
  if (f.component == 0) {
    if (flat.size() % 3 != 0)
      return p.add(name, "must hold cx, cy, r triples (a count divisible by 3), got " + std::to_string(flat.size()) +
                             " numbers");
    for (std::size_t i = 0; i < flat.size(); ++i) {
      const bool radius = i % 3 == 2;
      if (!std::isfinite(flat[i]) || (radius && !(flat[i] > 0.0))) {
        p.add(at(i), std::string(std::isfinite(flat[i]) ? "radius must be > 0" : "must be finite") + ", got " +
                         util::format_g10(flat[i]));
        ok = false;
      }
    }
    for (std::size_t i = 0; ok && i + 2 < flat.size(); i += 3) {
      core::KeepOutZone z;
      z.centre = core::Vec2(flat[i], flat[i + 1]);
      z.radius = flat[i + 2];
      zones.push_back(z);
    }
  } else {
    for (std::size_t i = 0; i < flat.size();) {
      const double n = flat[i];
      if (!(n >= 3.0 && n == std::floor(n) && n <= static_cast<double>((flat.size() - i - 1) / 2)))
        return p.add(at(i), "must be a polygon's vertex count (an integer >= 3, its 2 n numbers following), got " +
                                util::format_g10(n));
      core::KeepOutZone z;
      z.kind = core::KeepOutZone::Kind::Polygon;
      const std::size_t count = static_cast<std::size_t>(n);
      for (std::size_t v = 0; v < count; ++v) {
        const std::size_t ix = i + 1 + 2 * v;
        for (std::size_t k = ix; k < ix + 2; ++k)
          if (!std::isfinite(flat[k])) {
            p.add(at(k), "must be finite, got " + util::format_g10(flat[k]));
            ok = false;
          }
        z.vertices.emplace_back(flat[ix], flat[ix + 1]);
      }
      if (ok)
        for (const std::string& problem : core::keep_out_problems(z)) {
          p.add(at(i), problem);
          ok = false;
        }
      zones.push_back(std::move(z));
      i += 1 + 2 * count;
    }
  }
  if (!ok) return;
  std::vector<core::KeepOutZone> all = std::get<std::vector<core::KeepOutZone>>(f.param->get(c));
  const auto kind = f.component == 0 ? core::KeepOutZone::Kind::Circle : core::KeepOutZone::Kind::Polygon;
  all.erase(std::remove_if(all.begin(), all.end(), [kind](const core::KeepOutZone& z) { return z.kind == kind; }),
            all.end());
  all.insert(f.component == 0 ? all.begin() : all.end(), zones.begin(), zones.end());
  f.param->set(c, params::Value(std::move(all)));
}

/// One received field into c, its problems into p.
void read_field(const CommandWireField& f, WireValue v, core::Command& c, CommandProblems& p) {
  switch (f.param->type) {
    case params::Type::Real:
    case params::Type::Vec2:
      return read_number(f, std::get<double>(v), c, p);
    case params::Type::Choice:
      return read_choice(f, std::move(std::get<std::string>(v)), c, p);
    case params::Type::Vec2List:
      return read_vertices(f, std::get<std::vector<double>>(v), c, p);
    case params::Type::ZoneList:
      return read_zones(f, std::get<std::vector<double>>(v), c, p);
    case params::Type::Bool:
      return f.param->set(c, params::Value(std::get<bool>(v)));
    default:  // Text: any text (a shape's expression is checked when the shape is compiled)
      return f.param->set(c, params::Value(std::move(std::get<std::string>(v))));
  }
}

}  // namespace

const std::vector<CommandWireField>& command_wire() {
  static const std::vector<CommandWireField> fields = bind_command_wire();
  return fields;
}

msg::ShapeCommand to_msg(const core::Command& cmd, const CommandId& id, const std::string& issuer_name) {
  msg::ShapeCommand m;
  m.epoch(id.epoch);
  m.issuer(id.issuer.prefix);
  m.issuer_name(issuer_name);
  for (const CommandWireField& f : command_wire())
    f.set(m, std::visit(ToWire{f.component}, f.param->get(cmd)));
  return m;
}

bool from_msg(const msg::ShapeCommand& m, core::CompiledCommand& out, std::string& error) {
  CommandProblems p;
  core::Command c;
  for (const CommandWireField& f : command_wire()) read_field(f, f.get(m), c, p);
  if (!p.empty()) {
    error = p.joined();
    return false;
  }
  // Only a well-formed command is compiled: a shape that cannot be built is refused as a whole.
  core::CompiledCommand compiled;
  try {
    compiled = shapes::compile(c);
  } catch (const core::ShapeError& e) {
    error = "command: " + util::excerpt(e.what(), util::kLineMax);  // it quotes the received expression
    return false;
  }
  // A command that could carry the swarm out of its workspace is refused as a whole, too.
  for (const core::EnvelopeProblem& e : core::envelope_problems(compiled)) p.add(e.wire, e.text);
  if (!p.empty()) {
    error = p.joined();
    return false;
  }
  out = std::move(compiled);
  return true;
}

bool from_msg(const msg::ShapeCommand& m, const SourceId& source, CommandSample& out, std::string& error) {
  core::CompiledCommand cmd;
  const bool ok = from_msg(m, cmd, error);
  if (m.epoch() == 0) error = "command.epoch: must be >= 1, got 0" + (ok ? std::string() : "; " + error);
  if (!ok || m.epoch() == 0) return false;
  out.command = std::move(cmd);
  out.id.epoch = m.epoch();
  out.id.issuer.prefix = m.issuer();
  if (!out.id.issuer.known()) out.id.issuer = source;
  out.issuer_name.clear();
  for (const char ch : m.issuer_name().substr(0, kIssuerNameMax))
    out.issuer_name += (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f) ? '?' : ch;
  return true;
}

}  // namespace shapeform::dds
