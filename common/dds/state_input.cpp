#include "dds/state_input.hpp"

#include <algorithm>

#include "dds/convert.hpp"

namespace shapeform::dds {

StateInput::StateInput(Node& node)
    : single_(node.reader<msg::AgentState>(TopicId::State)),
      batch_(node.reader<msg::AgentStateBatch>(TopicId::StateBatch)) {}

void StateInput::drain(std::vector<StateItem>& out) {
  out.clear();
  single_.drain(single_buf_);
  for (const auto& r : single_buf_) {
    StateItem item;
    item.receive_stamp_ns = r.receive_stamp_ns;
    item.source = r.source;
    if (!r.valid_data) {
      if (r.key_id < 0) continue;  // an instance never heard alive: nobody to drop
      item.kind = StateItem::Kind::Gone;
      item.id = r.key_id;
      item.instance = r.instance;
    } else if (from_msg(r.msg, item.state, item.why)) {
      item.id = item.state.id;
    } else {
      item.kind = StateItem::Kind::Rejected;
    }
    out.push_back(std::move(item));
  }
  batch_.drain(batch_buf_);
  for (const auto& r : batch_buf_) {
    StateItem item;
    item.receive_stamp_ns = r.receive_stamp_ns;
    item.source = r.source;
    item.batched = true;
    const std::pair<SourceId, std::int32_t> instance{r.source, r.key_id};
    if (!r.valid_data) {
      auto it = carried_.find(instance);
      if (it == carried_.end() && !r.source.known()) {
        // The writer unknown: the instance of that first_id, whoever published it.
        it = std::find_if(carried_.begin(), carried_.end(), [&](const auto& c) { return c.first.second == r.key_id; });
      }
      if (it == carried_.end()) continue;
      item.kind = StateItem::Kind::Gone;
      item.instance = r.instance;
      for (const std::int32_t id : it->second) {
        item.id = id;
        out.push_back(item);
      }
      carried_.erase(it);
      continue;
    }
    if (!valid_batch(r.msg, item.why)) {
      item.kind = StateItem::Kind::Rejected;
      out.push_back(std::move(item));
      continue;
    }
    ++batches_;
    std::vector<std::int32_t>& ids = carried_[instance];
    ids.clear();
    // Each element converted straight into its item (no intermediate list of samples).
    const auto& states = r.msg.states();
    const std::size_t base = out.size();
    out.resize(base + states.size(), item);
    for (std::size_t k = 0; k < states.size(); ++k) {
      StateItem& one = out[base + k];
      one.state = to_sample(states[k]);
      one.id = one.state.id;
      ids.push_back(one.id);
    }
  }
}

}  // namespace shapeform::dds
