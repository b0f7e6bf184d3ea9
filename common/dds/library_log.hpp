#pragma once
/// Fast DDS's own log, routed into the project's: its default consumer prints to stdout, which the
/// programs keep for JSON results. Installed once per process by the participant factory.
#include <optional>
#include <string_view>
#include <vector>

#include "protocol/samples.hpp"

namespace shapeform::dds {

/// Replaces Fast DDS's log consumers (once per process; later calls do nothing): its errors become
/// stderr lines "fastdds CATEGORY: message" (each distinct message at most once per 5 s),
/// and DDS Security's refusals of a remote participant's permissions, which Fast DDS 2.9 reports only
/// in its log, are remembered for take_permission_refusals().
void route_library_log();

/// The participant a Fast DDS security log message says it refused for its permissions ("Error
/// validating remote permissions for GUID|..." or "Error checking remote participant  GUID ..."),
/// or nullopt. Pure.
std::optional<SourceId> permission_refusal(std::string_view message);

/// The participants refused for their permissions since the last call, each once (process-wide).
std::vector<SourceId> take_permission_refusals();

}  // namespace shapeform::dds
