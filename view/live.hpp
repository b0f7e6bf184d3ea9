#pragma once
/// The live viewer's DDS side: a read-only participant (dds::Node from the transport profile of the
/// config) with a reader on each of the project's topics and no writer at all. Each call drains what
/// arrived into the Scene.
#include <memory>

#include "config/config.hpp"
#include "scene.hpp"

namespace shapeform::view {

class LiveFeed {
 public:
  /// Joins the domain of cfg.transport. Throws std::runtime_error naming the entity that failed.
  explicit LiveFeed(const config::Config& cfg);
  ~LiveFeed();
  LiveFeed(const LiveFeed&) = delete;
  LiveFeed& operator=(const LiveFeed&) = delete;

  /// Drains every reader into scene (now_s: the viewer's clock); rebuilds the participant after a
  /// stall (dds::Node::recover_if_stalled, period_s: the loop's period).
  void drain(Scene& scene, double now_s, double period_s);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shapeform::view
