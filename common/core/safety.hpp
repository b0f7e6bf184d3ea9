#pragma once
/// The safety filter of one agent's step (issue 27): the law's wanted new position moved as little as
/// possible so that the agent keeps `safety.min_separation` from every neighbour it hears, stays out
/// of every keep-out zone (`safety.keep_out`) and inside the geofence shrunk by its margin
/// (`safety.fence`, `safety.fence_margin`; fence.hpp).
///
/// Method: buffered Voronoi cells (Zhou, Wang, Bandyopadhyay, Schwager, "Fast, on-line collision
/// avoidance for dynamic vehicles using buffered Voronoi cells", RA-L 2017). Agent i at x_i hearing
/// neighbour j at x_j (|x_j - x_i| = D, n = (x_j - x_i) / D) keeps its next position p in the half-plane
///
///     n . p <= n . (x_i + x_j) / 2 - d / 2 - margin_j,     margin_j = max_speed_j * age_j,
///
/// the agent's half of the gap minus the separation, shrunk by how far j may have moved since its
/// sample. The cell (those half-planes, one separating half-plane per convex piece of every keep-out
/// zone and the speed disc |p - x_i| <= max_step) is convex and holds x_i, so the whole straight
/// segment from x_i to p stays in it. p is the point of the cell nearest the wanted position: a 2-D
/// quadratic programme solved exactly (closest_feasible).
///
/// Guarantee (synchronous states, age 0: the simulator, lockstep agents): two agents that step from
/// positions at least d apart each stay in their own half of the gap, so their new positions, and every
/// pair of points on their straight segments at the same fraction of the step, are at least d apart.
/// With a half-plane that x_i itself breaks (the pair is already closer than d + 2 margin: a late
/// joiner placed on top, a rogue, a stale sample) the constraint becomes "do not approach" (n . p <=
/// n . x_i): two agents that both obey it never come closer, and x_i is always in the cell, so the
/// programme always has a solution. A neighbour closer than d is counted (`broken`), and the agent
/// takes the largest safe step away from it instead of the law's.
///
/// Stale states (agent processes): a sample of age a from a neighbour whose speed is at most v may be
/// v a off (margin_j = max_speed_j * age_j). The half-planes then come from two different views and
/// are no longer parallel, so they are not enough (an antipodal swap of 16 agents seeing one-step-old
/// states came to 0.9 d with them alone: safety_test.cpp). The step also stays in the disc of radius
/// (|x_j^ - x_i| - margin_j - d) / 2 about x_i: since |x_j^ - x_i| <= D + margin_j, each agent moves at
/// most half the true gap beyond d, whatever its neighbour's view, so the pair keeps d (with a fresh
/// neighbour keeping its exact half-plane, too). This holds when every speed bound is honest and every
/// age is measured; the price is that an agent within d + margin of a stale neighbour stands still.
///
/// Double integrators (SafetyParams::braking): a vehicle that cannot stop within one step can keep its
/// position in its cell and still carry on out of it. Each agent is then its braking segment B = [x, x +
/// braking_displacement(v)], and the cells separate segments: the half-plane against j passes between
/// the closest points p_i of B_i and p_j of B_j (D = |p_j - p_i|, n = (p_j - p_i) / D) at d / 2 from the
/// middle, and the agent keeps its new segment [x1, stop1] in it. B_i lies behind n . p_i, so braking
/// one more step (whose segment is a part of B_i) always keeps the cell: the programme always has a
/// solution, and two agents at least d apart as segments stay so, positions and the whole motion of the
/// step included (the step's path is a parabola inside the triangle x, x + h v0 / 2, x1, all in the cell).
/// Stale or blurred neighbours (margin r = max_speed * age + blur, max_speed here the mean speed of the
/// segment's ends over the age, braking_reach): the new segment stays within (D - r - d) / 2 of B_i (`grow`), which with the
/// neighbour doing the same keeps d whatever their views (the segment analogue of the disc above); none
/// is left (a stale neighbour too near) and the agent brakes, or, with exactly one such neighbour, backs
/// away from it (SafetyOutcome::away) as the integrator does. Zones and the fence are kept the same way
/// (half-planes that hold B_i). The velocity is chosen by drive_safely.
///
/// Deadlock: a step cut to below `stuck_fraction` of the law's while the law asks for more than
/// `stuck_min_step` is "held"; after `stuck_steps` held steps in a row the agent turns its wanted step
/// by `sidestep_deg` clockwise (the right-hand rule of Zhou et al.: two agents meeting head-on both
/// keep right) for `stuck_steps` steps, counted. An agent held for longer than that is reported
/// (SafetyState::held, SafetyOutcome::blocking_id), so a caller can say which agents the filter keeps
/// from their slots.
///
/// Pure: Eigen and the standard library; no clock (ages are given).
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "command.hpp"
#include "half_plane.hpp"
#include "types.hpp"
#include "vehicle.hpp"

namespace shapeform::core {

/// A neighbour as the safety filter sees it.
struct SafetyNeighbour {
  std::int32_t id = 0;
  Vec2 x = Vec2::Zero();   ///< its last known position, shape units
  double age_s = 0.0;      ///< how old x is, s (0: a state of this very step)
  double max_speed = 0.0;  ///< bound on its speed, shape units per s: its margin is max_speed * age_s
  /// Double integrators (SafetyParams::braking): its braking displacement (braking_displacement) at x,
  /// shape units, so that it is known as the segment [x, x + brake]; max_speed then bounds how fast
  /// that segment's ends move on average over age_s (braking_reach / age_s), and blur how far its true
  /// segment may lie from this one at the sample's time (a velocity known only as the mean of its last step).
  Vec2 brake = Vec2::Zero();
  double blur = 0.0;
};

/// The filter's settings (from the command: Command::min_separation, Command::keep_out, the speed limit).
struct SafetyParams {
  double min_separation = 0.0;   ///< d, shape units; 0: no separation kept (zones alone, if any)
  double max_step = 0.0;         ///< radius of the speed disc: the longest step, shape units; 0: none
  int stuck_steps = 5;           ///< K: held steps in a row before a sidestep, and the sidestep's length
  double stuck_fraction = 0.1;   ///< a step cut below this fraction of the law's is held
  double stuck_min_step = 1e-3;  ///< shape units: a law step shorter than this does not ask to move
  double sidestep_deg = 60.0;    ///< clockwise turn of the wanted step while sidestepping
  /// The fence shrunk by its margin (core::fence_half_planes: the workspace box's 4 sides, or one per
  /// fence edge) that the step stays in; empty: none. A side that x itself breaks becomes "go no
  /// further out" (n . p <= n . x), so an agent outside is never pushed further out and always has a step.
  std::vector<HalfPlane> fence;
  /// The agents are double integrators, which cannot stop at once: each keeps its braking segment
  /// (where it would stop braking as hard as it may), not only its position, in its cell (see below).
  bool braking = false;
};

/// Whether a command's steps go through the filter: safety.min_separation > 0, a keep-out zone, a
/// fence polygon or a fence margin > 0. Otherwise the law's steps are taken bit for bit (the law alone
/// keeps to the workspace box: core::keep_inside).
bool filters(const Command& cmd);

/// The filter's settings for a command and the vehicle that moves the agent: d and the fence (shrunk by
/// its margin: fence_half_planes) from the command, the speed disc the tighter of the command's max_speed *
/// dt and the vehicle's max_speed * dt * seconds_per_model_time (each 0 = none).
SafetyParams safety_params(const Command& cmd, const VehicleParams& vehicle);

/// A convex piece of a keep-out zone: a circle, or a convex polygon (counter-clockwise).
struct ConvexZone {
  bool circle = true;
  Vec2 centre = Vec2::Zero();
  double radius = 0.0;
  std::vector<Vec2> vertices;  ///< counter-clockwise
  int zone = 0;                ///< index of the KeepOutZone it is a piece of
};

/// The problems of a keep-out zone, each a sentence ("radius must be > 0, got -1"); none when usable:
/// a circle with a finite centre and a finite radius > 0; a polygon of >= 3 finite vertices, no two
/// consecutive equal, not all collinear, whose edges do not cross (simple).
std::vector<std::string> keep_out_problems(const KeepOutZone& z);

/// The zones in convex pieces: circles as they are, convex polygons as they are (turned
/// counter-clockwise), other simple polygons cut into triangles (ear clipping). Excluding every piece
/// excludes the zone. Zones with problems (keep_out_problems) are skipped.
std::vector<ConvexZone> convex_pieces(const std::vector<KeepOutZone>& zones);

/// How deep p is inside a zone: its distance to the zone's boundary when inside, 0 outside or on it.
double depth(const KeepOutZone& z, const Vec2& p);

/// Whether p is inside (or on) a piece.
bool inside(const ConvexZone& z, const Vec2& p);
/// The distance from p to a piece (0 inside).
double distance(const ConvexZone& z, const Vec2& p);

/// The buffered Voronoi half-plane of agent `self_id` at x against neighbour j for separation d, its
/// offset shrunk by j's margin (max_speed * age_s), and never below n . x ("do not approach") so that
/// x is always in it. Two agents on one point are told apart by their ids (the lower one steps to
/// -x1). Sets `broken` when j is closer than d.
HalfPlane separation_half_plane(std::int32_t self_id, const Vec2& x, const SafetyNeighbour& j, double d,
                                bool& broken);

/// The half-plane that keeps a piece out from x: the supporting line at the piece's point nearest x.
/// When x is inside the piece: "do not go deeper" (through x, facing the piece's centre), and `in` set.
HalfPlane keep_out_half_plane(const ConvexZone& z, const Vec2& x, bool& in);

/// The point nearest w in the intersection of the half-planes and the disc |p - c| <= r (r <= 0: no
/// disc): the exact solution of the 2-D quadratic programme, found among its candidates (w, w's
/// projection on each line and on the circle, the lines' pairwise intersections, each line's
/// intersections with the circle), keeping the feasible one nearest w. Requires c in every half-plane
/// (then the set is never empty); the answer is c itself when rounding leaves no candidate.
Vec2 closest_feasible(const Vec2& w, const std::vector<HalfPlane>& h, const Vec2& c, double r);

/// What the filter keeps of one agent between steps.
struct SafetyState {
  int held = 0;           ///< consecutive held steps (not counting sidesteps)
  int sidestep_left = 0;  ///< steps of the current sidestep still to take
};

/// What the filter did on one step.
struct SafetyOutcome {
  Vec2 x = Vec2::Zero();          ///< the safe new position
  bool intervened = false;        ///< x is not the wanted position
  bool sidestep = false;          ///< the wanted step was turned (a deadlock sidestep is under way)
  bool sidestep_started = false;  ///< this step began a sidestep (a deadlock resolution, counted)
  bool held = false;              ///< the law asks to move and the step was cut below stuck_fraction of it
  int broken = 0;                 ///< neighbours already closer than d: the agent stepped away from them
  int inside_zones = 0;           ///< keep-out pieces the agent was already in (a zone set over it): it steps out
  /// The neighbour whose half-plane binds at x (the nearest binding one), -1 when none does; with a
  /// zone binding instead, blocking_zone is its index.
  std::int32_t blocking_id = -1;
  int blocking_zone = -1;
  /// The cell the step was kept in (every half-plane and the disc |p - from| <= max_step): the
  /// vehicle's motion can be checked against it (drive_safely).
  std::vector<HalfPlane> cell;
  Vec2 from = Vec2::Zero();
  double max_step = 0.0;  ///< the disc's radius (0: none); with stale neighbours, their discs' too
  bool still = false;     ///< a stale neighbour too near for any step: the cell is `from` alone
  /// Whether p is in the cell (to rounding).
  bool in_cell(const Vec2& p) const;
  /// Braking (SafetyParams::braking): the agent's braking segment at the step's start is [from, from +
  /// brake]; its new one [x1, stop1] must lie in the cell's half-planes and within `grow` of the old
  /// (still: on it). Braking itself always does.
  bool braking = false;
  Vec2 brake = Vec2::Zero();
  double grow = std::numeric_limits<double>::infinity();
  /// Braking, backing off from one stale neighbour too near for any growth: the new segment stays in
  /// the old one's shadow away from it ({b - s away : b in the old segment, s >= 0}, `away` the unit
  /// vector toward the neighbour), which moves no point of it nearer the neighbour's true segment (that
  /// lies beyond the margin); zero otherwise.
  Vec2 away = Vec2::Zero();
  /// Whether a step to x1 whose braking would stop at stop1 keeps the cell (braking), or in_cell(x1).
  bool holds(const Vec2& x1, const Vec2& stop1) const;
};

/// The filter on one agent's step: agent `self_id` at x, the law's wanted new position `wanted`, the
/// neighbours it hears and the zones' convex pieces (convex_pieces). With d = 0 and no zones the
/// answer is `wanted` itself (the caller should not call it then: the law's bits stay untouched).
/// With p.braking, `brake` is the agent's own braking displacement (its velocity's, braking_displacement).
SafetyOutcome safety_filter(const SafetyParams& p, SafetyState& state, std::int32_t self_id, const Vec2& x,
                            const Vec2& wanted, const std::vector<SafetyNeighbour>& nbrs,
                            const std::vector<ConvexZone>& zones, const Vec2& brake = Vec2::Zero());

/// The vehicle's motion on the filter's step: drive toward f.x; when the vehicle would end outside the
/// cell (a double integrator's momentum, a unicycle's linearised steering), the commanded point is
/// chosen again among: the point that lands the vehicle on f.x (the double integrator's v1 = 2 (f.x -
/// x) / h - v0), then the same toward points halfway, a quarter, ... of the way, then standing still;
/// the first that lands in the cell is taken, else the one that lands nearest it. Sets `outside` when
/// none landed in the cell. Braking (a double integrator): the velocity toward f.x when its step and
/// braking segment keep the cell (SafetyOutcome::holds), else the one nearest it on the way from braking
/// (which always keeps it) to it, by bisection.
StepResult drive_safely(const VehicleParams& p, VehicleState& s, const StepResult& law,
                        const SafetyOutcome& f, double dt, double workspace, bool& outside);

}  // namespace shapeform::core
