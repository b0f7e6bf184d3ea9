#pragma once
/// Detecting that this process may be half-matched with a peer (no Fast DDS here).
///
/// A participant that sends nothing for its lease (transport.lease_s) is dropped by every peer. When it
/// is heard again, Fast DDS 2.9 re-discovers it, but the endpoint discovery between it and a peer that
/// did not drop it in turn can stay broken for good (docs/RELIABILITY.md, "Stalls, partitions and
/// membership"). One of the two sides always knows: the one that stalled (its own loop was late by
/// more than stall_threshold_s(), StallWatch), or the one that dropped the other for silence and then
/// heard it again soon after (a partition, a starved thread: SplitWatch). That side recreates its
/// participant (dds::Node::recover), which everyone discovers afresh.
#include <cstdint>
#include <map>
#include <optional>

#include "protocol/samples.hpp"
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

/// Peers this process dropped for silence (their lease ran out) and heard again soon after. After a
/// silence of about a lease, the peer may not have dropped this process in turn (its lease of this
/// process runs from another last message): the pair can then be half-matched, the peer's endpoint
/// announcements never reaching this side again. A peer heard again more than `window_s` after its
/// drop has dropped this process too (announcements leave every announce_s, so the two drops are at
/// most that far apart): both sides start afresh and nothing is due. Nor is a peer whose endpoints
/// this process hears announced within `grace_s` of its return (its endpoint discovery works, so it
/// dropped this process too), or that is removed meanwhile (a peer that stalled recreates its own
/// participant on its first tick, and its old one says goodbye).
/// Secured (DDS Security), a returned peer must authenticate again before anything else (Fast DDS 2.9.1
/// reports its discovery before the handshake), and a half-matched pair cannot: the side that kept its
/// peer authenticated discards the new handshake (docs/SECURITY.md, "Leases"). So a returned peer that
/// authenticates again (or announces an endpoint, which comes after) dropped this process too and both
/// start afresh: nothing is due, however long its endpoints then take (the key exchange and the secured
/// endpoint discovery follow the handshake). One not authenticated within kAuthBoundS of its return is
/// due. Pure: the caller passes the events and the clock.
class SplitWatch {
 public:
  SplitWatch(double window_s, double grace_s, bool secured = false);

  void dropped(const SourceId& peer, std::int64_t now_ns);     ///< its lease ran out
  /// Its announcement, first or again; for a peer dropped before, the seconds since its drop.
  std::optional<double> discovered(const SourceId& peer, std::int64_t now_ns);
  void authenticated(const SourceId& peer);                     ///< secured: its handshake ended
  void removed(const SourceId& peer);                          ///< it said goodbye
  void endpoint(const SourceId& peer);  ///< one of its endpoints announced (to this participant)

  struct Split {
    SourceId peer;
    double unheard_s = 0.0;  ///< from its drop to its return
  };
  /// The first peer that came back within window_s of its drop, and of which neither an endpoint nor a
  /// goodbye came within grace_s since (secured: that did not authenticate again within kAuthBoundS):
  /// this process should recreate its participant (then clear()).
  std::optional<Split> due(std::int64_t now_ns) const;
  /// Forgets everything: a new participant has no history with anyone.
  void clear();

  /// window_s for a transport profile: lease_s + announce_s.
  static double window_for(const TransportConfig& cfg) { return cfg.lease_s + cfg.announce_s; }
  static constexpr double kGraceS = 0.5;
  /// Secured: how long a returned peer may take to authenticate again (instead of grace_s). Fast DDS
  /// 2.9.1 resends an unanswered handshake message every second, so a handshake that loses each of its
  /// three messages once still ends within about 4 s.
  static constexpr double kAuthBoundS = 5.0;
  /// How long a drop is remembered for discovered() to report the peer's return (seconds).
  static constexpr double kDropMemoryS = 600.0;

 private:
  std::int64_t window_ns_;
  std::int64_t grace_ns_;  ///< secured: kAuthBoundS
  bool secured_;
  std::map<SourceId, std::int64_t> dropped_;                      ///< peer -> when, forgotten after kDropMemoryS
  std::map<SourceId, std::pair<std::int64_t, double>> returned_;  ///< peer -> (came back at, unheard_s)
};

}  // namespace shapeform::dds
