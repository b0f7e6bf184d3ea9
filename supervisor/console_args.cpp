#include "console_args.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <utility>

#include "core/command_table.hpp"
#include "util/text.hpp"

namespace shapeform::supervisor {

namespace params = core::params;
using params::Range;

// ---------------------------------------------------------------------------------------------
// Tokens

bool is_space(char ch) {
  return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\n' || ch == '\v' || ch == '\f';
}

std::string tokenize(std::string_view line, std::vector<Token>& out) {
  std::size_t i = 0;
  const std::size_t n = line.size();
  while (i < n) {
    while (i < n && is_space(line[i])) ++i;
    if (i >= n || line[i] == '#') break;
    Token tok;
    bool in_quotes = false;
    for (; i < n && (in_quotes || !is_space(line[i])); ++i) {
      const char ch = line[i];
      if (ch == '"') {
        in_quotes = !in_quotes;
        continue;
      }
      if (ch == '=' && !in_quotes && !tok.is_pair) {
        tok.is_pair = true;
        tok.key = tok.text;
        tok.text.push_back(ch);
        continue;
      }
      tok.text.push_back(ch);
      if (tok.is_pair) tok.value.push_back(ch);
    }
    if (in_quotes) return "unterminated double quote";
    out.push_back(std::move(tok));
  }
  return {};
}

void fail(std::string message) { throw ParseError{std::move(message)}; }

// ---------------------------------------------------------------------------------------------
// Parameters

const Range& field_range(std::string_view key) {
  const params::Param<core::Command>* p = params::find_key(key);
  if (p == nullptr) throw std::logic_error("no command key '" + std::string(key) + "'");
  return p->range;
}

const Range& ParamSpec::bounds() const { return field.empty() ? range : field_range(field); }

std::string ParamSpec::unit_name() const {
  if (field.empty()) return unit;
  field_range(field);  // throws for a key not in the table
  return params::find_key(field)->unit;
}

namespace {

/// strtod with a full-consumption check; nullopt when the text is not a number. May return
/// non-finite values ("inf", "nan", overflow), which callers reject with their own message.
std::optional<double> to_double(const std::string& s) {
  if (s.empty() || is_space(s.front())) return std::nullopt;  // strtod would skip leading blanks
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size()) return std::nullopt;
  return v;  // ERANGE overflow gives +-HUGE_VAL (non-finite); underflow gives a finite value
}

/// `x,y` as two finite numbers (blanks around each allowed when `blanks`); `label` names the value in
/// the messages ("track line: from").
core::Vec2 xy(const std::string& text, const std::string& label, bool blanks) {
  const std::size_t comma = text.find(',');
  if (comma == std::string::npos || text.find(',', comma + 1) != std::string::npos) {
    fail(label + " must be x,y, got '" + text + "'");
  }
  const auto part = [&](std::string s) { return to_double(blanks ? util::trim(s) : s); };
  const std::optional<double> x = part(text.substr(0, comma));
  const std::optional<double> y = part(text.substr(comma + 1));
  if (!x || !y) fail(label + ": not a number: '" + text + "'");
  if (!std::isfinite(*x) || !std::isfinite(*y)) fail(label + " must be finite, got " + text);
  return core::Vec2(*x, *y);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Args

Args::Args(std::string name, const std::vector<Token>& tokens, std::size_t first,
           std::vector<ParamSpec> params, std::size_t max_positionals)
    : name_(std::move(name)), params_(std::move(params)) {
  for (std::size_t i = first; i < tokens.size(); ++i) {
    const Token& t = tokens[i];
    if (!t.is_pair) {
      if (positionals_.size() >= max_positionals) fail(name_ + ": unexpected argument '" + t.text + "'");
      positionals_.push_back(t.text);
      continue;
    }
    if (t.key.empty()) fail(name_ + ": missing parameter name in '" + t.text + "'");
    bool known = false;
    for (const ParamSpec& p : params_) known = known || t.key == p.key;
    if (!known) {
      fail(name_ + ": unknown parameter '" + t.key + "' " +
           (params_.empty() ? std::string("(takes no key=value parameters)")
                            : "(expected " + params::join(keys(), ", ") + ")"));
    }
    if (!pairs_.emplace(t.key, t.value).second) fail(name_ + ": duplicate parameter " + t.key);
  }
}

std::vector<std::string> Args::keys() const {
  std::vector<std::string> out;
  for (const ParamSpec& p : params_) out.push_back(p.key);
  return out;
}

const ParamSpec& Args::declared(const std::string& key) const {
  for (const ParamSpec& p : params_)
    if (p.key == key) return p;
  throw std::logic_error(name_ + " declares no parameter '" + key + "'");
}

const std::string& Args::raw(const std::string& key) const {
  const auto it = pairs_.find(key);
  if (it == pairs_.end()) fail(name_ + ": missing parameter " + key);
  return it->second;
}

double Args::number(const std::string& key) const {
  return check_number(key, raw(key), declared(key).bounds());
}

double Args::number_or(const std::string& key, double fallback) const {
  return has(key) ? number(key) : fallback;
}

double Args::check_number(const std::string& label, const std::string& text, const Range& bound) const {
  const std::string owner = label.empty() ? name_ : name_ + ": " + label;
  const std::optional<double> v = to_double(text);
  if (!v) fail(owner + ": not a number: '" + text + "'");
  if (!std::isfinite(*v)) fail(owner + " must be finite, got " + text);
  if (!bound.contains(*v)) fail(owner + " " + bound.text_for(*v) + ", got " + text);
  return *v;
}

core::Vec2 Args::vec2(const std::string& key) const { return xy(raw(key), name_ + ": " + key, false); }

bool Args::on_off_or(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const std::string& text = raw(key);
  if (text == "on") return true;
  if (text == "off") return false;
  fail(name_ + ": " + key + " must be on or off, got '" + text + "'");
}

core::Vec2 Args::centre() const { return core::Vec2(number_or("cx", 0.0), number_or("cy", 0.0)); }

std::vector<core::Vec2> Args::points(const std::string& key) const { return check_points(key, raw(key)); }

core::Vec2 Args::check_vec2(const std::string& label, const std::string& text) const {
  return xy(text, name_ + ": " + label, false);
}

std::vector<core::Vec2> Args::check_points(const std::string& key, const std::string& text) const {
  std::vector<core::Vec2> out;
  if (util::trim(text).empty()) return out;
  std::size_t begin = 0;
  for (std::size_t n = 1;; ++n) {
    const std::size_t semi = text.find(';', begin);
    const std::string item =
        util::trim(text.substr(begin, semi == std::string::npos ? std::string::npos : semi - begin));
    out.push_back(xy(item, name_ + ": " + key + ": point " + std::to_string(n), true));
    if (semi == std::string::npos) break;
    begin = semi + 1;
  }
  return out;
}

void Args::placement(core::ShapeSpec& s) const {
  s.rotation = params::radians(number_or("rot", 0.0));
  s.scale = number_or("scale", 1.0);
}

}  // namespace shapeform::supervisor
