#pragma once
/// Compiles a ShapeSpec into its curve, including shapes given by equations (muparser): polar r(phi),
/// parametric x(s), y(s), implicit f(x, y) = 0. Every entry point that accepts a shape (config,
/// console, the command topic's receiver) calls compile() and reports a ShapeError as bad input.
#include "core/command.hpp"
#include "core/shape.hpp"

namespace shapeform::shapes {

/// Fills spec.curve (replacing any previous curve). Throws core::ShapeError with a message naming
/// the shape, the expression and what is wrong (e.g. "polar: r(phi) = '4+foo': Unexpected token...").
void compile(core::ShapeSpec& spec);

/// compile(cmd.shape), plus checks of the command's placement (scale > 0, finite rotation).
void compile(core::Command& cmd);

/// Half side of the box in which implicit curves are traced (shape-local units).
inline constexpr double kImplicitHalfBox = 20.0;

}  // namespace shapeform::shapes
