#pragma once
/// Explicit integrators for one agent's own state (other agents held fixed during a step).
#include <string_view>

#include "types.hpp"

namespace shapeform::core {

enum class Integrator { Euler, RK4 };

std::string_view to_string(Integrator i);
bool parse_integrator(std::string_view name, Integrator& out);

/// One step of dx/dt = f(x, t) from (x, t) over dt. f is any callable Vec2(const Vec2&, double).
/// Euler: x + dt f(x, t). RK4: the classical four-stage scheme.
template <class F>
Vec2 integrate(Integrator method, F&& f, const Vec2& x, double t, double dt) {
  if (method == Integrator::Euler) return x + dt * f(x, t);
  const Vec2 k1 = f(x, t);
  const Vec2 k2 = f(x + 0.5 * dt * k1, t + 0.5 * dt);
  const Vec2 k3 = f(x + 0.5 * dt * k2, t + 0.5 * dt);
  const Vec2 k4 = f(x + dt * k3, t + dt);
  return x + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
}

}  // namespace shapeform::core
