// Unit tests of common/dds/convert_command: the command's wire conversion, driven by the command table.
// Every case enumerates the table, so a field added to it is covered without touching this file.
#include "dds/convert_command.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/command_table.hpp"
#include "core/params.hpp"
#include "dds/convert.hpp"
#include "util/text.hpp"

namespace shapeform {
namespace {

namespace params = core::params;
using Param = params::Param<core::Command>;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// The defaults, plus expressions and vertices valid for their kinds: whichever kind an entry picks,
/// the command compiles and stays inside its envelope.
core::Command base_command() {
  core::Command c;
  c.shape.r_expr = "4 + cos(5*phi)";
  c.shape.x_expr = "3*cos(2*pi*s)";
  c.shape.y_expr = "2*sin(2*pi*s)";
  c.shape.f_expr = "x^4 + y^4 - 81";
  c.shape.vertices = {core::Vec2(-4, -3), core::Vec2(4, -3), core::Vec2(0, 5)};
  return c;
}

/// The binding of ShapeCommand field `name`.
const dds::CommandWireField& bound(const std::string& name) {
  for (const dds::CommandWireField& f : dds::command_wire())
    if (f.name == name) return f;
  throw std::logic_error("ShapeCommand field '" + name + "' is not bound");
}

/// A number other than d within r, with every mantissa bit in play where the range allows.
double other_number(double d, const params::Range& r) {
  for (const double v : {d + 1.0 / 3, d - 1.0 / 3, std::nextafter(d, kInf), std::nextafter(d, -kInf)})
    if (r.contains(v)) return v;
  throw std::logic_error("no other value in range");
}

/// Values other than v that entry p may hold (Choice: every other name).
std::vector<params::Value> non_defaults(const Param& p, const params::Value& v) {
  switch (p.type) {
    case params::Type::Real:
      return {other_number(std::get<double>(v), p.range)};
    case params::Type::Vec2: {
      const core::Vec2 xy = std::get<core::Vec2>(v);
      return {core::Vec2(other_number(xy.x(), p.range), other_number(xy.y() - 1, p.range))};
    }
    case params::Type::Bool:
      return {!std::get<bool>(v)};
    case params::Type::Text:
      return {std::get<std::string>(v) + " + 1/3"};
    case params::Type::Choice: {
      std::vector<params::Value> out;
      for (const std::string& name : p.choices)
        if (name != std::get<std::string>(v)) out.emplace_back(name);
      return out;
    }
    case params::Type::Vec2List:
      return {std::vector<core::Vec2>{core::Vec2(1.0 / 3, -2.0 / 3), core::Vec2(5.0 / 3, 1.0 / 7),
                                      core::Vec2(-1.0 / 9, 7.0 / 3)}};
    case params::Type::ZoneList: {
      core::KeepOutZone circle;
      circle.centre = core::Vec2(1.0 / 3, -2.0 / 3);
      circle.radius = 1.0 / 7;
      core::KeepOutZone polygon;
      polygon.kind = core::KeepOutZone::Kind::Polygon;
      polygon.vertices = {core::Vec2(1.0 / 3, 1.0 / 9), core::Vec2(5.0 / 3, 1.0 / 7), core::Vec2(-1.0 / 9, 7.0 / 3)};
      return {std::vector<core::KeepOutZone>{circle, circle, polygon}};  // circles first, as they travel
    }
    default:
      throw std::logic_error(p.key + ": a type this test cannot vary yet");
  }
}

/// The value as bytes: numbers bit for bit (-0 differs from 0, every NaN payload counts).
struct Bits {
  std::string operator()(double d) const {
    char b[sizeof d];
    std::memcpy(b, &d, sizeof d);
    return std::string(b, sizeof d);
  }
  std::string operator()(const core::Vec2& v) const { return (*this)(v.x()) + (*this)(v.y()); }
  std::string operator()(const std::vector<core::Vec2>& vs) const {
    std::string out;
    for (const core::Vec2& v : vs) out += (*this)(v);
    return out;
  }
  std::string operator()(const std::vector<core::KeepOutZone>& zs) const {
    std::string out;
    for (const core::KeepOutZone& z : zs)
      out += (z.kind == core::KeepOutZone::Kind::Circle ? "circle" : "polygon") + (*this)(z.centre) +
             (*this)(z.radius) + (*this)(z.vertices) + ";";
    return out;
  }
  std::string operator()(bool b) const { return b ? "true" : "false"; }
  std::string operator()(const std::string& s) const { return s; }
  template <class Other>
  std::string operator()(const Other&) const {
    throw std::logic_error("a type this test cannot compare yet");
  }
};

/// from_msg of m; the error, "" when accepted (a refused message leaves `out` untouched).
std::string receive(const msg::ShapeCommand& m, core::CompiledCommand& out) {
  out.dt = 123.0;  // sentinel
  std::string error;
  if (dds::from_msg(m, out, error)) return "";
  CHECK(out.dt == 123.0);
  return error;
}

/// The field names of the struct in an IDL file, in order.
std::vector<std::string> idl_fields(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in);
  const std::regex field(R"(^\s*[A-Za-z_][\w<>: ]*\s+([A-Za-z_]\w*)\s*(\[\d+\])?\s*;)");
  std::vector<std::string> out;
  std::smatch match;
  for (std::string line; std::getline(in, line);)
    if (std::regex_search(line, match, field)) out.push_back(match[1]);
  return out;
}

}  // namespace

TEST_CASE("the IDL's command fields, the command table's wire names and the bindings agree one to one",
          "[dds][convert][command]") {
  std::vector<std::string> bound_names = {"epoch", "issuer", "issuer_name"};  // the CommandId, by hand
  for (const dds::CommandWireField& f : dds::command_wire()) {
    INFO(f.name);
    bound_names.emplace_back(f.name);
    REQUIRE(f.component < f.param->wire.size());
    CHECK(f.param->wire[f.component] == f.name);  // the entry names the field it is bound to
  }
  CHECK(idl_fields(SHAPEFORM_SOURCE_DIR "/idl/ShapeCommand.idl") == bound_names);  // in IDL order
  std::size_t wire_names = 0;
  for (const Param& p : params::command_table()) {
    wire_names += p.wire.size();
    for (const std::string& w : p.wire) CHECK(bound(w).param == &p);
  }
  CHECK(wire_names == dds::command_wire().size());
}

TEST_CASE("every field of the command table survives to_msg -> from_msg bit for bit",
          "[dds][convert][command]") {
  const core::Command base = base_command();
  int checked = 0;
  for (const Param& p : params::command_table()) {
    for (const params::Value& v : non_defaults(p, p.get(base))) {
      INFO(p.key << " = " << std::visit(Bits{}, v));
      core::Command sent = base;
      p.set(sent, v);
      REQUIRE(std::visit(Bits{}, p.get(sent)) != std::visit(Bits{}, p.get(base)));  // really another value
      core::CompiledCommand back;
      REQUIRE(receive(dds::to_msg(sent, 1), back) == "");
      for (const Param& q : params::command_table()) {
        INFO("read back: " << q.key);
        CHECK(std::visit(Bits{}, q.get(back)) == std::visit(Bits{}, q.get(sent)));
      }
      ++checked;
    }
  }
  CHECK(checked >= static_cast<int>(params::command_table().size()));
}

TEST_CASE("every number field is refused on the wire just outside its range, NaN and inf, naming the field",
          "[dds][convert][command]") {
  const msg::ShapeCommand good = dds::to_msg(base_command(), 1);
  int checked = 0;
  for (const Param& p : params::command_table()) {
    if (p.type != params::Type::Real && p.type != params::Type::Vec2) continue;
    const params::Range& r = p.range;
    std::vector<double> refused = {kNaN, kInf, -kInf};
    if (r.lo != -kInf) refused.push_back(r.lo_open ? r.lo : std::nextafter(r.lo, -kInf));
    if (r.hi != kInf) refused.push_back(r.hi_open ? r.hi : std::nextafter(r.hi, kInf));
    for (const std::string& w : p.wire) {
      for (const double v : refused) {
        INFO(w << " = " << v);
        msg::ShapeCommand m = good;
        bound(w).set(m, dds::WireValue(v));
        core::CompiledCommand out;
        const std::string why = std::isfinite(v) ? r.text() : "must be finite";
        CHECK(receive(m, out) == "command." + w + ": " + why + ", got " + util::format_g10(v));
        ++checked;
      }
    }
  }
  CHECK(checked >= 3 * 29);  // 21 numbers and 4 pairs, NaN and both infinities each, and the range ends
}

TEST_CASE("every name field refuses an unknown name, and the vertices odd counts and non-finite numbers",
          "[dds][convert][command]") {
  const msg::ShapeCommand good = dds::to_msg(base_command(), 1);
  core::CompiledCommand out;
  int checked = 0;
  for (const Param& p : params::command_table()) {
    for (const std::string& w : p.wire) {
      INFO(w);
      msg::ShapeCommand m = good;
      const std::string field = "command." + w;
      if (p.type == params::Type::Choice) {
        bound(w).set(m, dds::WireValue(std::string("bogus")));
        const std::string error = receive(m, out);
        CHECK_THAT(error, Catch::Matchers::StartsWith(field + ": unknown ") &&
                              Catch::Matchers::EndsWith(" \"bogus\" (" + params::join(p.choices, "|") + ")"));
        ++checked;
      } else if (p.type == params::Type::Vec2List) {
        bound(w).set(m, dds::WireValue(std::vector<double>{1, 2, 3}));
        CHECK(receive(m, out) == field + ": must hold x, y pairs (an even count), got 3 numbers");
        bound(w).set(m, dds::WireValue(std::vector<double>{0, 0, 4, kNaN, 0, 4}));
        CHECK(receive(m, out) == field + "[3]: must be finite, got nan");
        ++checked;
      } else if (p.type == params::Type::ZoneList && w == "keep_out_circles") {
        bound(w).set(m, dds::WireValue(std::vector<double>{1, 2, 3, 4}));
        CHECK(receive(m, out) == field + ": must hold cx, cy, r triples (a count divisible by 3), got 4 numbers");
        bound(w).set(m, dds::WireValue(std::vector<double>{0, 0, -1}));
        CHECK(receive(m, out) == field + "[2]: radius must be > 0, got -1");
        bound(w).set(m, dds::WireValue(std::vector<double>{0, kInf, 1}));
        CHECK(receive(m, out) == field + "[1]: must be finite, got inf");
        ++checked;
      } else if (p.type == params::Type::ZoneList) {
        bound(w).set(m, dds::WireValue(std::vector<double>{2, 0, 0, 1, 1}));
        CHECK(receive(m, out) == field +
                                     "[0]: must be a polygon's vertex count (an integer >= 3, its 2 n numbers "
                                     "following), got 2");
        bound(w).set(m, dds::WireValue(std::vector<double>{3, 0, 0, 1, 0}));
        CHECK_THAT(receive(m, out), Catch::Matchers::StartsWith(field + "[0]: must be a polygon's vertex count"));
        bound(w).set(m, dds::WireValue(std::vector<double>{3, 0, 0, 1, 0, 0, kNaN}));
        CHECK(receive(m, out) == field + "[6]: must be finite, got nan");
        bound(w).set(m, dds::WireValue(std::vector<double>{4, 0, 0, 1, 1, 1, 0, 0, 1}));
        CHECK(receive(m, out) == field + "[0]: polygon edges 0 and 2 cross (the polygon must be simple)");
        ++checked;
      }
    }
  }
  CHECK(checked >= 7);  // shape_kind, path_kind, law, integrator, vertices, keep_out_circles and _polygons
}

}  // namespace shapeform

namespace shapeform {

TEST_CASE(
    "a received fence is taken when usable, else refused with the reason (not convex, not simple, outside "
    "the workspace)",
    "[dds][convert][command]") {
  msg::ShapeCommand m = dds::to_msg(base_command(), 1);
  core::CompiledCommand out;
  m.fence({-5, -5, 5, -5, 0, 5});
  m.fence_margin(0.5);
  m.breach_action("return");
  REQUIRE(receive(m, out) == "");
  CHECK(out.fence == std::vector<core::Vec2>{core::Vec2(-5, -5), core::Vec2(5, -5), core::Vec2(0, 5)});
  CHECK(out.fence_margin == 0.5);
  CHECK(out.breach_action == core::BreachAction::Return);
  m.fence({});  // the workspace box
  REQUIRE(receive(m, out) == "");
  CHECK(out.fence.empty());
  m.fence({0, 0, 4, 0, 4, 1, 1, 1, 1, 4, 0, 4});
  CHECK(receive(m, out) ==
        "command.fence: safety.fence = [[0, 0], [4, 0], [4, 1], [1, 1], [1, 4], [0, 4]]: a fence must be "
        "convex (it "
        "turns back at vertex 3); cut the rest out with safety.keep_out");
  m.fence({0, 0, 1, 1, 1, 0, 0, 1});
  CHECK(receive(m, out) ==
        "command.fence: safety.fence = [[0, 0], [1, 1], [1, 0], [0, 1]]: fence edges 0 and 2 cross (the "
        "fence must "
        "be simple)");
  m.fence({0, 0, 2000, 0, 0, 1});
  CHECK(receive(m, out) ==
        "command.fence: safety.fence = [[0, 0], [2000, 0], [0, 1]]: fence vertex 1 (2000, 0) is outside the "
        "workspace [-w, w]^2 (safety.workspace = 1000): move it in or widen safety.workspace");
  m.fence({0, 0, 1, 0});
  CHECK(receive(m, out) ==
        "command.fence: safety.fence = [[0, 0], [1, 0]]: fence needs >= 3 vertices, got 2");
  m.fence({});
  m.fence_margin(-1);
  CHECK(receive(m, out) == "command.fence_margin: must be >= 0, got -1");
  m.fence_margin(0);
  m.breach_action("land");
  CHECK(receive(m, out) == "command.breach_action: unknown breach_action \"land\" (hold|stop|return)");
}

}  // namespace shapeform
