#pragma once
/// The project's one steady clock reading: every *_stamp_ns and every age is taken from it.
#include <cstdint>

namespace shapeform::util {

/// steady_clock now in nanoseconds since that clock's epoch. On Linux this is CLOCK_MONOTONIC,
/// which is system-wide, so stamps from different processes on the same host are comparable
/// (e.g. data age = receiver steady_ns() - sender stamp_ns).
std::int64_t steady_ns();

/// system_clock now in nanoseconds since the Unix epoch: the wall time ROS 2 stamps its headers with
/// (builtin_interfaces/Time). Only for stamps another system reads; never for ages (it may jump).
std::int64_t system_ns();

}  // namespace shapeform::util
