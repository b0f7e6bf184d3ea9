// DDS wiring of shapeform_vehicle: each robot's commands into its Robot, a step, its pose out. No maths.
#include "vehicle_node.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>

#include "dds/node.hpp"
#include "dds/participant.hpp"
#include "core/params.hpp"
#include "dds/vehicle_io.hpp"
#include "robot.hpp"
#include "util/clock.hpp"
#include "util/log.hpp"
#include "util/rate_loop.hpp"
#include "util/signals.hpp"

namespace shapeform::vehicle {
namespace {

void emit(const nlohmann::json& j) { std::cout << j.dump() << std::endl; }

/// Rows of vehicles.csv per second.
constexpr double kRecordHz = 10.0;

class VehicleNode {
 public:
  VehicleNode(const std::vector<std::int32_t>& ids, const std::vector<core::Vec2>& starts, const config::Config& cfg,
              const VehicleOptions& opt)
      : ids_(ids),
        cfg_(cfg),
        opt_(opt),
        node_(dds::with_identity(cfg.transport, "vehicle"), "shapeform_vehicle_" + std::to_string(ids.front())),
        loop_(cfg.vehicle_sim.pose_rate_hz),
        period_s_(1.0 / cfg.vehicle_sim.pose_rate_hz),
        record_every_(std::max<long>(1, std::lround(cfg.vehicle_sim.pose_rate_hz / kRecordHz))),
        status_every_(std::max<long>(1, std::lround(cfg.vehicle_sim.pose_rate_hz))) {
    const config::VehicleLink& link = cfg.vehicle_link;
    const core::BodyParams body{cfg.vehicle_sim.response_s};
    for (std::size_t k = 0; k < ids.size(); ++k) {
      const std::int32_t id = ids[k];
      robots_.emplace_back(cfg.vehicle, body, starts[k], core::start_heading(cfg.vehicle, id, cfg.swarm.seed),
                           static_cast<std::int64_t>(cfg.vehicle_sim.command_timeout_s * 1e9),
                           cfg.vehicle_sim.pose_noise_m, cfg.swarm.seed * 1000003u + static_cast<std::uint64_t>(id));
      dds::VehicleTopics t;
      t.ns = link.namespace_of(id);
      t.cmd_topic = config::VehicleLink::with_id(link.cmd_topic, id);
      t.cmd_stamped = link.cmd_type == config::VehicleLink::CmdType::TwistStamped;
      t.pose_topic = config::VehicleLink::with_id(link.pose_topic, id);
      t.pose_stamped = link.pose_type == config::VehicleLink::PoseType::PoseStamped;
      drivers_.emplace_back(node_, t);
      stopped_.push_back(true);
    }
    if (!opt.record_dir.empty()) {
      std::filesystem::create_directories(opt.record_dir);
      const std::string path = (std::filesystem::path(opt.record_dir) / "vehicles.csv").string();
      csv_.reset(std::fopen(path.c_str(), "w"));
      if (!csv_) throw std::runtime_error("cannot write " + path);
      std::fprintf(csv_.get(), "t_s,id,x,y,base_x,base_y,heading,v,vy,w,stopped\n");
    }
  }

  int run() {
    start_ns_ = util::steady_ns();
    while (loop_.wait_next(util::stop_flag())) tick();
    util::log_info("stopping after " + std::to_string(ticks_) + " ticks (signal " +
                   std::to_string(util::stop_signal()) + ")");
    if (opt_.json) emit({{"event", "stop"}, {"ticks", ticks_}, {"signal", util::stop_signal()}});
    return 0;
  }

 private:
  void tick() {
    node_.recover(period_s_);  // it logs why
    const std::int64_t now = util::steady_ns();
    for (std::size_t k = 0; k < robots_.size(); ++k) {
      drivers_[k].drain(commands_);
      for (const dds::CommandItem& c : commands_) {
        if (c.valid) {
          robots_[k].on_command(c.sample, c.receive_stamp_ns);
          continue;
        }
        if (throttled_.warn("command " + c.why.substr(0, c.why.find(':')),
                            drivers_[k].topics().ns + ": command refused: " + c.why) &&
            opt_.json)
          emit({{"event", "rejected"}, {"id", ids_[k]}, {"why", c.why}});
      }
      Robot& r = robots_[k];
      if (r.step(now, period_s_)) {
        util::log_warn(drivers_[k].topics().ns + ": no command for " +
                       std::to_string(cfg_.vehicle_sim.command_timeout_s) +
                       " s (vehicle_sim.command_timeout_s): stopped by the watchdog");
        if (opt_.json) emit({{"event", "watchdog"}, {"id", ids_[k]}});
      }
      const bool stopped = r.stopped_by_watchdog(now);
      if (stopped_[k] && !stopped) {
        util::log_info(drivers_[k].topics().ns + ": commands coming, driving");
        if (opt_.json) emit({{"event", "resumed"}, {"id", ids_[k]}});
      }
      stopped_[k] = stopped;
      dds::PoseSample p = r.pose();
      p.stamp_ns = util::system_ns();
      p.frame_id = cfg_.vehicle_link.frame;
      p.child_frame_id = drivers_[k].topics().ns + "/" + cfg_.vehicle_sim.child_frame;
      drivers_[k].publish(p);
    }
    if (csv_ && ticks_ % record_every_ == 0) record(now);
    if (ticks_ % status_every_ == 0 && opt_.json) status();
    ++ticks_;
  }

  void record(std::int64_t now) {
    const double t = static_cast<double>(now - start_ns_) * 1e-9;
    for (std::size_t k = 0; k < robots_.size(); ++k) {
      const Robot& r = robots_[k];
      const core::Vec2 x = r.point();
      const core::Body& b = r.body();
      std::fprintf(csv_.get(), "%.4f,%d,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%d\n", t, ids_[k], x.x(), x.y(),
                   b.base.x(), b.base.y(), b.heading, b.actual.vx, b.actual.vy, b.actual.wz, stopped_[k] ? 1 : 0);
    }
    std::fflush(csv_.get());
  }

  void status() {
    for (std::size_t k = 0; k < robots_.size(); ++k) {
      const Robot& r = robots_[k];
      const core::Vec2 x = r.point();
      emit({{"event", "status"}, {"id", ids_[k]}, {"x", x.x()}, {"y", x.y()},
            {"base", {r.body().base.x(), r.body().base.y()}}, {"heading", r.body().heading},
            {"commands", r.commands()}, {"watchdog_stops", r.watchdog_stops()}, {"stopped", bool(stopped_[k])},
            {"command_writers", drivers_[k].command_writers()}});
    }
  }

  struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };

  const std::vector<std::int32_t> ids_;
  const config::Config& cfg_;
  const VehicleOptions opt_;
  dds::Node node_;
  std::vector<Robot> robots_;
  std::vector<dds::VehicleDriver> drivers_;
  std::vector<bool> stopped_;  ///< per robot: held by its watchdog at the last tick
  std::vector<dds::CommandItem> commands_;
  util::RateLoop loop_;
  util::ThrottledLog throttled_{5.0};
  const double period_s_;
  const long record_every_, status_every_;
  std::unique_ptr<std::FILE, FileCloser> csv_;
  std::int64_t start_ns_ = 0;
  long ticks_ = 0;
};

}  // namespace

int run_vehicles(const std::vector<std::int32_t>& ids, const std::vector<core::Vec2>& starts,
                 const config::Config& cfg, const VehicleOptions& opt) {
  util::log_init("vehicle " + std::to_string(ids.front()) + (ids.size() > 1 ? ".." + std::to_string(ids.back()) : ""));
  util::install_stop_signals();
  const config::VehicleLink& link = cfg.vehicle_link;
  util::log_info(std::to_string(ids.size()) + " simulated robot(s) " + std::string(core::to_string(cfg.vehicle.model)) +
                 ", poses on rt/" + link.namespace_of(ids.front()) + "/" + link.pose_topic + " ... at " +
                 core::params::format_number(cfg.vehicle_sim.pose_rate_hz) + " Hz, " +
                 dds::describe(dds::with_identity(cfg.transport, "vehicle")));
  if (opt.json) emit({{"event", "start"}, {"ids", ids}, {"namespace", link.ns}, {"pose_topic", link.pose_topic},
                      {"cmd_topic", link.cmd_topic}});
  try {
    VehicleNode node(ids, starts, cfg, opt);
    return node.run();
  } catch (const std::exception& e) {
    util::log_error(e.what());
    return 1;
  }
}

}  // namespace shapeform::vehicle
