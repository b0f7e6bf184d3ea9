#pragma once
/// Every reader of agent state in one place: the per-agent topic (shapeform/state, one AgentState per
/// agent and tick) and the per-process one (shapeform/state_batch, one AgentStateBatch per process
/// and tick, from shapeform_agent_group), drained as one stream of per-agent items. Agents,
/// supervisor and viewer read state only through this class.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "dds/node.hpp"
#include "protocol/samples.hpp"
#include "shapeform/msg/AgentState.h"
#include "shapeform/msg/AgentStateBatch.h"

namespace shapeform::dds {

/// One agent's state as received, or its departure, or a refused sample.
struct StateItem {
  enum class Kind {
    State,     ///< a valid state (`state`, validated by dds::from_msg)
    Gone,      ///< agent `id` left: its instance, or the batch instance that last carried it, was
               ///< disposed (`instance` Disposed) or lost its writer (NoWriters)
    Rejected,  ///< a sample refused by validation (`why` names the fields; a batch is refused whole)
  };
  Kind kind = Kind::State;
  std::int32_t id = -1;  ///< State and Gone: the agent; Rejected: -1
  StateSample state;     ///< State only
  std::int64_t receive_stamp_ns = 0;  ///< when the sample was taken (util::steady_ns)
  SourceId source;                    ///< the participant whose writer sent it (or left)
  InstanceState instance = InstanceState::Alive;  ///< Gone: Disposed or NoWriters
  bool batched = false;  ///< it came in (or with) an AgentStateBatch
  std::string why;       ///< Rejected only
};

class StateInput {
 public:
  StateInput() = default;  ///< reads nothing (drain gives nothing) until assigned one built on a Node
  /// A reader of each state topic on `node` (reader_qos: multicast when transport.multicast_data).
  explicit StateInput(Node& node);

  /// Passes everything received since the last call to each(item): the per-agent samples, then each
  /// batch unpacked into one item per element, in the batch's order. A disposed batch instance, or
  /// one whose writer left, gives one Gone item for every id that instance last carried. The item is
  /// good only during the call: one item is reused, so a receiver of thousands of states a tick fills
  /// no list of them (an agent group's loop goes straight from the message into its table).
  void drain(const std::function<void(const StateItem&)>& each);
  /// The same, copied into out (cleared first).
  void drain(std::vector<StateItem>& out);

  /// The samples of each topic as the last drain took them (before validation), for who forwards them
  /// raw (the viewer's Foxglove server): valid or not, as Fast DDS delivered them.
  const std::vector<Received<msg::AgentState>>& last_states() const { return single_buf_; }
  const std::vector<Received<msg::AgentStateBatch>>& last_batches() const { return batch_buf_; }

  /// Valid batches taken so far (each counted once, however many agents it carried).
  std::uint64_t batches() const { return batches_; }

 private:
  Reader<msg::AgentState> single_;
  Reader<msg::AgentStateBatch> batch_;
  std::vector<Received<msg::AgentState>> single_buf_;
  std::vector<Received<msg::AgentStateBatch>> batch_buf_;
  /// The ids each batch instance (writer's participant, first_id) carried last.
  std::map<std::pair<SourceId, std::int32_t>, std::vector<std::int32_t>> carried_;
  std::uint64_t batches_ = 0;
  StateItem item_;  ///< the one item drain() passes on
  std::vector<StateSample> batch_states_;  ///< one batch's states, converted (reused)
};

}  // namespace shapeform::dds
