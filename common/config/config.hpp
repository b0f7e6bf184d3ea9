#pragma once
/// shapeform configuration: YAML -> these plain structs. The one config loader of the project.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/compiled_command.hpp"
#include "core/metrics.hpp"

namespace shapeform::config {

inline constexpr int kSchemaVersion = 1;

/// How agents start when no explicit start is given.
struct SwarmConfig {
  int agents = 12;              ///< swarm size (1..1000)
  std::uint64_t seed = 1;       ///< seed of the uniform start
  double init_half_width = 5.0; ///< start uniform in [-w, w]^2
};

/// Simulator-only settings.
struct SimConfig {
  long steps = 500;  ///< number of integration steps
};

/// DDS transport profile; every participant is built from this by the one participant factory.
struct TransportConfig {
  std::string profile = "loopback";  ///< loopback | lan | discovery-server
  int domain = 0;                    ///< DDS domain id, 0..232
  int max_participants = 120;        ///< participant ids probed by loopback initial peers
  std::vector<std::string> interfaces;  ///< lan: IPv4 addresses to bind (empty = all)
  std::vector<std::string> peers;       ///< lan: unicast peer addresses (empty = multicast discovery)
  std::string discovery_server = "127.0.0.1:11811";  ///< discovery-server: host:port
  double lease_s = 2.0;     ///< participant lease duration
  double announce_s = 0.5;  ///< participant announcement period
  int socket_buffer_bytes = 0;  ///< UDP send/receive buffer size; 0 = OS default
  /// State-topic readers listen on the multicast group 239.255.0.1 (the domain's user multicast port)
  /// instead of a unicast port: a writer sends one datagram per sample instead of one per reader.
  /// Loopback profile, or discovery-server with a server on 127.x / localhost (whitelist 127.0.0.1,
  /// so the group stays on lo). Off by default.
  bool multicast_data = false;

  /// Whether every participant's traffic stays on lo: the loopback profile, or a discovery server on
  /// 127.x / localhost. multicast_data needs it (the loader and the participant factory both check).
  bool on_loopback() const {
    return profile == "loopback" || (profile == "discovery-server" && (discovery_server.rfind("127.", 0) == 0 ||
                                                                       discovery_server.rfind("localhost:", 0) == 0));
  }
};

/// Agent process settings.
struct AgentConfig {
  double rate_hz = 50.0;                  ///< control loop rate
  double neighbour_timeout_periods = 3.0; ///< drop a neighbour unheard for this many periods
  double status_rate_hz = 1.0;            ///< agent status publication rate
  /// How agents step: false = free running (each on its own clock, using the newest neighbour states);
  /// true = lockstep (step k+1 waits for every neighbour's step k: the simulator's synchronous update).
  bool lockstep = false;
};

/// Supervisor settings.
struct SupervisorConfig {
  double metrics_rate_hz = 10.0;      ///< metrics computation / publication / recording rate
  double target_rate_hz = 50.0;       ///< tracking target publication rate
  double agent_timeout_s = 1.0;       ///< an agent unheard for this long is shown dead
  core::ConvergenceDetector::Params converge;  ///< what "converged" means
  double flush_s = 1.0;               ///< recorder flush period
};

struct Config {
  int schema_version = kSchemaVersion;
  std::string name = "circle";  ///< scenario name (free text)
  SwarmConfig swarm;
  core::CompiledCommand command;  ///< shape, tracking, dynamics, integration; compiled by load
  SimConfig sim;
  AgentConfig agent;
  SupervisorConfig supervisor;
  TransportConfig transport;
};

/// Every problem found while loading or validating, one line each, e.g.
/// "dynamics.sigma: must be > 0, got -1 (line 7)".
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(std::vector<std::string> problems);
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  std::vector<std::string> problems_;
};

/// Loads a YAML file (empty path = defaults only), applies "dotted.key=value" overrides in order,
/// validates, and returns the result. Throws ConfigError naming every problem.
Config load(const std::string& path, const std::vector<std::string>& overrides = {});

/// Loads from YAML text (source_name is used in messages).
Config load_string(const std::string& yaml_text, const std::vector<std::string>& overrides = {},
                   const std::string& source_name = "<string>");

/// The effective configuration as YAML (printed once at start-up by every executable).
std::string to_yaml(const Config& c);

}  // namespace shapeform::config
