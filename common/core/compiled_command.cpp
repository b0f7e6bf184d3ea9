#include "compiled_command.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace shapeform::core {

CompiledCommand::CompiledCommand() : CompiledCommand(compile(Command{})) {}

CompiledCommand::CompiledCommand(Command cmd, std::shared_ptr<const Curve> curve)
    : Command(std::move(cmd)), curve_(std::move(curve)) {
  if (!curve_) throw std::invalid_argument("CompiledCommand: no curve");
}

CompiledCommand compile(const Command& cmd) { return CompiledCommand(cmd, make_curve(cmd.shape)); }

std::vector<Vec2> outline(const CompiledCommand& cmd, double t, bool& closed, int n, double line_half_length) {
  const ShapeSpec spec = shape_at(cmd, t);
  const Curve& curve = cmd.curve();
  const double length = curve.length();
  std::vector<Vec2> out;
  closed = curve.closed() && std::isfinite(length);
  if (n < 2) return out;
  out.reserve(static_cast<std::size_t>(n) + 1);
  const double from = std::isfinite(length) ? 0.0 : -line_half_length;
  const double span = std::isfinite(length) ? length : 2.0 * line_half_length;
  const int count = closed ? n : n + 1;
  for (int k = 0; k < count; ++k) {
    const double s = from + span * static_cast<double>(k) / static_cast<double>(n);
    out.push_back(to_world(spec, curve.at(s)));
  }
  return out;
}

}  // namespace shapeform::core
