#include "command.hpp"

namespace shapeform::core {

ShapeSpec shape_at(const Command& cmd, double t) {
  ShapeSpec s = cmd.shape;
  if (cmd.tracking.enabled) s.centre = centre_at(cmd.tracking.path, t);
  return s;
}

std::string_view to_string(Law l) { return l == Law::Paper ? "paper" : "arc"; }

bool parse_law(std::string_view name, Law& out) {
  if (name == "paper") out = Law::Paper;
  else if (name == "arc") out = Law::Arc;
  else return false;
  return true;
}

}  // namespace shapeform::core
