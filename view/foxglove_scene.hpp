#pragma once
/// The viewer's Scene as the snapshot Foxglove's 3-D panel is drawn from (viz::SceneSnapshot): the same
/// agents, states, headings, outline, zones, fence and centre the page shows at now_s.
#include "scene.hpp"
#include "viz/scene_update.hpp"

namespace shapeform::view {

/// The snapshot of scene at now_s: every agent with its look (Scene::state) and its heading when a
/// pose was heard within dead_s; the command's outline at the scene's model time (core::outline, the
/// page's points), its keep-out zones and fence (with its margin); the tracked centre.
viz::SceneSnapshot foxglove_snapshot(const Scene& scene, double now_s);

}  // namespace shapeform::view
