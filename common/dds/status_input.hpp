#pragma once
/// Every reader of agent status in one place: the per-agent topic (shapeform/status, one AgentStatus per
/// agent and status period) and the per-process one (shapeform/status_batch, one AgentStatusBatch per
/// process and period, from shapeform_agent_group), drained into one list of per-agent items. The
/// supervisor, the viewer and the benchmark's probe read statuses only through this class.
#include <cstdint>
#include <string>
#include <vector>

#include "dds/node.hpp"
#include "protocol/samples.hpp"
#include "shapeform/msg/AgentStatus.h"
#include "shapeform/msg/AgentStatusBatch.h"

namespace shapeform::dds {

/// One agent's status as received, or a refused sample.
struct StatusItem {
  bool valid = true;    ///< false: a sample refused by validation (`why` names the fields; a batch whole)
  StatusSample status;  ///< valid only
  std::int64_t receive_stamp_ns = 0;  ///< when the sample was taken (util::steady_ns)
  SourceId source;                    ///< the participant whose writer sent it
  bool batched = false;               ///< it came in an AgentStatusBatch
  std::string why;                    ///< refused only
};

class StatusInput {
 public:
  StatusInput() = default;  ///< reads nothing (drain gives nothing) until assigned one built on a Node
  /// A reader of each status topic on `node`.
  explicit StatusInput(Node& node);

  /// Moves everything received since the last call into out (cleared first): the per-agent samples,
  /// then each batch unpacked into one item per element, in the batch's order. Instance-state samples
  /// (a disposed instance, a writer gone) carry no status and give nothing.
  void drain(std::vector<StatusItem>& out);

  /// The samples of each topic as the last drain took them (before validation), for who records or
  /// forwards them raw (the supervisor's recording, the viewer's Foxglove server).
  const std::vector<Received<msg::AgentStatus>>& last_statuses() const { return single_buf_; }
  const std::vector<Received<msg::AgentStatusBatch>>& last_batches() const { return batch_buf_; }

 private:
  Reader<msg::AgentStatus> single_;
  Reader<msg::AgentStatusBatch> batch_;
  std::vector<Received<msg::AgentStatus>> single_buf_;
  std::vector<Received<msg::AgentStatusBatch>> batch_buf_;
  std::vector<StatusSample> unpacked_;  ///< reused by drain
};

}  // namespace shapeform::dds
