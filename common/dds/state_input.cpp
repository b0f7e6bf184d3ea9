#include "dds/state_input.hpp"

#include <algorithm>

#include "dds/convert.hpp"

namespace shapeform::dds {

StateInput::StateInput(Node& node)
    : single_(node.reader<msg::AgentState>(TopicId::State)),
      batch_(node.reader<msg::AgentStateBatch>(TopicId::StateBatch)) {}

void StateInput::drain(std::vector<StateItem>& out) {
  out.clear();
  drain([&out](const StateItem& item) { out.push_back(item); });
}

void StateInput::drain(const std::function<void(const StateItem&)>& each) {
  StateItem& item = item_;
  // Sets what every item of one sample shares; a Gone or Rejected item carries no state.
  const auto begin = [&item](std::int64_t stamp, const SourceId& source, bool batched) {
    item.kind = StateItem::Kind::State;
    item.id = -1;
    item.receive_stamp_ns = stamp;
    item.source = source;
    item.instance = InstanceState::Alive;
    item.batched = batched;
    item.why.clear();
  };
  single_.drain(single_buf_);
  for (const auto& r : single_buf_) {
    begin(r.receive_stamp_ns, r.source, false);
    if (!r.valid_data) {
      if (r.key_id < 0) continue;  // an instance never heard alive: nobody to drop
      item.kind = StateItem::Kind::Gone;
      item.id = r.key_id;
      item.instance = r.instance;
      item.state = {};
    } else if (from_msg(r.msg, item.state, item.why)) {
      item.id = item.state.id;
    } else {
      item.kind = StateItem::Kind::Rejected;
      item.state = {};
    }
    each(item);
  }
  batch_.drain(batch_buf_);
  for (const auto& r : batch_buf_) {
    begin(r.receive_stamp_ns, r.source, true);
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
      item.state = {};
      for (const std::int32_t id : it->second) {
        item.id = id;
        each(item);
      }
      carried_.erase(it);
      continue;
    }
    if (!from_msg(r.msg, batch_states_, item.why)) {
      item.kind = StateItem::Kind::Rejected;
      item.state = {};
      each(item);
      continue;
    }
    ++batches_;
    std::vector<std::int32_t>& ids = carried_[instance];
    ids.clear();
    // Each element passed on in the one item (no list of thousands of items).
    for (const StateSample& state : batch_states_) {
      item.state = state;
      item.id = state.id;
      ids.push_back(item.id);
      each(item);
    }
  }
}

}  // namespace shapeform::dds
