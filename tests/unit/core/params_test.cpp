// The declared parameter table: ranges and their texts, the enum name tables, the command table.
#include "core/command_table.hpp"
#include "core/enum_names.hpp"
#include "core/params.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

namespace core = shapeform::core;
namespace params = shapeform::core::params;

TEST_CASE("a range's texts name its bounds", "[params]") {
  CHECK(params::above(0).text() == "must be > 0");
  CHECK(params::at_least(1).text() == "must be >= 1");
  CHECK(params::above_up_to(0, 10).text() == "must be in (0, 10]");
  CHECK(params::integers(1, 1000).text() == "must be in 1..1000");
  CHECK(params::integers(1, 1).text() == "must be 1");
  CHECK(params::any().text().empty());
  // The console names the side that is broken.
  CHECK(params::above_up_to(0, 10).text_for(0) == "must be > 0");
  CHECK(params::above_up_to(0, 10).text_for(10.5) == "must be <= 10");
  CHECK(params::above(0).text_for(-1) == "must be > 0");
  CHECK(params::above_up_to(0, 10).doc() == "`(0, 10]`");
  CHECK(params::at_least(0).doc() == "`>= 0`");
  CHECK(params::any().doc() == "finite");
  CHECK(params::integers(0, 232).doc() == "`0..232`");
}

TEST_CASE("a range contains exactly its values", "[params]") {
  const params::Range r = params::above_up_to(0, 10);
  CHECK_FALSE(r.contains(0));
  CHECK(r.contains(1e-300));
  CHECK(r.contains(10));
  CHECK_FALSE(r.contains(std::nextafter(10.0, 11.0)));
  CHECK(params::at_least(0).contains(0));
  CHECK_FALSE(params::at_least(0).contains(-1e-300));
  CHECK(params::any().contains(-1e300));
}

namespace {
/// Every name of `table` round-trips through core's to_string and `parse`.
template <class E, std::size_t N, class Parse>
void check_names(const params::Name<E> (&table)[N], Parse parse) {
  for (const auto& n : table) {
    INFO(n.name);
    CHECK(core::to_string(n.value) == n.name);
    E v{};
    REQUIRE(parse(n.name, v));
    CHECK(v == n.value);
  }
}
}  // namespace

TEST_CASE("core's to_string and parse functions use the one name table", "[params]") {
  check_names(params::kShapeKindNames, [](std::string_view s, core::ShapeKind& k) { return core::parse_shape_kind(s, k); });
  check_names(params::kPathKindNames,
              [](std::string_view s, core::CentrePath::Kind& k) { return core::parse_path_kind(s, k); });
  check_names(params::kIntegratorNames, [](std::string_view s, core::Integrator& i) { return core::parse_integrator(s, i); });
  check_names(params::kLawNames, [](std::string_view s, core::Law& l) { return core::parse_law(s, l); });
  core::Law l = core::Law::Arc;
  CHECK_FALSE(core::parse_law("Paper", l));
  CHECK(l == core::Law::Arc);  // untouched
  CHECK(params::join(params::names(params::kIntegratorNames), ", ") == "euler, rk4");
}

TEST_CASE("the command table: unique keys and wire names, defaults from the struct", "[params]") {
  std::set<std::string> keys, wires;
  for (const auto& p : params::command_table()) {
    INFO(p.key);
    CHECK(keys.insert(p.key).second);
    CHECK_FALSE(p.wire.empty());
    // a pair (x, y) and the keep-out zones (circles, polygons) travel as two fields
    CHECK(p.wire.size() == (p.type == params::Type::Vec2 || p.type == params::Type::ZoneList ? 2u : 1u));
    for (const auto& w : p.wire) CHECK(wires.insert(w).second);
    CHECK_FALSE(p.doc.empty());
    CHECK(params::find_key(p.key) == &p);
    CHECK(params::find_wire(p.wire.front()) == &p);
  }
  CHECK(params::find_key("integration.nope") == nullptr);
  CHECK(params::find_wire("nope") == nullptr);
  CHECK(params::find_wire("cy")->key == "shape.centre");

  const core::Command defaults;
  CHECK(std::get<double>(params::find_key("integration.dt")->get(defaults)) == defaults.dt);
  CHECK(std::get<std::string>(params::find_key("shape.kind")->get(defaults)) == "circle");
  CHECK(std::get<core::Vec2>(params::find_key("tracking.point")->get(defaults)) == core::Vec2::Zero());
}

TEST_CASE("the command table writes the field it names", "[params]") {
  core::Command c;
  params::find_key("dynamics.sigma")->set(c, params::Value(2.5));
  CHECK(c.gains.sigma == 2.5);
  params::find_key("dynamics.law")->set(c, params::Value(std::string("arc")));
  CHECK(c.law == core::Law::Arc);
  params::find_key("tracking.velocity")->set(c, params::Value(core::Vec2(1, -2)));
  CHECK(c.tracking.path.velocity == core::Vec2(1, -2));
  params::find_key("shape.closed")->set(c, params::Value(false));
  CHECK_FALSE(c.shape.closed);
  params::find_key("dynamics.hold")->set(c, params::Value(true));
  CHECK(c.hold);
  CHECK(params::find_wire("hold")->key == "dynamics.hold");
  // Every entry reads back what it wrote.
  core::Command other;
  for (const auto& p : params::command_table()) {
    INFO(p.key);
    p.set(other, p.get(c));
    CHECK(p.get(other) == p.get(c));
  }
}
