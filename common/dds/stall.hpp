#pragma once
/// Detecting that this process stalled long enough for its peers to drop it (no Fast DDS here).
///
/// A participant that sends nothing for its lease (transport.lease_s) is dropped by every peer. When it
/// resumes, Fast DDS 2.9 re-discovers it, but the endpoint discovery between it and a peer that it did
/// not drop in turn can stay broken for good (docs/RELIABILITY.md, "Stalls and membership"). A process
/// therefore watches its own loop: a stall longer than stall_threshold_s() makes it recreate its
/// participant (dds::Node::recover_if_stalled), which everyone discovers afresh.
#include <cstdint>
#include <optional>

#include "protocol/transport.hpp"

namespace shapeform::dds {

/// The stall after which a process recreates its participant, seconds: lease_s - announce_s. Peers
/// drop a participant they heard nothing from for lease_s, and its last announcement may have left up to
/// announce_s before the stall began (any message renews the lease; announcements are the rarest).
double stall_threshold_s(const TransportConfig& cfg);

/// CLOCK_BOOTTIME in nanoseconds: like the steady clock, but it also runs while the host is suspended
/// (a suspended laptop is a stall too; its peers' leases keep running).
std::int64_t boot_ns();

/// Watches the calls of a fixed-rate loop for gaps. Pure: the caller passes the clock reading.
class StallWatch {
 public:
  /// now_ns: a boot_ns() reading; period_s: the loop's period (a slow loop is not a stall). Returns how
  /// late this call is (time since the previous call minus one period, seconds) when that exceeds
  /// threshold_s, else nullopt. The first call only starts the watch.
  std::optional<double> check(std::int64_t now_ns, double period_s, double threshold_s);

 private:
  std::int64_t last_ns_ = -1;
};

}  // namespace shapeform::dds
