#pragma once
/// The project's IDL files as text, embedded at build time (common/dds/embed_idl.cmake, generated into
/// the build tree): each self-contained, its includes inlined before it in dependency order.
#include <string_view>
#include <vector>

namespace shapeform::dds {

struct IdlFile {
  std::string_view
      key;  ///< its path under idl/ (or idl/ros2) without ".idl": "AgentState", "geometry_msgs/msg/Twist"
  std::string_view text;  ///< the IDL with every type it uses, includes inlined, #include lines dropped
};

/// Every idl/*.idl and idl/ros2/**/*.idl, sorted by path.
const std::vector<IdlFile>& idl_files();

}  // namespace shapeform::dds
