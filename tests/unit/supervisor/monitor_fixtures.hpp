#pragma once
/// What the SwarmMonitor and presentation tests share: the paper's circle and agents placed on a ring.
#include <cmath>
#include <cstdint>

#include "core/compiled_command.hpp"
#include "swarm_monitor.hpp"

namespace shapeform::test {

/// One second, ns.
inline constexpr std::int64_t kS = 1'000'000'000;

/// The circle of radius 4 about the origin, compiled.
inline core::CompiledCommand circle() {
  core::Command c;
  c.shape.kind = core::ShapeKind::Circle;
  c.shape.r0 = 4;
  return core::compile(c);
}

/// Agents 0..n-1 evenly on a ring of `radius` about the origin, following `epoch`, heard at now.
inline void ring(supervisor::SwarmMonitor& m, int n, double radius, std::uint64_t epoch, std::int64_t now) {
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    const core::Vec2 x = radius * core::Vec2(std::cos(a), std::sin(a));
    m.on_state(i, x, x, epoch, 0.0, now);
  }
}

/// A status of agent id hearing `heard` neighbours, following `epoch`.
inline dds::StatusSample status(std::int32_t id, int heard, std::uint64_t epoch = 1) {
  dds::StatusSample s;
  s.id = id;
  s.neighbours_heard = heard;
  s.epoch = epoch;
  return s;
}

}  // namespace shapeform::test
