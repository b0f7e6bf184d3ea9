#pragma once
/// A command ready to run: the plain Command and the curve compiled from its shape. A command is
/// compiled once where it enters (config loader, console, command topic), never per step; copies
/// share the immutable curve.
#include <memory>
#include <vector>

#include "command.hpp"
#include "curve.hpp"

namespace shapeform::core {

/// A Command (sent, saved and described as one) that also owns the curve of its shape, in the
/// shape's local frame: on a copy the placement (centre, rotation, scale) and every field outside the
/// shape may change and the curve stays right; a new shape is compiled anew (compile,
/// shapes::compile).
class CompiledCommand : public Command {
 public:
  /// The default Command (the paper's circle), compiled.
  CompiledCommand();
  /// cmd with `curve`, the curve compiled from cmd.shape. Throws std::invalid_argument when null.
  CompiledCommand(Command cmd, std::shared_ptr<const Curve> curve);
  const Curve& curve() const { return *curve_; }

 private:
  std::shared_ptr<const Curve> curve_;
};

/// cmd with the curve of its analytic shape or polygon (make_curve). Throws ShapeError for the
/// expression kinds (shapes::compile builds every kind) and for bad parameters.
CompiledCommand compile(const Command& cmd);

/// Points of the commanded shape at model time t (tracked shapes about C(t)), in world coordinates:
/// `n` points spread evenly by arc length on a closed curve (`closed` set true: the last joins the
/// first), n + 1 from end to end on an open one, and for the (infinite) line n + 1 points over
/// +-line_half_length (shape units, before scale) about the foot of the shape's origin. Empty when n < 2.
std::vector<Vec2> outline(const CompiledCommand& cmd, double t, bool& closed, int n = 240,
                          double line_half_length = 100.0);

}  // namespace shapeform::core
