#include "params.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>

namespace shapeform::core::params {

std::string format_number(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

namespace {

std::string integer_text(double v) { return std::to_string(static_cast<long long>(v)); }

std::string end_text(double v, bool integer) { return integer ? integer_text(v) : format_number(v); }

/// "> 0", "(0, 10]", "1..1000", "1"; "" when unbounded.
std::string bare(const Range& r) {
  if (r.integer && r.bounded()) {
    if (r.lo == r.hi) return integer_text(r.lo);
    if (r.hi == kInf) return ">= " + integer_text(r.lo);
    return integer_text(r.lo) + ".." + integer_text(r.hi);
  }
  if (!r.bounded()) return "";
  if (r.hi == kInf) return (r.lo_open ? "> " : ">= ") + end_text(r.lo, r.integer);
  if (r.lo == -kInf) return (r.hi_open ? "< " : "<= ") + end_text(r.hi, r.integer);
  return std::string(r.lo_open ? "(" : "[") + format_number(r.lo) + ", " + format_number(r.hi) +
         (r.hi_open ? ")" : "]");
}

}  // namespace

std::string Range::text() const {
  const std::string b = bare(*this);
  if (b.empty()) return "";
  const bool interval = b[0] == '(' || b[0] == '[' || b.find("..") != std::string::npos;
  return (interval ? "must be in " : "must be ") + b;
}

std::string Range::text_for(double v) const {
  if (lo == -kInf || hi == kInf || integer) return text();
  if (!(lo_open ? v > lo : v >= lo))
    return std::string("must be ") + (lo_open ? "> " : ">= ") + format_number(lo);
  if (!(hi_open ? v < hi : v <= hi))
    return std::string("must be ") + (hi_open ? "< " : "<= ") + format_number(hi);
  return text();
}

std::string Range::bounds() const { return bare(*this); }

std::string Range::doc() const {
  const std::string b = bare(*this);
  return b.empty() ? "finite" : "`" + b + "`";
}

std::string join(const std::vector<std::string>& items, std::string_view sep) {
  std::string out;
  for (const auto& s : items) {
    if (!out.empty()) out += sep;
    out += s;
  }
  return out;
}

std::string_view type_name(Type t) {
  switch (t) {
    case Type::Real:
      return "number";
    case Type::Integer:
      return "integer";
    case Type::UInt64:
      return "integer (64-bit)";
    case Type::Bool:
      return "flag";
    case Type::Choice:
      return "choice";
    case Type::Text:
      return "text";
    case Type::Vec2:
      return "2-vector";
    case Type::Vec2List:
      return "list of 2-vectors";
    case Type::TextList:
      return "list of text";
    case Type::ZoneList:
      return "list of zones";
  }
  return "?";
}

}  // namespace shapeform::core::params
