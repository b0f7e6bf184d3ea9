#include "foxglove_scene.hpp"

#include <cstring>

namespace shapeform::view {

viz::SceneSnapshot foxglove_snapshot(const Scene& scene, double now_s) {
  viz::SceneSnapshot s;
  s.agents.reserve(scene.agents().size());
  for (const auto& [id, a] : scene.agents()) {
    viz::AgentDraw d;
    d.id = id;
    d.x = a.x;
    const char* look = scene.state(a, now_s);
    d.look = std::strcmp(look, "alive") == 0   ? viz::AgentLook::Alive
             : std::strcmp(look, "stale") == 0 ? viz::AgentLook::Stale
                                               : viz::AgentLook::Dead;
    if (a.heading && now_s - a.heading_seen_s <= scene.params().dead_s) d.heading = a.heading;
    s.agents.push_back(d);
  }
  if (const auto& cmd = scene.command()) {
    s.outline = core::outline(*cmd, scene.model_time(), s.outline_closed, scene.params().outline_points);
    s.keep_out = cmd->keep_out;
    s.fence = cmd->fence;
    s.fence_margin = cmd->fence_margin;
  }
  s.centre = scene.centre();
  return s;
}

}  // namespace shapeform::view
