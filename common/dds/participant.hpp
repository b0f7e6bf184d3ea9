#pragma once
/// What a process may know of its participant without Fast DDS: a description of its transport
/// profile for the start-up line. The participant itself comes from dds::create_participant
/// (dds/participant_factory.hpp, the dds library's own), through a dds::Node.
#include <string>

#include "protocol/transport.hpp"

namespace shapeform::dds {

/// One line for logs, e.g. "loopback (UDPv4 127.0.0.1 only, unicast discovery of ids 0..119),
/// domain 0, lease 2 s, announce 0.5 s" or "lan (UDPv4 on 10.0.0.2, multicast discovery on
/// 239.255.0.1:7400), ...". Never throws, even for an invalid config.
std::string describe(const TransportConfig& cfg);

}  // namespace shapeform::dds
