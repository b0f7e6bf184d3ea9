#include "command.hpp"

namespace shapeform::core {

ShapeSpec shape_at(const Command& cmd, double t) {
  ShapeSpec s = cmd.shape;
  if (cmd.tracking.enabled) s.centre = centre_at(cmd.tracking.path, t);
  return s;
}

}  // namespace shapeform::core
