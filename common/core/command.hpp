#pragma once
/// What an agent is told to do: the plain command description that travels in config files, on the
/// console and on the wire. The curve of its shape is compiled once per command (CompiledCommand).
#include <string_view>
#include <vector>

#include "integrator.hpp"
#include "law_arc.hpp"
#include "law_paper.hpp"
#include "shape.hpp"

namespace shapeform::core {

/// Which control law the agents run.
enum class Law {
  Paper,  ///< Goswami et al. eq. 2 (the default, untouched)
  Arc     ///< arc-length slots: exact, evenly spaced, chatter-free (docs/LAW.md)
};
std::string_view to_string(Law l);
bool parse_law(std::string_view name, Law& out);

/// What an agent found beyond the geofence does (`safety.breach_action`; docs/SAFETY.md, "Geofence").
enum class BreachAction {
  Hold,   ///< the agent stops and the supervisor holds the whole swarm (as the console's `hold`)
  Stop,   ///< that agent stops until the next command
  Return  ///< the agent heads straight back to core::fence_return_point, then follows the law again
};
std::string_view to_string(BreachAction a);
bool parse_breach_action(std::string_view name, BreachAction& out);

/// Tracking: the shape's centre follows a path; the shape is drawn around C(t).
struct Tracking {
  bool enabled = false;
  CentrePath path;
  bool feedforward = false;  ///< add dC/dt to every agent's velocity
};

/// The full command an agent follows (what the supervisor publishes).
struct Command {
  using BreachAction = core::BreachAction;  ///< also spelled Command::BreachAction
  ShapeSpec shape;
  Tracking tracking;
  Gains gains;
  Integrator integrator = Integrator::Euler;
  double dt = 1.0;         ///< model time per step (one paper iteration = 1)
  /// Speed limit in units per model time; 0 = none. The default never binds in any shipped scenario
  /// (the fastest, arc_line, peaks at 4.4; the paper's law at 0.41): it only bounds a mis-tuned
  /// command's steps (config/README.md).
  double max_speed = 10.0;
  /// Half-width of the workspace [-w, w]^2 (shape units): commands that would carry agents outside are
  /// refused (core::envelope_problems) and no step leaves it (core::agent_step).
  double workspace = 1000.0;
  /// Smallest distance two agents keep at every step (shape units); 0 = no separation filter. When > 0
  /// (or with keep-out zones) every agent's step goes through core::safety_filter (safety.hpp).
  double min_separation = 0.0;
  /// Regions no agent enters (core::safety_filter keeps every step out of them).
  std::vector<KeepOutZone> keep_out;
  /// The geofence: a convex polygon the agents stay inside (counter-clockwise or clockwise), in shape
  /// units, world frame; empty: the workspace box [-workspace, workspace]^2 is the fence. Checked by
  /// core::fence_problems (fence.hpp).
  std::vector<Vec2> fence;
  /// Shape units: the filter keeps every step this far inside the fence; an agent beyond the fence
  /// itself is a breach (core::beyond_fence > 0).
  double fence_margin = 0.0;
  /// What an agent found beyond the fence does.
  BreachAction breach_action = BreachAction::Hold;
  Law law = Law::Paper;
  ArcParams arc;
  /// Held (the console's hold / stop): every agent keeps its position (velocity 0) and its model
  /// time stands still, so a tracked centre does not move on either. Cleared by `resume`.
  bool hold = false;
};

/// The shape in force at model time t (tracked shapes are centred on C(t)).
ShapeSpec shape_at(const Command& cmd, double t);

}  // namespace shapeform::core
