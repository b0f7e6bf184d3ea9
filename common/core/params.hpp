#pragma once
/// The declared parameter table, in the manner of PX4's parameter definitions: each parameter is
/// declared once, with its key, type, unit, range and description, beside an accessor to the field
/// that holds it. Its default is NOT repeated here: it is read from a default-constructed struct, so
/// the struct initialisers stay the one place of a default. The config loader, its YAML emitter,
/// config/README.md's key tables, the command receiver's validation (dds::from_msg) and the
/// console's parameter bounds are all driven by these tables.
///
/// Also here: the name-table machinery of enumerations (the tables are in enum_names.hpp) and the one
/// degrees -> radians constant. The command's table is command_table.hpp. Pure: standard library and
/// Eigen only.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "types.hpp"

namespace shapeform::core::params {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Radians per degree: the one conversion of shape.rotation_deg (config) and rot= (console), so the
/// same degrees give the same bits everywhere.
inline constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;
inline double radians(double degrees) { return degrees * kRadPerDeg; }

/// Shortest text that reads back to exactly v ("10", "0.5", "2.5e-07"); ".nan", ".inf", "-.inf"
/// (YAML's spellings) for non-finite values.
std::string format_number(double v);

// ---------------------------------------------------------------------------------------------
// Ranges.

/// The accepted values of a number: an interval whose ends may be open, closed or infinite.
struct Range {
  double lo = -kInf;
  bool lo_open = false;
  double hi = kInf;
  bool hi_open = false;
  bool integer = false;  ///< an integer key: both ends closed, written "1..1000"

  bool contains(double v) const { return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi); }
  bool bounded() const { return lo != -kInf || hi != kInf; }
  /// "must be > 0", "must be >= 1", "must be <= 10", "must be in (0, 10]", "must be in 1..1000",
  /// "must be 1" (an integer range of one value); "" when unbounded.
  std::string text() const;
  /// The bound v breaks, alone: "must be > 0" or "must be <= 10" for (0, 10] (the console's
  /// messages name the side); text() when v is inside or the range has one end.
  std::string text_for(double v) const;
  /// The bounds alone: "> 0", "(0, 10]", "1..1000", "1"; "" when unbounded.
  std::string bounds() const;
  /// For the docs: "`> 0`", "`(0, 10]`", "`1..1000`", "`1`"; "finite" when unbounded.
  std::string doc() const;
};

/// Any finite value.
inline constexpr Range any() { return {}; }
/// (lo, inf).
inline constexpr Range above(double lo) { return {lo, true, kInf, false, false}; }
/// [lo, inf).
inline constexpr Range at_least(double lo) { return {lo, false, kInf, false, false}; }
/// (lo, hi].
inline constexpr Range above_up_to(double lo, double hi) { return {lo, true, hi, false, false}; }
/// Integers lo..hi, both included.
inline constexpr Range integers(double lo, double hi) { return {lo, false, hi, false, true}; }

// ---------------------------------------------------------------------------------------------
// Enumeration names: Name<E> tables (enum_names.hpp holds one per enumeration).

template <class E>
struct Name {
  E value;
  std::string_view name;
};

/// The name of v in table, "?" when absent.
template <class E, std::size_t N>
constexpr std::string_view name_of(const Name<E> (&table)[N], E v) {
  for (const auto& entry : table)
    if (entry.value == v) return entry.name;
  return "?";
}

/// The value named s; false (out untouched) when s is not in table. Case-sensitive.
template <class E, std::size_t N>
bool parse_name(const Name<E> (&table)[N], std::string_view s, E& out) {
  for (const auto& entry : table) {
    if (entry.name == s) {
      out = entry.value;
      return true;
    }
  }
  return false;
}

/// Every name of table, in order.
template <class E, std::size_t N>
std::vector<std::string> names(const Name<E> (&table)[N]) {
  std::vector<std::string> out;
  for (const auto& entry : table) out.emplace_back(entry.name);
  return out;
}

/// items joined by sep ("line, circle").
std::string join(const std::vector<std::string>& items, std::string_view sep);

// ---------------------------------------------------------------------------------------------
// Parameters.

/// What a parameter holds (and how the config file spells it).
enum class Type {
  Real,      ///< a finite number
  Integer,   ///< an integer (within range)
  UInt64,    ///< an integer 0..2^64-1
  Bool,      ///< true or false
  Choice,    ///< one of `choices` (stored as the name)
  Text,      ///< free text
  Vec2,      ///< [x1, x2]
  Vec2List,  ///< [[x, y], ...]
  TextList,  ///< [a, b, ...]
  ZoneList   ///< keep-out zones: [{circle: [cx, cy, r]}, {polygon: [[x, y], ...]}, ...]
};

/// The type as the docs name it ("number", "integer", "flag", ...).
std::string_view type_name(Type t);

/// A parameter's value, whatever its type (Choice: the name).
using Value = std::variant<double, long long, std::uint64_t, bool, std::string, Vec2, std::vector<Vec2>,
                           std::vector<std::string>, std::vector<KeepOutZone>>;

/// One declared parameter of the struct T.
template <class T>
struct Param {
  std::string key;  ///< dotted config key, e.g. "dynamics.k1"
  Type type = Type::Real;
  std::string unit;                  ///< "" when it has none
  Range range;                       ///< Real / Integer: the accepted values
  std::vector<std::string> choices;  ///< Choice: the accepted names, in order
  std::string doc;                   ///< what it means (the docs' description)
  std::string range_note;            ///< docs only: rules beyond `range`, appended to its text
  std::vector<std::string> wire;     ///< ShapeCommand field names (Vec2: x, y); empty: not on the wire
  bool degrees = false;              ///< Real stored in radians, written in degrees (rotation_deg)
  std::function<Value(const T&)> get;
  std::function<void(T&, const Value&)> set;  ///< v holds this type's alternative (a checked value)
};

/// The same parameter read through member(outer), a reference to the T inside Outer.
template <class Outer, class T, class Member>
Param<Outer> lift(const Param<T>& p, Member member) {
  Param<Outer> out;
  out.key = p.key;
  out.type = p.type;
  out.unit = p.unit;
  out.range = p.range;
  out.choices = p.choices;
  out.doc = p.doc;
  out.range_note = p.range_note;
  out.wire = p.wire;
  out.degrees = p.degrees;
  out.get = [get = p.get, member](const Outer& o) { return get(member(o)); };
  out.set = [set = p.set, member](Outer& o, const Value& v) { set(member(o), v); };
  return out;
}

/// Binds a parameter to the field `field(t)` returns (a generic lambda `[](auto& t) -> auto& {...}`)
/// stored as V (double, long long, bool, std::string, ...), the field's own type being F.
template <class T, class V, class Field>
void bind(Param<T>& p, Field field) {
  p.get = [field](const T& t) { return Value(static_cast<V>(field(t))); };
  p.set = [field](T& t, const Value& v) {
    using F = std::decay_t<decltype(field(t))>;
    field(t) = static_cast<F>(std::get<V>(v));
  };
}

/// A parameter of T stored as V in the field `field(t)` returns: the one constructor every table uses.
template <class T, class V, class Field>
Param<T> make(Type type, std::string key, std::string unit, Range range, std::string doc, Field field,
              std::string range_note = {}, std::vector<std::string> wire = {}) {
  Param<T> p;
  p.key = std::move(key);
  p.type = type;
  p.unit = std::move(unit);
  p.range = range;
  p.doc = std::move(doc);
  p.range_note = std::move(range_note);
  p.wire = std::move(wire);
  bind<T, V>(p, field);
  return p;
}

/// Binds a Choice parameter to an enumeration field through its name table.
template <class T, class E, std::size_t N, class Field>
void bind_choice(Param<T>& p, const Name<E> (&table)[N], Field field) {
  p.choices = names(table);
  p.get = [&table, field](const T& t) { return Value(std::string(name_of(table, field(t)))); };
  p.set = [&table, field](T& t, const Value& v) { parse_name(table, std::get<std::string>(v), field(t)); };
}

/// A Choice parameter of T, the enumeration field `field(t)` spelled by its name table.
template <class T, class E, std::size_t N, class Field>
Param<T> make_choice(std::string key, std::string doc, const Name<E> (&table)[N], Field field) {
  Param<T> p;
  p.key = std::move(key);
  p.type = Type::Choice;
  p.doc = std::move(doc);
  bind_choice(p, table, field);
  return p;
}

}  // namespace shapeform::core::params
