#include "command.hpp"

#include "params.hpp"

namespace shapeform::core {

ShapeSpec shape_at(const Command& cmd, double t) {
  ShapeSpec s = cmd.shape;
  if (cmd.tracking.enabled) s.centre = centre_at(cmd.tracking.path, t);
  return s;
}

std::string_view to_string(Law l) { return params::name_of(params::kLawNames, l); }

bool parse_law(std::string_view name, Law& out) { return params::parse_name(params::kLawNames, name, out); }

}  // namespace shapeform::core
