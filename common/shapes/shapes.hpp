#pragma once
/// Compiles shapes into their curves, including shapes given by equations (muparser): polar r(phi),
/// parametric x(s), y(s), implicit f(x, y) = 0. Every entry point that accepts a shape (config,
/// console, the command topic's receiver) calls compile() once per command and reports a ShapeError
/// as bad input.
#include <memory>

#include "core/compiled_command.hpp"
#include "core/shape.hpp"

namespace shapeform::shapes {

/// The curve of any shape kind (core::make_curve for the analytic kinds and polygons), after checks
/// of its placement (scale > 0, finite centre and rotation). Throws core::ShapeError with a message
/// naming the shape, the expression and what is wrong (e.g. "polar: r(phi) = '4+foo': Unexpected
/// token...").
std::shared_ptr<const core::Curve> compile_curve(const core::ShapeSpec& spec);

/// cmd with the curve of its shape (compile_curve).
core::CompiledCommand compile(const core::Command& cmd);

/// Half side of the box in which implicit curves are traced (shape-local units).
inline constexpr double kImplicitHalfBox = 20.0;

}  // namespace shapeform::shapes
