#include "robot.hpp"

namespace shapeform::vehicle {

Robot::Robot(const core::VehicleParams& p, const core::BodyParams& b, const core::Vec2& point, double heading,
             std::int64_t command_timeout_ns, double noise_m, std::uint64_t seed)
    : params_(p), body_params_(b), timeout_ns_(command_timeout_ns), noise_m_(noise_m), rng_(seed) {
  body_.heading = core::vehicle_start(point, heading).heading;
  body_.base = core::base_of(p, point, body_.heading);
}

void Robot::on_command(const dds::VelocitySample& v, std::int64_t now_ns) {
  command_ = {v.vx, v.vy, v.wz};
  command_ns_ = now_ns;
  ++commands_;
}

bool Robot::stopped_by_watchdog(std::int64_t now_ns) const {
  return command_ns_ < 0 || now_ns - command_ns_ > timeout_ns_;
}

bool Robot::step(std::int64_t now_ns, double h) {
  const bool held = stopped_by_watchdog(now_ns);
  const bool just_stopped = held && !held_ && command_ns_ >= 0;
  if (just_stopped) ++watchdog_stops_;
  held_ = held;
  core::body_step(params_, body_params_, body_, held ? core::Twist{} : command_, h);
  return just_stopped;
}

dds::PoseSample Robot::pose() {
  dds::PoseSample p;
  p.x = body_.base;
  if (noise_m_ > 0.0) {
    std::normal_distribution<double> g(0.0, noise_m_);
    p.x += core::Vec2(g(rng_), g(rng_));
  }
  p.yaw = body_.heading;
  p.has_twist = true;
  p.vx = body_.actual.vx;
  p.vy = body_.actual.vy;
  p.wz = body_.actual.wz;
  return p;
}

}  // namespace shapeform::vehicle
