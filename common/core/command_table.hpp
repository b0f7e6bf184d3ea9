#pragma once
/// The command table: every field of core::Command declared once (config key, type, unit, range,
/// description and its ShapeCommand field names), in the parameter machinery of params.hpp. The
/// config loader, the console's bounds and the command's wire conversion read it (dds/convert_command,
/// which binds each field name to the generated message's accessors and loops over the table).
#include <string_view>
#include <vector>

#include "command.hpp"
#include "params.hpp"

namespace shapeform::core::params {

/// The command table: one entry per field of core::Command (shape, tracking, gains and max_speed,
/// law and arc parameters, integration), keyed by config key, with its ShapeCommand field name(s).
const std::vector<Param<Command>>& command_table();

/// The entry of a config key ("integration.dt"), or null.
const Param<Command>* find_key(std::string_view key);
/// The entry holding ShapeCommand field `wire` ("dt", "cx", "path_radius"), or null.
const Param<Command>* find_wire(std::string_view wire);

}  // namespace shapeform::core::params
