#include "dds/status_input.hpp"

#include "dds/convert.hpp"

namespace shapeform::dds {

StatusInput::StatusInput(Node& node)
    : single_(node.reader<msg::AgentStatus>(TopicId::Status)),
      batch_(node.reader<msg::AgentStatusBatch>(TopicId::StatusBatch)) {}

void StatusInput::drain(std::vector<StatusItem>& out) {
  out.clear();
  single_.drain(single_buf_);
  for (const auto& r : single_buf_) {
    if (!r.valid_data) continue;
    StatusItem item;
    item.receive_stamp_ns = r.receive_stamp_ns;
    item.source = r.source;
    item.valid = from_msg(r.msg, item.status, item.why);
    out.push_back(std::move(item));
  }
  batch_.drain(batch_buf_);
  for (const auto& r : batch_buf_) {
    if (!r.valid_data) continue;
    StatusItem item;
    item.receive_stamp_ns = r.receive_stamp_ns;
    item.source = r.source;
    item.batched = true;
    if (!from_msg(r.msg, unpacked_, item.why)) {
      item.valid = false;
      out.push_back(std::move(item));
      continue;
    }
    for (const StatusSample& s : unpacked_) {
      item.status = s;
      out.push_back(item);
    }
  }
}

}  // namespace shapeform::dds
