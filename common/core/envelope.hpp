#pragma once
/// The safe operating envelope: the one check of a command against its workspace (Command::workspace,
/// `safety.workspace`) and against gains no formation can follow. The config loader, the console
/// parser and the command topic's receiver (dds::from_msg) all refuse a command for which it finds a
/// problem, with the same message; core::agent_step keeps every agent inside the workspace whatever
/// it is told. Pure: Eigen and the standard library only.
#include <string>
#include <vector>

#include "compiled_command.hpp"

namespace shapeform::core {

/// Largest accepted workspace half-width (shape units): every position an agent can take stays an
/// order of magnitude inside the bound every receiver accepts (dds::kStateLimit = 1e6).
inline constexpr double kWorkspaceMax = 1e5;

/// Largest step gain (gain x dt x sigma^(-2 beta) for k1 and k2, k_normal x dt for the arc law)
/// without a speed limit: above 2 one Euler step overshoots the target by more than it corrects, so
/// the error doubles step after step and the swarm leaves any workspace.
inline constexpr double kStepGainMaxFree = 2.0;
/// ... and with a speed limit (max_speed > 0), which bounds the overshoot's growth to max_speed x dt
/// per step: agents oscillate about their targets but stay within reach. Above this nothing a
/// formation could follow is left (every step overshoots by 9 times the distance).
inline constexpr double kStepGainMaxLimited = 10.0;

/// One reason a command is outside the envelope.
struct EnvelopeProblem {
  std::string key;   ///< config key ("dynamics.k1", "shape.centre")
  std::string wire;  ///< ShapeCommand field ("k1", "cx")
  std::string text;  ///< "dynamics.k1 = 1e+300: ..." (names the key and the value)
};

/// Every problem of cmd: its shape (placed by centre, rotation and scale) or its tracked path must lie
/// within the workspace [-workspace, workspace]^2, its fence must be usable and inside the workspace
/// (core::fence_problems), and its step gains within kStepGainMax*.
/// Empty when the command is safe.
std::vector<EnvelopeProblem> envelope_problems(const CompiledCommand& cmd);

/// The problems' texts joined by "; " ("" when none).
std::string envelope_text(const std::vector<EnvelopeProblem>& problems);

/// Largest distance from the shape's centre of any point of cmd's curve as placed (scale applied);
/// for the infinite line, the distance of its point nearest the centre.
double shape_reach(const CompiledCommand& cmd);

/// Where the law leaves an agent at a step's end: `next` moved into [-workspace, workspace]^2. Sets
/// `clamped` when it had to move it.
Vec2 keep_inside(const Vec2& next, double workspace, bool& clamped);

}  // namespace shapeform::core
