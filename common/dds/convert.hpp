#pragma once
/// Conversions between wire messages and core types (or the plain structs of protocol/samples.hpp), one
/// to_msg / from_msg pair per message, and validation of received samples.
/// Received data is never trusted: non-finite numbers, unknown names and absurd values are rejected
/// with a message naming the field.
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/compiled_command.hpp"
#include "core/metrics.hpp"
#include "protocol/samples.hpp"
#include "shapeform/msg/AgentState.h"
#include "shapeform/msg/AgentStateBatch.h"
#include "shapeform/msg/AgentStatus.h"
#include "shapeform/msg/AgentStatusBatch.h"
#include "shapeform/msg/ShapeCommand.h"
#include "shapeform/msg/SwarmMetrics.h"
#include "shapeform/msg/TrackingTarget.h"

namespace shapeform::dds {


/// core::Command -> wire message with the given id (epoch and issuer) and issuer name (every field,
/// the law by name; polygon vertices flattened x0, y0, x1, y1, ...; the compiled curve is not sent:
/// receivers compile).
msg::ShapeCommand to_msg(const core::Command& cmd, const CommandId& id, const std::string& issuer_name = {});

/// Wire message -> core::CompiledCommand, its shape compiled (shapes::compile).
/// On failure returns false, leaves `out` untouched and sets `error` to every problem found,
/// separated by "; ", each naming its field, e.g. "command.dt: must be in (0, 10], got 50". Checks:
/// every number finite and within the range the command table (core/command_table.hpp) declares for its
/// field, the same bounds as the config loader and the console; shape_kind, path_kind, integrator,
/// law one of the names of their tables; vertices of even length. When all of that passes, the
/// shape is compiled; a core::ShapeError is reported as "command: <its message>", e.g.
/// "command: polar: r(phi) = '4+foo': Unexpected token \"foo\" found at position 2.".
/// Last, the compiled command is checked against its envelope (core::envelope_problems, as the
/// config loader and the console do), e.g. "command.k1: dynamics.k1 = 1e+300: the step gain ...".
/// The epoch is not part of core::Command: read m.epoch().
bool from_msg(const msg::ShapeCommand& m, core::CompiledCommand& out, std::string& error);

/// Wire message sent by participant `source` -> CommandSample: the command as above, its id (the
/// issuer field, or `source` when that is all zero: a writer that does not fill it issued the command
/// itself) and the issuer's name (control characters replaced by '?', cut to kIssuerNameMax). Also
/// refuses epoch 0 ("command.epoch: must be >= 1, got 0").
bool from_msg(const msg::ShapeCommand& m, const SourceId& source, CommandSample& out, std::string& error);

/// True when s is plausible: id in 0..kMaxAgentId, model_time in [0, kModelTimeLimit], x, y, vx,
/// vy, arc finite, |x|, |y| <=
/// kStateLimit and speed |(vx, vy)| <= kStateLimit. Otherwise false with `why` naming the field
/// ("state.x: ...").
bool valid_state(const msg::AgentState& s, std::string& why);

/// StateSample -> AgentState: has_arc when s.arc is known (arc and prev_arc then carry s.arc and
/// s.prev_arc, prev_arc falling back to arc); without it both are sent as 0, which receivers ignore.
msg::AgentState to_msg(const StateSample& s);

/// AgentState -> StateSample when valid_state(m) holds (arc and prev_arc are nullopt unless has_arc);
/// otherwise false, `out` untouched and `why` naming every bad field.
bool from_msg(const msg::AgentState& m, StateSample& out, std::string& why);
/// A valid AgentState (valid_state, or an element of a batch valid_batch passed) -> StateSample, as
/// from_msg converts it, without checking again.
StateSample to_sample(const msg::AgentState& m);

/// The states of the agents one process hosts -> one AgentStateBatch (first_id: states[0].id; each
/// element as to_msg(StateSample)). states holds 1 to kMaxBatchStates samples with distinct ids.
msg::AgentStateBatch to_msg(const std::vector<StateSample>& states);

/// states[begin, end) -> one AgentStateBatch (first_id: states[begin].id), as to_msg(states) of that part.
msg::AgentStateBatch to_msg(const std::vector<StateSample>& states, std::size_t begin, std::size_t end);
/// The same into out, a message reused from tick to tick (its sequence keeps its capacity).
void to_msg(const std::vector<StateSample>& states, std::size_t begin, std::size_t end, msg::AgentStateBatch& out);

/// How a process cuts the `count` states it publishes per tick into AgentStateBatch samples of at most
/// `max_states` (agent.batch_max_states) each, every sample its own instance (keyed by its first_id):
/// ceil(count / max_states) consecutive [begin, end) ranges covering 0..count in order, of lengths that
/// differ by at most 1 (1000 states, at most 500: 500 + 500; at most 400: 334 + 333 + 333), so each
/// datagram of a tick is about the same size. Empty for count 0; max_states 0 is taken as 1.
std::vector<std::pair<std::size_t, std::size_t>> batch_ranges(std::size_t count, std::size_t max_states);

/// AgentStateBatch -> one StateSample per element, in order, when the batch holds 1 to
/// kMaxBatchStates states, first_id is the id of states[0], every element passes valid_state and no
/// id appears twice. Otherwise false (the whole batch refused: its publisher is broken), `out`
/// untouched and `why` naming every bad field, e.g. "state_batch.states[3].x: must be finite, got nan".
bool from_msg(const msg::AgentStateBatch& m, std::vector<StateSample>& out, std::string& why);
/// The checks of from_msg(AgentStateBatch) alone: true when from_msg would convert m (its elements then
/// each convert by to_sample), else false and `why` as from_msg says it.
bool valid_batch(const msg::AgentStateBatch& m, std::string& why);

/// TargetSample -> TrackingTarget (every field).
msg::TrackingTarget to_msg(const TargetSample& t);

/// TrackingTarget -> TargetSample when model_time, cx, cy, vx, vy are finite and within
/// kStateLimit; otherwise false, `out` untouched and `why` naming the fields ("target.cx: ...").
bool from_msg(const msg::TrackingTarget& m, TargetSample& out, std::string& why);

/// StatusSample -> AgentStatus (every field).
msg::AgentStatus to_msg(const StatusSample& s);

/// AgentStatus -> StatusSample when id is in 0..kMaxAgentId; otherwise false, `out` untouched, `why` says so.
bool from_msg(const msg::AgentStatus& m, StatusSample& out, std::string& why);

/// statuses[begin, end) -> one AgentStatusBatch (first_id: statuses[begin].id; each element as
/// to_msg(StatusSample)) into out, a message reused from period to period. The parts are those of
/// batch_ranges(count, kBatchStatusesPerDatagram).
void to_msg(const std::vector<StatusSample>& statuses, std::size_t begin, std::size_t end, msg::AgentStatusBatch& out);

/// AgentStatusBatch -> one StatusSample per element, in order, when the batch holds 1 to
/// kMaxBatchStates statuses, first_id is the id of statuses[0], every element converts by
/// from_msg(AgentStatus) and no id appears twice. Otherwise false (the whole batch refused), `out`
/// untouched and `why` naming every bad field, e.g. "status_batch.statuses[3].id: must be in 0..9999, got -4".
bool from_msg(const msg::AgentStatusBatch& m, std::vector<StatusSample>& out, std::string& why);

/// core::Metrics -> wire message (agents as agents_alive, every metric of core::kMetricTable under its
/// name); undefined (nullopt) values become -1.
msg::SwarmMetrics to_msg(const core::Metrics& m, std::uint64_t epoch, double model_time,
                         std::int64_t stamp_ns, bool converged);

/// Wire message -> core::Metrics; negative (-1) or non-finite values become nullopt.
core::Metrics from_msg(const msg::SwarmMetrics& m);

}  // namespace shapeform::dds
