#pragma once
/// Conversions between wire messages and core types, and validation of received samples.
/// Received data is never trusted: non-finite numbers, unknown names and absurd values are rejected
/// with a message naming the field.
#include <cstdint>
#include <string>

#include "core/command.hpp"
#include "core/metrics.hpp"
#include "shapeform/msg/AgentState.h"
#include "shapeform/msg/ShapeCommand.h"
#include "shapeform/msg/SwarmMetrics.h"

namespace shapeform::dds {

/// The only control law understood so far (ShapeCommand.law).
inline constexpr const char* kLawPaper = "paper";

/// Largest |x|, |y| and speed accepted in an AgentState.
inline constexpr double kStateLimit = 1e6;

/// core::Command -> wire message with the given epoch (law = "paper").
msg::ShapeCommand to_msg(const core::Command& cmd, std::uint32_t epoch);

/// Wire message -> core::Command. On failure returns false, leaves `out` untouched and sets `error`
/// to every problem found, separated by "; ", each naming its field, e.g.
/// "command.sigma: must be > 0, got -1". Checks: every number finite; shape_kind, path_kind,
/// integrator, law known; r0, a, b, sigma, dt, path_period > 0; k1, k2, beta, r, max_speed,
/// path_radius >= 0. The epoch is not part of core::Command: read m.epoch().
bool from_msg(const msg::ShapeCommand& m, core::Command& out, std::string& error);

/// True when s is plausible: id >= 0, model_time, x, y, vx, vy finite, |x|, |y| <= kStateLimit and
/// speed |(vx, vy)| <= kStateLimit. Otherwise false with `why` naming the field ("state.x: ...").
bool valid_state(const msg::AgentState& s, std::string& why);

/// core::Metrics -> wire message; undefined (nullopt) values become -1.
msg::SwarmMetrics to_msg(const core::Metrics& m, std::uint32_t epoch, double model_time,
                         std::int64_t stamp_ns, bool converged);

/// Wire message -> core::Metrics; negative (-1) or non-finite values become nullopt.
core::Metrics from_msg(const msg::SwarmMetrics& m);

}  // namespace shapeform::dds
