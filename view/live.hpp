#pragma once
/// The live viewer's DDS side: a read-only participant (dds::Node from the transport profile of the
/// config) with a reader on each of the project's topics and no writer at all. Each call drains what
/// arrived into the Scene.
#include <cstdint>
#include <memory>
#include <vector>

#include "config/config.hpp"
#include "dds/topics.hpp"
#include "scene.hpp"

namespace shapeform::view {

/// Where the raw samples the feed reads go as well (the Foxglove server): asked per topic first, so
/// that a sample is serialized only when someone takes it.
class SampleSink {
 public:
  virtual ~SampleSink() = default;
  virtual bool wants(dds::TopicId topic) const = 0;
  /// A valid sample of topic, as its CDR bytes on the wire (dds::to_cdr).
  virtual void on_sample(dds::TopicId topic, std::vector<std::uint8_t> cdr) = 0;
};

class LiveFeed {
 public:
  /// Joins the domain of cfg.transport. Throws std::runtime_error naming the entity that failed.
  explicit LiveFeed(const config::Config& cfg);
  ~LiveFeed();
  LiveFeed(const LiveFeed&) = delete;
  LiveFeed& operator=(const LiveFeed&) = delete;

  /// Drains every reader into scene (now_s: the viewer's clock); rebuilds the participant after a
  /// stall or a split (dds::Node::recover, period_s: the loop's period).
  void drain(Scene& scene, double now_s, double period_s);

  /// Every valid sample drained from now on also goes to sink (nullptr: none). The sink must outlive
  /// the feed or be reset first.
  void set_sink(SampleSink* sink);

  /// The topics the feed reads (each of its readers'), in the topic table's order.
  static std::vector<dds::TopicId> topics();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shapeform::view
