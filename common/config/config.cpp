/// The one config loader: YAML text -> (overrides) -> checked conversion -> Config.
/// Conversion and validation happen in one walk over the tree so every problem can name its key
/// path and line; the walk collects problems instead of stopping at the first.
#include "config/config.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string_view>
#include <system_error>

#include "shapes/shapes.hpp"

namespace shapeform::config {

namespace {

using Problems = std::vector<std::string>;

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------
// Names of enumerations. The spellings are those of core's to_string/parse helpers; the mapping
// is kept here so the loader depends on core's types only, not on its function bodies.

template <class E>
struct Name {
  E value;
  std::string_view name;
};

constexpr Name<core::ShapeKind> kShapeNames[] = {{core::ShapeKind::Line, "line"},
                                                 {core::ShapeKind::Circle, "circle"},
                                                 {core::ShapeKind::Ellipse, "ellipse"},
                                                 {core::ShapeKind::Square, "square"},
                                                 {core::ShapeKind::Polar, "polar"},
                                                 {core::ShapeKind::Parametric, "parametric"},
                                                 {core::ShapeKind::Implicit, "implicit"},
                                                 {core::ShapeKind::Polygon, "polygon"}};
constexpr Name<core::Law> kLawNames[] = {{core::Law::Paper, "paper"}, {core::Law::Arc, "arc"}};
constexpr Name<bool> kSyncNames[] = {{false, "free"}, {true, "lockstep"}};
constexpr Name<core::CentrePath::Kind> kPathNames[] = {{core::CentrePath::Kind::Fixed, "fixed"},
                                                       {core::CentrePath::Kind::Line, "line"},
                                                       {core::CentrePath::Kind::Circle, "circle"}};
constexpr Name<core::Integrator> kIntegratorNames[] = {{core::Integrator::Euler, "euler"},
                                                       {core::Integrator::RK4, "rk4"}};
constexpr Name<std::string_view> kProfileNames[] = {
    {"loopback", "loopback"}, {"lan", "lan"}, {"discovery-server", "discovery-server"}};

template <class E, std::size_t N>
std::optional<E> parse_name(const Name<E> (&table)[N], std::string_view s) {
  for (const auto& entry : table)
    if (entry.name == s) return entry.value;
  return std::nullopt;
}

template <class E, std::size_t N>
std::string name_of(const Name<E> (&table)[N], E v) {
  for (const auto& entry : table)
    if (entry.value == v) return std::string(entry.name);
  return "?";
}

template <class E, std::size_t N>
std::string names_list(const Name<E> (&table)[N]) {
  std::string out;
  for (const auto& entry : table) out += (out.empty() ? "" : ", ") + std::string(entry.name);
  return out;
}

// ---------------------------------------------------------------------------------------------
// The schema's key names per section ("" = top level). Used for unknown-key checks and to check
// --set paths before they touch the tree.

const std::map<std::string, std::vector<std::string>>& schema_sections() {
  static const std::map<std::string, std::vector<std::string>> sections = {
      {"",
       {"schema_version", "name", "swarm", "shape", "tracking", "dynamics", "integration", "sim",
        "agent", "supervisor", "transport"}},
      {"swarm", {"agents", "seed", "init_half_width"}},
      {"shape",
       {"kind", "m", "c", "r0", "a", "b", "centre", "rotation_deg", "scale", "r_expr", "x_expr",
        "y_expr", "f_expr", "vertices", "closed"}},
      {"tracking",
       {"enabled", "path", "point", "velocity", "origin", "radius", "period", "phase",
        "feedforward"}},
      {"dynamics",
       {"k1", "k2", "sigma", "beta", "r", "max_speed", "law", "k_normal", "k_tangent", "spacing"}},
      {"integration", {"integrator", "dt"}},
      {"sim", {"steps"}},
      {"agent", {"rate_hz", "neighbour_timeout_periods", "status_rate_hz", "sync"}},
      {"supervisor",
       {"metrics_rate_hz", "target_rate_hz", "agent_timeout_s", "flush_s", "converge"}},
      {"supervisor.converge", {"band_abs", "band_rel", "gap_cv_max", "hold"}},
      {"transport",
       {"profile", "domain", "max_participants", "interfaces", "peers", "discovery_server",
        "lease_s", "announce_s", "socket_buffer_bytes", "multicast_data"}},
  };
  return sections;
}

std::string join_path(const std::string& section, std::string_view key) {
  return section.empty() ? std::string(key) : section + "." + std::string(key);
}

bool schema_has(const std::string& dotted) {
  const auto dot = dotted.rfind('.');
  const std::string parent = dot == std::string::npos ? "" : dotted.substr(0, dot);
  const std::string leaf = dot == std::string::npos ? dotted : dotted.substr(dot + 1);
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

/// Shortest text that reads back to exactly v (no forced decimal point): for messages.
std::string format_number(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

/// As format_number, but always reads back as a YAML float ("1.0", not "1").
std::string format_real(double v) {
  std::string s = format_number(v);
  if (std::isfinite(v) && s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

double radians(double degrees) { return degrees * kRadPerDeg; }

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

std::string quote(const std::string& s) {
  constexpr std::size_t kMaxShown = 60;
  std::string out = "\"";
  for (std::size_t i = 0; i < s.size() && i < kMaxShown; ++i) {
    const char ch = s[i];
    if (ch == '"' || ch == '\\')
      out += '\\', out += ch;
    else if (ch == '\n')
      out += "\\n";
    else if (ch == '\t')
      out += "\\t";
    else
      out += ch;
  }
  if (s.size() > kMaxShown) out += "...";
  return out + "\"";
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
// Ranges.

struct Bound {
  double lo = -kInf;
  bool lo_open = false;
  double hi = kInf;
  bool hi_open = false;

  bool contains(double v) const {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  std::string text() const {
    if (std::isinf(hi))
      return std::string("must be ") + (lo_open ? "> " : ">= ") + format_number(lo);
    if (std::isinf(lo))
      return std::string("must be ") + (hi_open ? "< " : "<= ") + format_number(hi);
    return std::string("must be in ") + (lo_open ? "(" : "[") + format_number(lo) + ", " +
           format_number(hi) + (hi_open ? ")" : "]");
  }
};

Bound above(double lo) { return {lo, true, kInf, false}; }
Bound at_least(double lo) { return {lo, false, kInf, false}; }
Bound above_up_to(double lo, double hi) { return {lo, true, hi, false}; }

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
        problems.push_back(path + ": unknown key" + where(path, it->first));
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
                             const Bound& bound) {
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
  std::optional<double> real(const Entry& e, const Bound& bound) {
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
      bad(e, "must be in " + std::to_string(lo) + ".." + std::to_string(hi));
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

  template <class E, std::size_t N>
  std::optional<E> choice(const Entry& e, const Name<E> (&table)[N]) {
    const auto s = text(e);
    if (!s) return std::nullopt;
    const auto v = parse_name(table, *s);
    if (!v) bad(e, "must be one of " + names_list(table));
    return v;
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
                          item.IsNull() ? e.anchor() : item, Bound{});
      if (x) out[static_cast<Eigen::Index>(i)] = *x;
      ok = ok && x.has_value();
    }
    return ok ? std::optional<core::Vec2>(out) : std::nullopt;
  }

  /// A list of [x, y] pairs (each checked like vec2, named "key[i]"); null means empty.
  std::optional<std::vector<core::Vec2>> vec2_list(const Entry& e) {
    if (!e.present) return std::nullopt;
    if (e.value.IsNull()) return std::vector<core::Vec2>{};
    if (!e.value.IsSequence()) {
      bad(e, "expected a list of [x, y] pairs");
      return std::nullopt;
    }
    std::vector<core::Vec2> out;
    bool ok = true;
    for (std::size_t i = 0; i < e.value.size(); ++i) {
      Entry item;
      item.path = e.path + "[" + std::to_string(i) + "]";
      item.key.reset(e.key);
      item.value.reset(e.value[i]);  // reset, not '=': assigning a YAML::Node writes through it
      item.present = true;
      const auto v = vec2(item);
      if (v) out.push_back(*v);
      ok = ok && v.has_value();
    }
    return ok ? std::optional<std::vector<core::Vec2>>(std::move(out)) : std::nullopt;
  }

  /// A list of non-empty strings; null means empty.
  std::optional<std::vector<std::string>> text_list(const Entry& e) {
    if (!e.present) return std::nullopt;
    if (e.value.IsNull()) return std::vector<std::string>{};
    if (!e.value.IsSequence()) {
      bad(e, "expected a list of strings");
      return std::nullopt;
    }
    std::vector<std::string> out;
    bool ok = true;
    for (std::size_t i = 0; i < e.value.size(); ++i) {
      const YAML::Node item = e.value[i];
      const std::string path = e.path + "[" + std::to_string(i) + "]";
      const YAML::Node& at = item.IsNull() ? e.anchor() : item;
      if (!item.IsScalar()) {
        bad(path, "expected a string", item, at);
        ok = false;
      } else if (item.Scalar().empty()) {
        bad(path, "must not be empty", item, at);
        ok = false;
      } else {
        out.push_back(item.Scalar());
      }
    }
    return ok ? std::optional<std::vector<std::string>>(std::move(out)) : std::nullopt;
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

template <class T, class U>
void assign(const std::optional<U>& v, T& out) {
  if (v) out = static_cast<T>(*v);
}

/// "a.b.c.d" with each part 0..255 (the transport takes IPv4 literals only).
bool valid_ipv4(const std::string& s) {
  int parts = 0;
  std::size_t pos = 0;
  while (pos <= s.size()) {
    const std::size_t dot = std::min(s.find('.', pos), s.size());
    const std::string part = s.substr(pos, dot - pos);
    if (part.empty() || part.size() > 3 || part.find_first_not_of("0123456789") != std::string::npos ||
        std::stoi(part) > 255)
      return false;
    ++parts;
    pos = dot + 1;
  }
  return parts == 4;
}

/// "host:port" with host an IPv4 literal or localhost and port 1..65535.
bool valid_host_port(const std::string& s) {
  const auto colon = s.rfind(':');
  if (colon == std::string::npos || colon == 0) return false;
  const std::string host = s.substr(0, colon);
  if (host != "localhost" && !valid_ipv4(host)) return false;
  long long port = 0;
  return parse_integer(s.substr(colon + 1), port) == IntParse::Ok && s[colon + 1] != '+' &&
         s[colon + 1] != '-' && port >= 1 && port <= 65535;
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t");
  return s.substr(first, last - first + 1);
}

/// Applies "dotted.key=value" overrides to root in order. Returns the paths set; bad overrides
/// are reported in problems and skipped.
std::vector<std::string> apply_overrides(YAML::Node& root,
                                         const std::vector<std::string>& overrides,
                                         Problems& problems) {
  std::vector<std::string> applied;
  for (const auto& item : overrides) {
    const auto eq = item.find('=');
    const std::string key = eq == std::string::npos ? "" : trim(item.substr(0, eq));
    if (key.empty()) {
      problems.push_back("--set " + item + ": expected dotted.key=value");
      continue;
    }
    if (!schema_has(key)) {
      problems.push_back("--set " + item + ": unknown key " + key);
      continue;
    }
    YAML::Node value;
    try {
      value = YAML::Load(item.substr(eq + 1));
    } catch (const YAML::Exception& ex) {
      problems.push_back("--set " + item + ": YAML syntax error: " + ex.msg);
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

/// The checked conversion of a (map) tree.
Config convert(const YAML::Node& root, bool version_required, Reader& rd) {
  Config c;
  rd.check_keys(root, "");

  const Entry version = rd.find(root, "", "schema_version");
  if (!version.present) {
    if (version_required)
      rd.problems.push_back("schema_version: missing (required, must be " +
                            std::to_string(kSchemaVersion) + ")");
  } else if (const auto v = rd.integer(version, std::numeric_limits<long long>::min(),
                                       std::numeric_limits<long long>::max())) {
    if (*v != kSchemaVersion)
      rd.bad(version, "must be " + std::to_string(kSchemaVersion));
    else
      c.schema_version = kSchemaVersion;
  }
  assign(rd.text(rd.find(root, "", "name")), c.name);

  const auto get = [&rd](const YAML::Node& map, const std::string& section, const char* key) {
    return rd.find(map, section, key);
  };

  {
    const std::string s = "swarm";
    const YAML::Node m = rd.section(get(root, "", "swarm"));
    assign(rd.integer(get(m, s, "agents"), 1, 1000), c.swarm.agents);
    assign(rd.unsigned64(get(m, s, "seed")), c.swarm.seed);
    assign(rd.real(get(m, s, "init_half_width"), above(0)), c.swarm.init_half_width);
  }
  // The shape is compiled (expressions parsed, curve built) once every key is read; its problems
  // name the key that holds the faulty expression or vertices.
  ShapeKeys shape_keys;
  bool shape_ok = false;
  const std::size_t problems_before_shape = rd.problems.size();
  {
    const std::string s = "shape";
    auto& shape = c.command.shape;
    const YAML::Node m = rd.section(get(root, "", "shape"));
    assign(rd.choice(get(m, s, "kind"), kShapeNames), shape.kind);
    assign(rd.real(get(m, s, "m"), Bound{}), shape.m);
    assign(rd.real(get(m, s, "c"), Bound{}), shape.c);
    assign(rd.real(get(m, s, "r0"), above(0)), shape.r0);
    assign(rd.real(get(m, s, "a"), above(0)), shape.a);
    assign(rd.real(get(m, s, "b"), above(0)), shape.b);
    assign(rd.vec2(get(m, s, "centre")), shape.centre);
    if (const auto deg = rd.real(get(m, s, "rotation_deg"), Bound{})) shape.rotation = radians(*deg);
    assign(rd.real(get(m, s, "scale"), above(0)), shape.scale);
    shape_keys.r_expr = get(m, s, "r_expr");
    shape_keys.x_expr = get(m, s, "x_expr");
    shape_keys.y_expr = get(m, s, "y_expr");
    shape_keys.f_expr = get(m, s, "f_expr");
    shape_keys.vertices = get(m, s, "vertices");
    assign(rd.text(shape_keys.r_expr), shape.r_expr);
    assign(rd.text(shape_keys.x_expr), shape.x_expr);
    assign(rd.text(shape_keys.y_expr), shape.y_expr);
    assign(rd.text(shape_keys.f_expr), shape.f_expr);
    assign(rd.vec2_list(shape_keys.vertices), shape.vertices);
    assign(rd.boolean(get(m, s, "closed")), shape.closed);
    shape_ok = rd.problems.size() == problems_before_shape;
  }
  {
    const std::string s = "tracking";
    auto& tracking = c.command.tracking;
    const YAML::Node m = rd.section(get(root, "", "tracking"));
    assign(rd.boolean(get(m, s, "enabled")), tracking.enabled);
    assign(rd.choice(get(m, s, "path"), kPathNames), tracking.path.kind);
    assign(rd.vec2(get(m, s, "point")), tracking.path.point);
    assign(rd.vec2(get(m, s, "velocity")), tracking.path.velocity);
    assign(rd.vec2(get(m, s, "origin")), tracking.path.origin);
    assign(rd.real(get(m, s, "radius"), at_least(0)), tracking.path.radius);
    assign(rd.real(get(m, s, "period"), above(0)), tracking.path.period);
    assign(rd.real(get(m, s, "phase"), Bound{}), tracking.path.phase);
    assign(rd.boolean(get(m, s, "feedforward")), tracking.feedforward);
  }
  {
    const std::string s = "dynamics";
    auto& gains = c.command.gains;
    const YAML::Node m = rd.section(get(root, "", "dynamics"));
    assign(rd.real(get(m, s, "k1"), at_least(0)), gains.k1);
    assign(rd.real(get(m, s, "k2"), at_least(0)), gains.k2);
    assign(rd.real(get(m, s, "sigma"), above(0)), gains.sigma);
    assign(rd.real(get(m, s, "beta"), at_least(0)), gains.beta);
    assign(rd.real(get(m, s, "r"), at_least(0)), gains.r);
    assign(rd.real(get(m, s, "max_speed"), at_least(0)), c.command.max_speed);
    assign(rd.choice(get(m, s, "law"), kLawNames), c.command.law);
    assign(rd.real(get(m, s, "k_normal"), above_up_to(0, 10)), c.command.arc.k_normal);
    assign(rd.real(get(m, s, "k_tangent"), above_up_to(0, 1)), c.command.arc.k_tangent);
    assign(rd.real(get(m, s, "spacing"), above(0)), c.command.arc.spacing);
  }
  {
    const std::string s = "integration";
    const YAML::Node m = rd.section(get(root, "", "integration"));
    assign(rd.choice(get(m, s, "integrator"), kIntegratorNames), c.command.integrator);
    assign(rd.real(get(m, s, "dt"), above_up_to(0, 10)), c.command.dt);
  }
  {
    const YAML::Node m = rd.section(get(root, "", "sim"));
    assign(rd.integer(get(m, "sim", "steps"), 0, 10'000'000), c.sim.steps);
  }
  {
    const std::string s = "agent";
    const YAML::Node m = rd.section(get(root, "", "agent"));
    assign(rd.real(get(m, s, "rate_hz"), above_up_to(0, 1000)), c.agent.rate_hz);
    assign(rd.real(get(m, s, "neighbour_timeout_periods"), at_least(1)),
           c.agent.neighbour_timeout_periods);
    assign(rd.real(get(m, s, "status_rate_hz"), above(0)), c.agent.status_rate_hz);
    assign(rd.choice(get(m, s, "sync"), kSyncNames), c.agent.lockstep);
  }
  {
    const std::string s = "supervisor";
    auto& sup = c.supervisor;
    const YAML::Node m = rd.section(get(root, "", "supervisor"));
    assign(rd.real(get(m, s, "metrics_rate_hz"), above(0)), sup.metrics_rate_hz);
    assign(rd.real(get(m, s, "target_rate_hz"), above(0)), sup.target_rate_hz);
    assign(rd.real(get(m, s, "agent_timeout_s"), above(0)), sup.agent_timeout_s);
    assign(rd.real(get(m, s, "flush_s"), above(0)), sup.flush_s);
    const std::string cs = "supervisor.converge";
    const YAML::Node cm = rd.section(get(m, s, "converge"));
    assign(rd.real(get(cm, cs, "band_abs"), at_least(0)), sup.converge.band_abs);
    assign(rd.real(get(cm, cs, "band_rel"), at_least(0)), sup.converge.band_rel);
    assign(rd.real(get(cm, cs, "gap_cv_max"), above(0)), sup.converge.gap_cv_max);
    assign(rd.real(get(cm, cs, "hold"), at_least(0)), sup.converge.hold);
  }
  {
    const std::string s = "transport";
    auto& tr = c.transport;
    const YAML::Node m = rd.section(get(root, "", "transport"));
    const Entry profile = get(m, s, "profile");
    assign(rd.choice(profile, kProfileNames), tr.profile);
    assign(rd.integer(get(m, s, "domain"), 0, 232), tr.domain);
    assign(rd.integer(get(m, s, "max_participants"), 1, 230), tr.max_participants);
    for (auto [key, field] : {std::pair{"interfaces", &tr.interfaces}, std::pair{"peers", &tr.peers}}) {
      const Entry e = get(m, s, key);
      if (const auto v = rd.text_list(e)) {
        const auto bad = std::find_if(v->begin(), v->end(), [](const std::string& a) { return !valid_ipv4(a); });
        if (bad == v->end())
          *field = *v;
        else
          rd.bad(e, "must be a list of IPv4 addresses (\"" + *bad + "\" is not one)");
      }
    }
    const Entry server = get(m, s, "discovery_server");
    if (const auto v = rd.text(server)) {
      if (valid_host_port(*v))
        tr.discovery_server = *v;
      else
        rd.bad(server, "must be host:port with host an IPv4 address or localhost and port 1..65535");
    }
    const Entry lease = get(m, s, "lease_s");
    const Entry announce = get(m, s, "announce_s");
    const auto lease_v = rd.real(lease, above(0));
    const auto announce_v = rd.real(announce, above(0));
    assign(lease_v, tr.lease_s);
    assign(announce_v, tr.announce_s);
    const bool lease_ok = lease_v || !lease.present;
    const bool announce_ok = announce_v || !announce.present;
    if (lease_ok && announce_ok && !(tr.announce_s < tr.lease_s)) {
      if (announce.present)
        rd.bad(announce, "must be < transport.lease_s (" + format_number(tr.lease_s) + ")");
      else
        rd.bad(lease, "must be > transport.announce_s (" + format_number(tr.announce_s) + ")");
    }
    assign(rd.integer(get(m, s, "socket_buffer_bytes"), 0, std::numeric_limits<int>::max()),
           tr.socket_buffer_bytes);
    const Entry multicast = get(m, s, "multicast_data");
    assign(rd.boolean(multicast), tr.multicast_data);
    if (tr.multicast_data && !tr.on_loopback())
      rd.bad(multicast, "needs transport.profile loopback, or discovery-server with a server on 127.x (profile is " +
                            tr.profile + ")");
  }
  if (shape_ok) compile_shape(c.command, shape_keys, rd);
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
  return "config file '" + source + "': " + what;
}

// ---------------------------------------------------------------------------------------------
// Emitting.

/// Free text is quoted when it would not read back as the same string.
void put_text(YAML::Emitter& e, const std::string& s) {
  double ignored_real = 0.0;
  const bool ambiguous = s.empty() || s == "~" || s == "null" || s == "Null" || s == "NULL" ||
                         is_bool_word(s) || parse_real(s, ignored_real) || trim(s) != s;
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

std::string join_lines(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += (out.empty() ? "" : "\n") + l;
  return out;
}

}  // namespace

ConfigError::ConfigError(std::vector<std::string> problems)
    : std::runtime_error(join_lines(problems)), problems_(std::move(problems)) {}

Config load_string(const std::string& yaml_text, const std::vector<std::string>& overrides,
                   const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
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
  std::error_code ec;
  std::ifstream in(path, std::ios::binary);
  if (!in || std::filesystem::is_directory(path, ec))
    throw ConfigError({file_problem(path, "cannot open")});
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError({file_problem(path, "cannot open")});
  return load_string(text.str(), overrides, path);
}

std::string to_yaml(const Config& c) {
  YAML::Emitter e;
  e << YAML::BeginMap;
  e << YAML::Key << "schema_version" << YAML::Value << c.schema_version;
  e << YAML::Key << "name" << YAML::Value;
  put_text(e, c.name);

  e << YAML::Key << "swarm" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "agents" << YAML::Value << c.swarm.agents;
  e << YAML::Key << "seed" << YAML::Value << static_cast<unsigned long long>(c.swarm.seed);
  put_real(e, "init_half_width", c.swarm.init_half_width);
  e << YAML::EndMap;

  const auto& shape = c.command.shape;
  e << YAML::Key << "shape" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "kind" << YAML::Value << name_of(kShapeNames, shape.kind);
  put_real(e, "m", shape.m);
  put_real(e, "c", shape.c);
  put_real(e, "r0", shape.r0);
  put_real(e, "a", shape.a);
  put_real(e, "b", shape.b);
  put_vec2(e, "centre", shape.centre);
  put_real(e, "rotation_deg", degrees_for(shape.rotation));
  put_real(e, "scale", shape.scale);
  e << YAML::Key << "r_expr" << YAML::Value;
  put_text(e, shape.r_expr);
  e << YAML::Key << "x_expr" << YAML::Value;
  put_text(e, shape.x_expr);
  e << YAML::Key << "y_expr" << YAML::Value;
  put_text(e, shape.y_expr);
  e << YAML::Key << "f_expr" << YAML::Value;
  put_text(e, shape.f_expr);
  e << YAML::Key << "vertices" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto& v : shape.vertices)
    e << YAML::Flow << YAML::BeginSeq << format_real(v.x()) << format_real(v.y()) << YAML::EndSeq;
  e << YAML::EndSeq;
  e << YAML::Key << "closed" << YAML::Value << shape.closed;
  e << YAML::EndMap;

  const auto& tracking = c.command.tracking;
  e << YAML::Key << "tracking" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "enabled" << YAML::Value << tracking.enabled;
  e << YAML::Key << "path" << YAML::Value << name_of(kPathNames, tracking.path.kind);
  put_vec2(e, "point", tracking.path.point);
  put_vec2(e, "velocity", tracking.path.velocity);
  put_vec2(e, "origin", tracking.path.origin);
  put_real(e, "radius", tracking.path.radius);
  put_real(e, "period", tracking.path.period);
  put_real(e, "phase", tracking.path.phase);
  e << YAML::Key << "feedforward" << YAML::Value << tracking.feedforward;
  e << YAML::EndMap;

  const auto& gains = c.command.gains;
  e << YAML::Key << "dynamics" << YAML::Value << YAML::BeginMap;
  put_real(e, "k1", gains.k1);
  put_real(e, "k2", gains.k2);
  put_real(e, "sigma", gains.sigma);
  put_real(e, "beta", gains.beta);
  put_real(e, "r", gains.r);
  put_real(e, "max_speed", c.command.max_speed);
  e << YAML::Key << "law" << YAML::Value << name_of(kLawNames, c.command.law);
  put_real(e, "k_normal", c.command.arc.k_normal);
  put_real(e, "k_tangent", c.command.arc.k_tangent);
  put_real(e, "spacing", c.command.arc.spacing);
  e << YAML::EndMap;

  e << YAML::Key << "integration" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "integrator" << YAML::Value << name_of(kIntegratorNames, c.command.integrator);
  put_real(e, "dt", c.command.dt);
  e << YAML::EndMap;

  e << YAML::Key << "sim" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "steps" << YAML::Value << c.sim.steps;
  e << YAML::EndMap;

  e << YAML::Key << "agent" << YAML::Value << YAML::BeginMap;
  put_real(e, "rate_hz", c.agent.rate_hz);
  put_real(e, "neighbour_timeout_periods", c.agent.neighbour_timeout_periods);
  put_real(e, "status_rate_hz", c.agent.status_rate_hz);
  e << YAML::Key << "sync" << YAML::Value << name_of(kSyncNames, c.agent.lockstep);
  e << YAML::EndMap;

  const auto& sup = c.supervisor;
  e << YAML::Key << "supervisor" << YAML::Value << YAML::BeginMap;
  put_real(e, "metrics_rate_hz", sup.metrics_rate_hz);
  put_real(e, "target_rate_hz", sup.target_rate_hz);
  put_real(e, "agent_timeout_s", sup.agent_timeout_s);
  put_real(e, "flush_s", sup.flush_s);
  e << YAML::Key << "converge" << YAML::Value << YAML::BeginMap;
  put_real(e, "band_abs", sup.converge.band_abs);
  put_real(e, "band_rel", sup.converge.band_rel);
  put_real(e, "gap_cv_max", sup.converge.gap_cv_max);
  put_real(e, "hold", sup.converge.hold);
  e << YAML::EndMap;
  e << YAML::EndMap;

  const auto& tr = c.transport;
  e << YAML::Key << "transport" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "profile" << YAML::Value << tr.profile;
  e << YAML::Key << "domain" << YAML::Value << tr.domain;
  e << YAML::Key << "max_participants" << YAML::Value << tr.max_participants;
  put_list(e, "interfaces", tr.interfaces);
  put_list(e, "peers", tr.peers);
  e << YAML::Key << "discovery_server" << YAML::Value;
  put_text(e, tr.discovery_server);
  put_real(e, "lease_s", tr.lease_s);
  put_real(e, "announce_s", tr.announce_s);
  e << YAML::Key << "socket_buffer_bytes" << YAML::Value << tr.socket_buffer_bytes;
  e << YAML::Key << "multicast_data" << YAML::Value << tr.multicast_data;
  e << YAML::EndMap;

  e << YAML::EndMap;
  return std::string(e.c_str()) + "\n";
}

}  // namespace shapeform::config
