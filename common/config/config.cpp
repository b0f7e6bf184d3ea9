/// The one config loader: YAML text -> (overrides) -> checked conversion -> Config.
/// Conversion and validation happen in one walk over the tree so every problem can name its key
/// path and line; the walk collects problems instead of stopping at the first.
#include "config/config.hpp"

#include <yaml-cpp/yaml.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include "core/command_table.hpp"
#include "core/envelope.hpp"
#include "core/safety.hpp"
#include "shapes/shapes.hpp"
#include "util/text.hpp"

namespace shapeform::config {

namespace {

using Problems = std::vector<std::string>;

constexpr double kInf = std::numeric_limits<double>::infinity();

namespace params = core::params;
using params::Type;
using Param = params::Param<Config>;

// ---------------------------------------------------------------------------------------------
// The schema's key names per section ("" = top level), from the config table. Used for unknown-key
// checks and to check --set paths before they touch the tree.

std::pair<std::string, std::string> split_key(const std::string& dotted) {
  const auto dot = dotted.rfind('.');
  if (dot == std::string::npos) return {"", dotted};
  return {dotted.substr(0, dot), dotted.substr(dot + 1)};
}

const std::map<std::string, std::vector<std::string>>& schema_sections() {
  static const std::map<std::string, std::vector<std::string>> sections = [] {
    std::map<std::string, std::vector<std::string>> out;
    auto add = [&out](const std::string& section, const std::string& name) {
      auto& names = out[section];
      if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
    };
    for (const Param& p : config_table()) {
      // Every ancestor section is a key of its parent: "supervisor.converge.hold" gives
      // "" -> supervisor, supervisor -> converge, supervisor.converge -> hold.
      for (std::string path = p.key;;) {
        const auto [parent, leaf] = split_key(path);
        add(parent, leaf);
        if (parent.empty()) break;
        path = parent;
      }
    }
    return out;
  }();
  return sections;
}

std::string join_path(const std::string& section, std::string_view key) {
  return section.empty() ? std::string(key) : section + "." + std::string(key);
}

bool schema_has(const std::string& dotted) {
  const auto [parent, leaf] = split_key(dotted);
  const auto it = schema_sections().find(parent);
  if (it == schema_sections().end()) return false;
  return std::find(it->second.begin(), it->second.end(), leaf) != it->second.end();
}

// ---------------------------------------------------------------------------------------------
// Scalars. Numbers follow the YAML 1.2 core schema; quoted scalars are strings, never numbers.

bool is_quoted(const YAML::Node& n) { return n.Tag() == "!" || n.Tag() == "tag:yaml.org,2002:str"; }

bool is_bool_word(std::string_view s) {
  return s == "true" || s == "True" || s == "TRUE" || s == "false" || s == "False" || s == "FALSE";
}

bool is_digit(char ch) { return ch >= '0' && ch <= '9'; }

/// [-+]? (.[0-9]+ | [0-9]+(.[0-9]*)?) ([eE][-+]?[0-9]+)?, or .inf/.nan spellings (non-finite).
/// Locale independent. Overflow gives +-inf, underflow 0.
bool parse_real(std::string_view s, double& out) {
  std::string_view body = s;
  bool negative = false;
  if (!body.empty() && (body[0] == '+' || body[0] == '-')) {
    negative = body[0] == '-';
    body.remove_prefix(1);
  }
  if (body == ".inf" || body == ".Inf" || body == ".INF") {
    out = negative ? -kInf : kInf;
    return true;
  }
  if (body == ".nan" || body == ".NaN" || body == ".NAN") {
    out = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  std::size_t i = 0;
  std::size_t mantissa_digits = 0;
  while (i < body.size() && is_digit(body[i])) ++i, ++mantissa_digits;
  if (i < body.size() && body[i] == '.') {
    ++i;
    while (i < body.size() && is_digit(body[i])) ++i, ++mantissa_digits;
  }
  if (mantissa_digits == 0) return false;
  bool negative_exponent = false;
  if (i < body.size() && (body[i] == 'e' || body[i] == 'E')) {
    ++i;
    if (i < body.size() && (body[i] == '+' || body[i] == '-')) negative_exponent = body[i++] == '-';
    std::size_t exponent_digits = 0;
    while (i < body.size() && is_digit(body[i])) ++i, ++exponent_digits;
    if (exponent_digits == 0) return false;
  }
  if (i != body.size()) return false;
  double v = 0.0;
  const auto [end, ec] = std::from_chars(body.data(), body.data() + body.size(), v);
  if (ec == std::errc::result_out_of_range)
    v = negative_exponent ? 0.0 : kInf;
  else if (ec != std::errc() || end != body.data() + body.size())
    return false;
  out = negative ? -v : v;
  return true;
}

enum class IntParse { NotInteger, Ok, OutOfRange };

/// [-+]?[0-9]+ into long long.
IntParse parse_integer(std::string_view s, long long& out) {
  std::string_view body = s;
  if (!body.empty() && body[0] == '+') body.remove_prefix(1);
  const std::string_view digits = !body.empty() && body[0] == '-' ? body.substr(1) : body;
  if (digits.empty() || !std::all_of(digits.begin(), digits.end(), is_digit))
    return IntParse::NotInteger;
  const auto [end, ec] = std::from_chars(body.data(), body.data() + body.size(), out);
  if (ec == std::errc::result_out_of_range) return IntParse::OutOfRange;
  return ec == std::errc() && end == body.data() + body.size() ? IntParse::Ok
                                                               : IntParse::NotInteger;
}

using params::format_number;

/// As format_number, but always reads back as a YAML float ("1.0", not "1").
std::string format_real(double v) {
  std::string s = format_number(v);
  if (std::isfinite(v) && s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

using params::kRadPerDeg;
using params::radians;

/// The degrees d that read back (radians(d)) as exactly `rad`, in the shortest spelling found near
/// rad / kRadPerDeg; so to_yaml's rotation_deg round-trips the stored radians bit for bit.
double degrees_for(double rad) {
  const double d0 = rad / kRadPerDeg;
  double best = d0;
  std::size_t best_len = std::string::npos;
  double lo = d0;
  double hi = d0;
  for (int k = 0; k < 16; ++k) {
    for (const double d : {lo, hi}) {
      const std::size_t len = format_number(d).size();
      if (radians(d) == rad && len < best_len) {
        best = d;
        best_len = len;
      }
    }
    lo = std::nextafter(lo, -kInf);
    hi = std::nextafter(hi, kInf);
  }
  return best;
}

/// A string value as a message shows it: double-quoted, at most util::kQuoteMax characters of it.
std::string quote(const std::string& s) {
  std::string escaped;  // quotes and backslashes first: excerpt's own escapes must stay single
  for (const char ch : s) {
    if (ch == '"' || ch == '\\') escaped += '\\';
    escaped += ch;
  }
  return "\"" + util::excerpt(escaped) + "\"";
}

/// How a value is shown after "got": numbers and booleans as written, strings quoted.
std::string describe(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "null";
  if (n.IsMap()) return "a map";
  if (n.IsSequence()) return "a list";
  const std::string& s = n.Scalar();
  double ignored = 0.0;
  if (!is_quoted(n) && (parse_real(s, ignored) || is_bool_word(s))) return s;
  return quote(s);
}

// ---------------------------------------------------------------------------------------------
// The walk.

/// One key of a map as found in the tree (present == false when the key is absent).
struct Entry {
  std::string path;
  YAML::Node key;
  YAML::Node value;
  bool present = false;

  /// Node whose line a problem with the value is reported at (a null value's mark is unreliable).
  const YAML::Node& anchor() const { return value.IsNull() ? key : value; }
};

class Reader {
 public:
  explicit Reader(std::vector<std::string> overridden) : overridden_(std::move(overridden)) {}

  Problems problems;

  /// "<path>: <what>, got <value> (line N)" with the line of `at` (or "(--set)").
  void bad(const std::string& path, const std::string& what, const YAML::Node& value,
           const YAML::Node& at) {
    problems.push_back(path + ": " + what + ", got " + describe(value) + where(path, at));
  }
  void bad(const Entry& e, const std::string& what) { bad(e.path, what, e.value, e.anchor()); }

  /// " (--set)" for a value that came from an override, " (line N)" for one from the file.
  std::string where(const std::string& path, const YAML::Node& at) const {
    if (from_override(path)) return " (--set)";
    if (!at.IsDefined()) return "";
    const YAML::Mark mark = at.Mark();
    return mark.is_null() ? "" : " (line " + std::to_string(mark.line + 1) + ")";
  }

  /// The first entry of `map` named key (map may be null: then nothing is present).
  Entry find(const YAML::Node& map, const std::string& section, std::string_view key) const {
    Entry e;
    e.path = join_path(section, key);
    if (!map.IsMap()) return e;
    for (auto it = map.begin(); it != map.end(); ++it) {
      if (it->first.IsScalar() && it->first.Scalar() == key) {
        e.key = it->first;
        e.value = it->second;
        e.present = true;
        break;
      }
    }
    return e;
  }

  /// Reports keys of `map` not in the schema section, duplicated, or not strings.
  void check_keys(const YAML::Node& map, const std::string& section) {
    const auto& known = schema_sections().at(section);
    std::vector<std::string> seen;
    for (auto it = map.begin(); it != map.end(); ++it) {
      if (!it->first.IsScalar()) {
        const std::string path = section.empty() ? "(top level)" : section;
        bad(path, "keys must be strings", it->first, it->first);
        continue;
      }
      const std::string& key = it->first.Scalar();
      const std::string path = join_path(section, key);
      if (std::find(known.begin(), known.end(), key) == known.end())
        problems.push_back(util::excerpt(path) + ": unknown key" + where(path, it->first));
      else if (std::find(seen.begin(), seen.end(), key) != seen.end())
        problems.push_back(path + ": duplicate key" + where(path, it->first));
      seen.push_back(key);
    }
  }

  /// The map under e (a null node when absent or empty), its keys checked.
  YAML::Node section(const Entry& e) {
    if (!e.present || e.value.IsNull()) return YAML::Node();
    if (!e.value.IsMap()) {
      bad(e, "expected a map");
      return YAML::Node();
    }
    check_keys(e.value, e.path);
    return e.value;
  }

  std::optional<double> real(const std::string& path, const YAML::Node& v, const YAML::Node& at,
                             const params::Range& bound) {
    double x = 0.0;
    if (!v.IsScalar() || is_quoted(v) || !parse_real(v.Scalar(), x)) {
      bad(path, "expected a number", v, at);
      return std::nullopt;
    }
    if (!std::isfinite(x)) {
      bad(path, "must be finite", v, at);
      return std::nullopt;
    }
    if (!bound.contains(x)) {
      bad(path, bound.text(), v, at);
      return std::nullopt;
    }
    return x;
  }
  std::optional<double> real(const Entry& e, const params::Range& bound) {
    if (!e.present) return std::nullopt;
    return real(e.path, e.value, e.anchor(), bound);
  }

  /// An integer in lo..hi (both inclusive).
  std::optional<long long> integer(const Entry& e, long long lo, long long hi) {
    if (!e.present) return std::nullopt;
    long long x = 0;
    const IntParse parsed = e.value.IsScalar() && !is_quoted(e.value)
                                ? parse_integer(e.value.Scalar(), x)
                                : IntParse::NotInteger;
    if (parsed == IntParse::NotInteger) {
      bad(e, "expected an integer");
      return std::nullopt;
    }
    if (parsed == IntParse::OutOfRange || x < lo || x > hi) {
      bad(e, lo == hi ? "must be " + std::to_string(lo)
                      : "must be in " + std::to_string(lo) + ".." + std::to_string(hi));
      return std::nullopt;
    }
    return x;
  }

  std::optional<std::uint64_t> unsigned64(const Entry& e) {
    if (!e.present) return std::nullopt;
    long long x = 0;
    const std::string& s = e.value.Scalar();
    const IntParse parsed =
        e.value.IsScalar() && !is_quoted(e.value) ? parse_integer(s, x) : IntParse::NotInteger;
    if (parsed == IntParse::NotInteger) {
      bad(e, "expected an integer");
      return std::nullopt;
    }
    if (parsed == IntParse::Ok) {
      if (x < 0) {
        bad(e, "must be >= 0");
        return std::nullopt;
      }
      return static_cast<std::uint64_t>(x);
    }
    // Beyond long long: still fine up to 2^64 - 1.
    std::uint64_t u = 0;
    const std::string_view body = !s.empty() && s[0] == '+' ? std::string_view(s).substr(1) : s;
    const auto [end, ec] = std::from_chars(body.data(), body.data() + body.size(), u);
    if (s[0] == '-' || ec != std::errc() || end != body.data() + body.size()) {
      bad(e, s[0] == '-'
                 ? "must be >= 0"
                 : "must be in 0.." + std::to_string(std::numeric_limits<std::uint64_t>::max()));
      return std::nullopt;
    }
    return u;
  }

  std::optional<bool> boolean(const Entry& e) {
    if (!e.present) return std::nullopt;
    if (e.value.IsScalar() && !is_quoted(e.value) && is_bool_word(e.value.Scalar()))
      return e.value.Scalar()[0] == 't' || e.value.Scalar()[0] == 'T';
    bad(e, "expected true or false");
    return std::nullopt;
  }

  /// Any scalar, taken as text.
  std::optional<std::string> text(const Entry& e) {
    if (!e.present) return std::nullopt;
    if (!e.value.IsScalar()) {
      bad(e, "expected a string");
      return std::nullopt;
    }
    return e.value.Scalar();
  }

  /// One of `names`, as text.
  std::optional<std::string> choice(const Entry& e, const std::vector<std::string>& names) {
    const auto s = text(e);
    if (!s) return std::nullopt;
    if (std::find(names.begin(), names.end(), *s) != names.end()) return s;
    bad(e, "must be one of " + params::join(names, ", "));
    return std::nullopt;
  }

  /// [x1, x2], both finite numbers.
  std::optional<core::Vec2> vec2(const Entry& e) {
    if (!e.present) return std::nullopt;
    if (!e.value.IsSequence() || e.value.size() != 2) {
      const std::string got =
          e.value.IsSequence() ? "a list of " + std::to_string(e.value.size()) : describe(e.value);
      problems.push_back(e.path + ": expected a list of 2 numbers [x1, x2], got " + got +
                         where(e.path, e.anchor()));
      return std::nullopt;
    }
    core::Vec2 out;
    bool ok = true;
    for (std::size_t i = 0; i < 2; ++i) {
      const YAML::Node item = e.value[i];
      const auto x = real(e.path + "[" + std::to_string(i) + "]", item,
                          item.IsNull() ? e.anchor() : item, params::any());
      if (x) out[static_cast<Eigen::Index>(i)] = *x;
      ok = ok && x.has_value();
    }
    return ok ? std::optional<core::Vec2>(out) : std::nullopt;
  }

  /// A list whose items `read_item(item entry)` checks one by one (each named "key[i]"); null means
  /// empty; `what` names the list in its error ("a list of strings").
  template <class T, class ReadItem>
  std::optional<std::vector<T>> list(const Entry& e, const char* what, ReadItem read_item) {
    if (!e.present) return std::nullopt;
    if (e.value.IsNull()) return std::vector<T>{};
    if (!e.value.IsSequence()) {
      bad(e, std::string("expected ") + what);
      return std::nullopt;
    }
    std::vector<T> out;
    bool ok = true;
    for (std::size_t i = 0; i < e.value.size(); ++i) {
      Entry item;
      item.path = e.path + "[" + std::to_string(i) + "]";
      item.key.reset(e.key);
      item.value.reset(e.value[i]);  // reset, not '=': assigning a YAML::Node writes through it
      item.present = true;
      const std::optional<T> v = read_item(item);
      if (v) out.push_back(*v);
      ok = ok && v.has_value();
    }
    return ok ? std::optional<std::vector<T>>(std::move(out)) : std::nullopt;
  }

  /// A list of [x, y] pairs (each checked like vec2); null means empty.
  std::optional<std::vector<core::Vec2>> vec2_list(const Entry& e) {
    return list<core::Vec2>(e, "a list of [x, y] pairs", [this](const Entry& item) { return vec2(item); });
  }

  /// A list of keep-out zones, each {circle: [cx, cy, r]} or {polygon: [[x, y], ...]}, checked by
  /// core::keep_out_problems; null means empty. Circles come first (the order they travel in).
  std::optional<std::vector<core::KeepOutZone>> zone_list(const Entry& e) {
    const char* form = "{circle: [cx, cy, r]} or {polygon: [[x, y], ...]}";
    auto zones = list<core::KeepOutZone>(
        e, "a list of zones", [this, form](const Entry& item) -> std::optional<core::KeepOutZone> {
          const YAML::Node& v = item.value;
          if (!v.IsMap() || v.size() != 1 || !v.begin()->first.IsScalar()) {
            bad(item, std::string("expected ") + form);
            return std::nullopt;
          }
          const std::string kind = v.begin()->first.Scalar();
          Entry body;
          body.path = item.path + "." + kind;
          body.key.reset(v.begin()->first);
          body.value.reset(v.begin()->second);
          body.present = true;
          core::KeepOutZone z;
          if (kind == "circle") {
            if (!body.value.IsSequence() || body.value.size() != 3) {
              bad(body, "expected [cx, cy, r] (centre and radius)");
              return std::nullopt;
            }
            double n[3] = {0, 0, 0};
            bool ok = true;
            for (std::size_t i = 0; i < 3; ++i) {
              const YAML::Node at = body.value[i];
              const auto x = real(body.path + "[" + std::to_string(i) + "]", at, at.IsNull() ? body.anchor() : at,
                                  i == 2 ? params::above(0) : params::any());
              if (x) n[i] = *x;
              ok = ok && x.has_value();
            }
            if (!ok) return std::nullopt;
            z.centre = core::Vec2(n[0], n[1]);
            z.radius = n[2];
          } else if (kind == "polygon") {
            const auto vs = vec2_list(body);
            if (!vs) return std::nullopt;
            z.kind = core::KeepOutZone::Kind::Polygon;
            z.vertices = *vs;
          } else {
            bad(item.path, std::string("unknown zone ") + quote(kind) + ", expected " + form, body.key, body.key);
            return std::nullopt;
          }
          const auto found = core::keep_out_problems(z);
          if (!found.empty()) {
            bad(body, params::join(found, "; "));
            return std::nullopt;
          }
          return z;
        });
    if (zones)
      std::stable_partition(zones->begin(), zones->end(),
                            [](const core::KeepOutZone& z) { return z.kind == core::KeepOutZone::Kind::Circle; });
    return zones;
  }

  /// A list of non-empty strings; null means empty.
  std::optional<std::vector<std::string>> text_list(const Entry& e) {
    return list<std::string>(e, "a list of strings", [this, &e](const Entry& item) -> std::optional<std::string> {
      const YAML::Node& at = item.value.IsNull() ? e.anchor() : item.value;
      if (!item.value.IsScalar()) {
        bad(item.path, "expected a string", item.value, at);
      } else if (item.value.Scalar().empty()) {
        bad(item.path, "must not be empty", item.value, at);
      } else {
        return item.value.Scalar();
      }
      return std::nullopt;
    });
  }

  /// The value of e as parameter p declares it (type, then range), or nullopt (problem reported,
  /// or e absent).
  std::optional<params::Value> value(const Entry& e, const Param& p) {
    auto wrap = [](auto v) { return v ? std::optional<params::Value>(std::move(*v)) : std::nullopt; };
    switch (p.type) {
      case Type::Real: {
        const auto v = real(e, p.range);
        if (v && p.degrees) return params::Value(radians(*v));
        return wrap(v);
      }
      case Type::Integer:
        return wrap(integer(e, static_cast<long long>(p.range.lo), static_cast<long long>(p.range.hi)));
      case Type::UInt64: return wrap(unsigned64(e));
      case Type::Bool: return wrap(boolean(e));
      case Type::Choice: return wrap(choice(e, p.choices));
      case Type::Text: return wrap(text(e));
      case Type::Vec2: return wrap(vec2(e));
      case Type::Vec2List: return wrap(vec2_list(e));
      case Type::TextList: return wrap(text_list(e));
      case Type::ZoneList: return wrap(zone_list(e));
    }
    return std::nullopt;
  }

 private:
  bool from_override(const std::string& path) const {
    for (const auto& o : overridden_) {
      if (path == o) return true;
      if (path.size() > o.size() && path.compare(0, o.size(), o) == 0 &&
          (path[o.size()] == '.' || path[o.size()] == '['))
        return true;
    }
    return false;
  }

  std::vector<std::string> overridden_;
};

/// Applies "dotted.key=value" overrides to root in order. Returns the paths set; bad overrides
/// are reported in problems and skipped.
std::vector<std::string> apply_overrides(YAML::Node& root,
                                         const std::vector<std::string>& overrides,
                                         Problems& problems) {
  std::vector<std::string> applied;
  for (const auto& item : overrides) {
    const auto eq = item.find('=');
    const std::string key = eq == std::string::npos ? "" : util::trim(item.substr(0, eq));
    if (key.empty()) {
      problems.push_back("--set " + util::excerpt(item) + ": expected dotted.key=value");
      continue;
    }
    if (!schema_has(key)) {
      problems.push_back("--set " + util::excerpt(item) + ": unknown key " + util::excerpt(key));
      continue;
    }
    YAML::Node value;
    try {
      value = YAML::Load(item.substr(eq + 1));
    } catch (const YAML::Exception& ex) {
      problems.push_back("--set " + util::excerpt(item) + ": YAML syntax error: " + util::excerpt(ex.msg));
      continue;
    }
    // Walk down to the parent map, creating missing (or null) sections.
    YAML::Node node = root;
    std::string::size_type begin = 0;
    bool reachable = true;
    for (auto dot = key.find('.'); dot != std::string::npos; dot = key.find('.', begin)) {
      const std::string segment = key.substr(begin, dot - begin);
      if (!node[segment].IsDefined() || node[segment].IsNull()) {
        node.remove(segment);  // fresh node: never write through a node an alias shares
        node[segment] = YAML::Node(YAML::NodeType::Map);
      }
      YAML::Node child = node[segment];
      if (!child.IsMap()) {  // the file's own value is wrong; the walk reports it
        reachable = false;
        break;
      }
      node.reset(child);
      begin = dot + 1;
    }
    if (!reachable) continue;
    const std::string leaf = key.substr(begin);
    node.remove(leaf);
    node[leaf] = value;
    applied.push_back(key);
  }
  return applied;
}

/// Where the shape's own keys were found, so a compile problem can name the key and its line.
struct ShapeKeys {
  Entry r_expr, x_expr, y_expr, f_expr, vertices;
};

/// shapes::compile on the converted command; a ShapeError becomes one problem naming the key that
/// holds the faulty expression (shape.r_expr, shape.x_expr / shape.y_expr, shape.f_expr) or
/// shape.vertices for polygons.
void compile_shape(core::CompiledCommand& cmd, const ShapeKeys& keys, Reader& rd) {
  try {
    cmd = shapes::compile(cmd);
  } catch (const core::ShapeError& ex) {
    const std::string what = ex.what();
    const Entry* e = nullptr;
    switch (cmd.shape.kind) {
      case core::ShapeKind::Polar: e = &keys.r_expr; break;
      case core::ShapeKind::Parametric:
        e = what.find("y(s)") != std::string::npos ? &keys.y_expr : &keys.x_expr;
        break;
      case core::ShapeKind::Implicit: e = &keys.f_expr; break;
      case core::ShapeKind::Polygon: e = &keys.vertices; break;
      default: break;
    }
    if (e == nullptr)
      rd.problems.push_back("shape: " + what);
    else
      rd.problems.push_back(e->path + ": " + what + rd.where(e->path, e->anchor()));
  }
}

/// The transport's problems (dds::transport_problems, the one validator) at the keys and lines they
/// came from; a problem of a key already reported, or about one, is not repeated.
void check_transport(const dds::TransportConfig& tr, const std::map<std::string, Entry>& found,
                     const std::set<std::string>& reported, Reader& rd) {
  for (const dds::TransportProblem& p : dds::transport_problems(tr)) {
    if (reported.count(p.key) != 0 || (!p.related.empty() && reported.count(p.related) != 0)) continue;
    const Entry& e = found.at(p.key);
    if (p.key == "transport.announce_s" && !e.present) {
      // Only the lease was given: it is the key that is wrong.
      rd.bad(found.at("transport.lease_s"),
             "must be > transport.announce_s (" + format_number(tr.announce_s) + ")");
    } else if (e.present) {
      rd.bad(e, p.what);
    } else {
      rd.problems.push_back(p.key + ": " + p.what + ", got " + p.got);
    }
  }
}

/// Whether a ROS 2 name part is made of letters, digits, '_' and '/' (with `{id}` where allowed).
bool ros_name_ok(std::string name, bool with_id) {
  if (with_id)
    for (auto at = name.find("{id}"); at != std::string::npos; at = name.find("{id}")) name.replace(at, 4, "0");
  if (name.empty() || name.back() == '/') return false;
  for (const char ch : name)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '/')) return false;
  return name.find("//") == std::string::npos;
}

/// The vehicle interface's keys as a whole (config/README.md, docs/ROBOTS.md): the names, and what
/// driving a robot over ROS 2 needs of the other keys.
void check_vehicle(const Config& c, const std::map<std::string, Entry>& found, const std::set<std::string>& reported,
                   Reader& rd) {
  // `what` without the value: a key given in the file or by --set is quoted as given, with where; a
  // default one with `got` (as check_transport does).
  const auto bad = [&](const std::string& key, const std::string& what, const std::string& got) {
    if (reported.count(key) != 0) return;
    const Entry& e = found.at(key);
    if (e.present)
      rd.bad(e, what);
    else
      rd.problems.push_back(key + ": " + what + ", got " + got);
  };
  const VehicleLink& v = c.vehicle_link;
  if (!ros_name_ok(v.ns, true) || v.ns.find("{id}") == std::string::npos)
    bad("vehicle.namespace",
        "must be letters, digits, '_' and '/' with {id} (each agent drives its own robot: "
        "robot_{id})",
        quote(v.ns));
  for (const auto& [key, name] : {std::pair<const char*, const std::string&>{"vehicle.cmd_topic", v.cmd_topic},
                                  {"vehicle.pose_topic", v.pose_topic}}) {
    const std::string relative = !name.empty() && name.front() == '/' ? name.substr(1) : name;
    if (!ros_name_ok(relative, true))
      bad(key, "must be a ROS 2 topic name (letters, digits, '_' and '/', {id} for the agent's id)", quote(name));
  }
  if (v.frame.empty()) bad("vehicle.frame", "must name the swarm's frame (map, world, ...)", quote(v.frame));
  if (c.vehicle_sim.child_frame.empty())
    bad("vehicle_sim.child_frame", "must name the robot's frame", quote(c.vehicle_sim.child_frame));
  if (!v.ros2()) return;
  if (c.vehicle.max_speed <= 0.0)
    bad("vehicle.max_speed",
        "must be > 0 with vehicle.interface: ros2 (a robot has a top speed: commands are "
        "held to it and a pose that moves faster is refused)",
        format_number(c.vehicle.max_speed));
  if (c.agent.lockstep)
    bad("agent.sync",
        "must be free with vehicle.interface: ros2 (a robot moves in real time: it cannot wait "
        "for its neighbours' steps)",
        "\"lockstep\"");
  if (c.transport.static_edp)
    bad("transport.static_edp",
        "must be false with vehicle.interface: ros2 (a ROS 2 robot announces its "
        "topics by simple discovery)",
        "true");
}

/// The checked conversion of a (map) tree: every key of the config table, in order.
Config convert(const YAML::Node& root, bool version_required, Reader& rd) {
  Config c;
  rd.check_keys(root, "");

  // The map of each section, its keys checked once, when its first key is read.
  std::map<std::string, YAML::Node> maps{{"", root}};
  std::function<YAML::Node(const std::string&)> section_map = [&](const std::string& path) {
    if (const auto it = maps.find(path); it != maps.end()) return it->second;
    const auto [parent, leaf] = split_key(path);
    const YAML::Node parent_map = section_map(parent);
    const YAML::Node m = rd.section(rd.find(parent_map, parent, leaf));
    maps.emplace(path, m);
    return m;
  };

  std::map<std::string, Entry> found;  // every key, present or not (cross-key checks)
  std::set<std::string> reported;      // keys with a problem
  // The shape is compiled (expressions parsed, curve built) once every key is read, and only when
  // the shape section itself had no problem; compile problems name the key that holds the faulty
  // expression or vertices.
  std::optional<std::size_t> problems_before_shape;
  std::optional<bool> shape_ok;
  for (const Param& p : config_table()) {
    const bool in_shape = p.key.rfind("shape.", 0) == 0;
    if (in_shape && !problems_before_shape) problems_before_shape = rd.problems.size();
    if (!in_shape && problems_before_shape && !shape_ok) shape_ok = rd.problems.size() == *problems_before_shape;
    const auto [section, leaf] = split_key(p.key);
    const Entry e = rd.find(section_map(section), section, leaf);
    found.emplace(p.key, e);
    const std::size_t before = rd.problems.size();
    if (p.key == "schema_version") {
      if (!e.present) {
        if (version_required)
          rd.problems.push_back("schema_version: missing (required, must be " + std::to_string(kSchemaVersion) +
                                ")");
      } else if (const auto v = rd.integer(e, std::numeric_limits<long long>::min(),
                                           std::numeric_limits<long long>::max())) {
        if (*v != kSchemaVersion) rd.bad(e, "must be " + std::to_string(kSchemaVersion));
      }
    } else if (const auto v = rd.value(e, p)) {
      p.set(c, *v);
    }
    if (rd.problems.size() != before) reported.insert(p.key);
  }
  check_transport(c.transport, found, reported, rd);
  check_vehicle(c, found, reported, rd);
  if (shape_ok.value_or(false)) {
    ShapeKeys keys{found.at("shape.r_expr"), found.at("shape.x_expr"), found.at("shape.y_expr"),
                   found.at("shape.f_expr"), found.at("shape.vertices")};
    compile_shape(c.command, keys, rd);
  }
  // The envelope (core/envelope.hpp) judges the command as a whole: only once every key of it is good.
  if (rd.problems.empty()) {
    for (const core::EnvelopeProblem& p : core::envelope_problems(c.command)) {
      const Entry& e = found.at(p.key);
      rd.problems.push_back(p.text + rd.where(e.path, e.anchor()));
    }
  }
  return c;
}

Config build(YAML::Node root, bool version_required, const std::vector<std::string>& overrides) {
  Problems override_problems;
  const auto applied = apply_overrides(root, overrides, override_problems);
  Reader rd(applied);
  rd.problems = std::move(override_problems);
  Config c = convert(root, version_required, rd);
  if (!rd.problems.empty()) throw ConfigError(std::move(rd.problems));
  return c;
}

std::string file_problem(const std::string& source, const std::string& what) {
  return "config file '" + util::excerpt(source) + "': " + what;
}

/// The 1-based line where the second document of text begins: its node's line, or (an empty
/// document has no usable mark) the second line that starts a document ("---" at column 0, not
/// counting one that opens the first document before any content).
std::size_t second_document_line(const std::string& text, const YAML::Node& second) {
  std::size_t line = 1;
  bool content = false;  // the first document has begun
  for (std::size_t pos = 0; pos < text.size(); ++line) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    const std::string_view l(text.data() + pos, end - pos);
    const bool marker = l.substr(0, 3) == "---" && (l.size() == 3 || l[3] == ' ' || l[3] == '\t' || l[3] == '\r');
    if (marker && content) return line;
    const std::string t = util::trim(l);
    if (marker || (!t.empty() && t[0] != '#' && t[0] != '%')) content = true;
    pos = end + 1;
  }
  return second.Mark().is_null() ? line : static_cast<std::size_t>(second.Mark().line) + 1;
}

/// What a config file must be, said after every problem with the file itself.
constexpr const char* kFileFix = ": give the path of a YAML config file";

/// "a directory", "a FIFO", ...: what a path that is not a regular file is.
std::string file_kind(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

/// The text of the config file at path: a regular file of at most kMaxFileBytes. Opened without
/// blocking and checked on the open descriptor, so a FIFO, a device or a file swapped in between
/// never blocks or floods the reader. Throws ConfigError naming the path and the fix.
std::string read_config_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    throw ConfigError({file_problem(path, std::string("cannot open (") + std::strerror(err) + ")" + kFileFix)});
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    const std::string kind = ::fstat(fd, &st) == 0 ? file_kind(st.st_mode) : "of unknown kind";
    throw ConfigError({file_problem(path, "is " + kind + ", not a regular file" + kFileFix)});
  }
  const auto too_big = [&path](std::uint64_t bytes, const char* how) {
    return ConfigError({file_problem(path, how + std::to_string(bytes) + " bytes, more than the " +
                                               std::to_string(kMaxFileBytes) + " (1 MiB) a config may hold" +
                                               kFileFix)});
  };
  if (static_cast<std::uint64_t>(st.st_size) > kMaxFileBytes)
    throw too_big(static_cast<std::uint64_t>(st.st_size), "");
  // Read at most one byte past the limit: a file that grows while it is read is refused too.
  std::string text(kMaxFileBytes + 1, '\0');
  std::size_t got = 0;
  while (got < text.size()) {
    const ssize_t n = ::read(fd, &text[got], text.size() - got);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      throw ConfigError({file_problem(path, std::string("cannot read (") + std::strerror(err) + ")" + kFileFix)});
    }
    got += static_cast<std::size_t>(n);
  }
  if (got > kMaxFileBytes) throw too_big(got, "more than ");
  text.resize(got);
  return text;
}

// ---------------------------------------------------------------------------------------------
// Emitting.

/// Free text is quoted when it would not read back as the same string.
void put_text(YAML::Emitter& e, const std::string& s) {
  double ignored_real = 0.0;
  const bool ambiguous = s.empty() || s == "~" || s == "null" || s == "Null" || s == "NULL" ||
                         is_bool_word(s) || parse_real(s, ignored_real) || util::trim(s) != s;
  if (ambiguous) e << YAML::DoubleQuoted;
  e << s;
}

void put_real(YAML::Emitter& e, const char* key, double v) {
  e << YAML::Key << key << YAML::Value << format_real(v);
}

void put_vec2(YAML::Emitter& e, const char* key, const core::Vec2& v) {
  e << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq << format_real(v.x())
    << format_real(v.y()) << YAML::EndSeq;
}

void put_list(YAML::Emitter& e, const char* key, const std::vector<std::string>& items) {
  e << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto& s : items) put_text(e, s);
  e << YAML::EndSeq;
}

/// One key of a table (the config table or the command table) with its value, spelled so that it
/// reads back the same.
template <class T>
void put_value(YAML::Emitter& e, const char* key, const params::Param<T>& p, const params::Value& v) {
  switch (p.type) {
    case Type::Real: {
      const double x = std::get<double>(v);
      put_real(e, key, p.degrees ? degrees_for(x) : x);
      return;
    }
    case Type::Integer: e << YAML::Key << key << YAML::Value << std::get<long long>(v); return;
    case Type::UInt64:
      e << YAML::Key << key << YAML::Value << static_cast<unsigned long long>(std::get<std::uint64_t>(v));
      return;
    case Type::Bool: e << YAML::Key << key << YAML::Value << std::get<bool>(v); return;
    case Type::Choice: e << YAML::Key << key << YAML::Value << std::get<std::string>(v); return;
    case Type::Text:
      e << YAML::Key << key << YAML::Value;
      put_text(e, std::get<std::string>(v));
      return;
    case Type::Vec2: put_vec2(e, key, std::get<core::Vec2>(v)); return;
    case Type::Vec2List:
      e << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (const auto& x : std::get<std::vector<core::Vec2>>(v))
        e << YAML::Flow << YAML::BeginSeq << format_real(x.x()) << format_real(x.y()) << YAML::EndSeq;
      e << YAML::EndSeq;
      return;
    case Type::TextList: put_list(e, key, std::get<std::vector<std::string>>(v)); return;
    case Type::ZoneList:
      e << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (const core::KeepOutZone& z : std::get<std::vector<core::KeepOutZone>>(v)) {
        e << YAML::Flow << YAML::BeginMap;
        if (z.kind == core::KeepOutZone::Kind::Circle) {
          e << YAML::Key << "circle" << YAML::Value << YAML::Flow << YAML::BeginSeq << format_real(z.centre.x())
            << format_real(z.centre.y()) << format_real(z.radius) << YAML::EndSeq;
        } else {
          e << YAML::Key << "polygon" << YAML::Value << YAML::Flow << YAML::BeginSeq;
          for (const auto& x : z.vertices)
            e << YAML::Flow << YAML::BeginSeq << format_real(x.x()) << format_real(x.y()) << YAML::EndSeq;
          e << YAML::EndSeq;
        }
        e << YAML::EndMap;
      }
      e << YAML::EndSeq;
      return;
  }
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += (out.empty() ? "" : "\n") + l;
  return out;
}

}  // namespace

namespace {

/// Each problem bounded (util::kLineMax): whatever input it quotes, one problem stays one short line.
std::vector<std::string> bounded(std::vector<std::string> problems) {
  for (auto& p : problems) p = util::bounded_line(p);
  return problems;
}

}  // namespace

ConfigError::ConfigError(std::vector<std::string> problems)
    : ConfigError(bounded(std::move(problems)), 0) {}

ConfigError::ConfigError(std::vector<std::string> problems, int)
    : std::runtime_error(join_lines(problems)), problems_(std::move(problems)) {}

Config load_string(const std::string& yaml_text, const std::vector<std::string>& overrides,
                   const std::string& source_name) {
  YAML::Node root;
  try {
    const std::vector<YAML::Node> documents = YAML::LoadAll(yaml_text);
    if (documents.size() > 1) {
      const std::size_t line = second_document_line(yaml_text, documents[1]);
      throw ConfigError({file_problem(source_name, "a second YAML document starts at line " + std::to_string(line) +
                                                       ": a config holds one document (remove the '---' line and "
                                                       "what follows it, or split the file)")});
    }
    if (!documents.empty()) root = documents.front();
  } catch (const YAML::Exception& ex) {
    const std::string at = ex.mark.is_null() ? "" : " at line " + std::to_string(ex.mark.line + 1);
    throw ConfigError({file_problem(source_name, "YAML syntax error" + at + ": " + ex.msg)});
  }
  if (root.IsNull()) {
    root.reset(YAML::Node(YAML::NodeType::Map));
  } else if (!root.IsMap()) {
    const std::string got = root.IsSequence() ? "a list" : describe(root);
    throw ConfigError({file_problem(source_name, "top level must be a map, got " + got + " (line " +
                                                     std::to_string(root.Mark().line + 1) + ")")});
  }
  return build(root, true, overrides);
}

Config load(const std::string& path, const std::vector<std::string>& overrides) {
  if (path.empty()) return build(YAML::Node(YAML::NodeType::Map), false, overrides);
  return load_string(read_config_file(path), overrides, path);
}

namespace {

/// "a.b.c" -> {"a", "b", "c"}: every part of a dotted key.
std::vector<std::string> key_parts(const std::string& key) {
  std::vector<std::string> parts;
  for (std::size_t begin = 0;;) {
    const auto dot = key.find('.', begin);
    parts.push_back(key.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin));
    if (dot == std::string::npos) return parts;
    begin = dot + 1;
  }
}

/// How many leading sections the open ones share with a key's sections (the tables are in file order).
std::size_t shared_depth(const std::vector<std::string>& open, const std::vector<std::string>& sections) {
  std::size_t n = 0;
  while (n < open.size() && n < sections.size() && open[n] == sections[n]) ++n;
  return n;
}

}  // namespace

std::string to_yaml(const Config& c) {
  YAML::Emitter e;
  e << YAML::BeginMap;
  std::vector<std::string> open;  // the sections whose maps are open, outermost first
  for (const Param& p : config_table()) {
    const std::vector<std::string> parts = key_parts(p.key);
    const std::vector<std::string> sections(parts.begin(), parts.end() - 1);
    const std::size_t common = shared_depth(open, sections);
    for (; open.size() > common; open.pop_back()) e << YAML::EndMap;
    for (; open.size() < sections.size(); open.push_back(sections[open.size()]))
      e << YAML::Key << sections[open.size()] << YAML::Value << YAML::BeginMap;
    put_value(e, parts.back().c_str(), p, p.get(c));
  }
  for (; !open.empty(); open.pop_back()) e << YAML::EndMap;
  e << YAML::EndMap;
  return std::string(e.c_str()) + "\n";
}

// ---------------------------------------------------------------------------------------------
// Documentation: config/README.md's key tables.

namespace {

/// The value as to_yaml writes it (one line).
template <class T>
std::string yaml_text(const params::Param<T>& p, const params::Value& v) {
  YAML::Emitter e;
  e << YAML::BeginMap;
  put_value(e, "k", p, v);
  e << YAML::EndMap;
  return std::string(e.c_str()).substr(3);  // after "k: "
}

}  // namespace

std::vector<std::pair<std::string, std::string>> command_settings(const core::Command& c) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& p : params::command_table()) out.emplace_back(p.key, yaml_text(p, p.get(c)));
  return out;
}

namespace {

std::string code(const std::string& s) { return "`" + s + "`"; }

/// Markdown cell text: '|' would end the cell.
std::string cell(const std::string& s) {
  std::string out;
  for (const char ch : s) out += ch == '|' ? std::string("\\|") : std::string(1, ch);
  return out;
}

std::string range_doc(const Param& p) {
  std::string base;
  switch (p.type) {
    case Type::Real:
    case Type::Integer: base = p.range.doc(); break;
    case Type::UInt64: base = "`>= 0`"; break;
    case Type::Bool: base = "`true`, `false`"; break;
    case Type::Choice: {
      std::vector<std::string> quoted;
      for (const auto& name : p.choices) quoted.push_back(code(name));
      base = params::join(quoted, ", ");
      break;
    }
    case Type::Vec2: base = "2 finite numbers"; break;
    case Type::Text:
    case Type::Vec2List:
    case Type::TextList:
    case Type::ZoneList: break;
  }
  return base + p.range_note;
}

std::string top_section(const std::string& key) {
  const auto dot = key.find('.');
  return dot == std::string::npos ? "" : key.substr(0, dot);
}

}  // namespace

std::string markdown_table(const std::string& section) {
  static const Config defaults;
  std::string out =
      "| key | type | unit | default | range | description |\n|---|---|---|---|---|---|\n";
  bool any = false;
  for (const Param& p : config_table()) {
    if (top_section(p.key) != section) continue;
    any = true;
    const std::string def = p.key == "schema_version" ? "(required)" : code(yaml_text(p, p.get(defaults)));
    out += "| " + code(p.key) + " | " + std::string(params::type_name(p.type)) + " | " +
           cell(p.unit.empty() ? "-" : p.unit) + " | " + cell(def) + " | " + cell(range_doc(p)) + " | " +
           cell(p.doc) + " |\n";
  }
  if (!any) throw std::invalid_argument("no config keys in section '" + section + "'");
  return out;
}

std::string regenerate_doc(const std::string& text) {
  return util::regenerate_blocks(text, "<!-- BEGIN GENERATED keys: ", "<!-- END GENERATED -->",
                                 [](const std::string& section) { return markdown_table(section == "top" ? "" : section); });
}

std::string default_yaml() {
  static const Config defaults;
  std::string out =
      "# shapeform: every key with its default value, the loader's built-in defaults. Every key but\n"
      "# schema_version is optional: this file is documentation and a starting point. Generated from the\n"
      "# config table by scripts/gen_config_doc.sh (a test fails while it is stale); each comment gives the\n"
      "# key's unit, range and meaning (more in config/README.md).\n";
  std::vector<std::string> open;  // sections written, outermost first
  for (const Param& p : config_table()) {
    const std::vector<std::string> parts = key_parts(p.key);
    const std::vector<std::string> sections(parts.begin(), parts.end() - 1);
    const std::size_t common = shared_depth(open, sections);
    open.resize(common);
    for (; open.size() < sections.size(); open.push_back(sections[open.size()])) {
      if (open.empty()) out += "\n";
      out += std::string(2 * open.size(), ' ') + sections[open.size()] + ":\n";
    }
    std::string line = std::string(2 * open.size(), ' ') + parts.back() + ": " + yaml_text(p, p.get(defaults));
    std::string note = p.doc;
    if (!p.unit.empty()) note += ", " + p.unit;
    const std::string range = range_doc(p);
    if (!range.empty() && range != "finite") note += "; " + range;
    note.erase(std::remove(note.begin(), note.end(), '`'), note.end());  // Markdown quoting
    line.resize(std::max<std::size_t>(line.size() + 1, 32), ' ');
    out += line + "# " + note + "\n";
  }
  return out;
}

std::string VehicleLink::namespace_of(std::int32_t id) const {
  // ROS 2 namespaces are absolute: "/robot_{id}" is "robot_{id}" (topics rt/robot_3/...).
  return with_id(!ns.empty() && ns.front() == '/' ? ns.substr(1) : ns, id);
}

std::string VehicleLink::with_id(const std::string& text, std::int32_t id) {
  std::string out = text;
  const std::string value = std::to_string(id);
  for (auto at = out.find("{id}"); at != std::string::npos; at = out.find("{id}", at + value.size()))
    out.replace(at, 4, value);
  return out;
}

}  // namespace shapeform::config
