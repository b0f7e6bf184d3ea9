#pragma once
/// The command's wire conversion, driven by the command table (core/command_table.hpp): every field of
/// ShapeCommand that carries a core::Command field is bound once, by its IDL name, to the generated
/// message's accessors (convert_command.cpp), and matched by that name to the command-table entry that
/// declares it (Param::wire). to_msg(Command) and from_msg(ShapeCommand) (declared in convert.hpp) loop
/// over these bindings: the entry's get/set move the value, its range and choices check it. Only
/// epoch, issuer and issuer_name (the CommandId, not part of core::Command) are converted by hand.
#include <cstddef>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "core/command_table.hpp"
#include "shapeform/msg/ShapeCommand.h"

namespace shapeform::dds {

/// A ShapeCommand field's value, whatever its IDL type: double, boolean, string, sequence<double>.
using WireValue = std::variant<double, bool, std::string, std::vector<double>>;

/// One ShapeCommand field bound to the command-table entry that declares it.
struct CommandWireField {
  std::string_view name;                             ///< the IDL field ("cx")
  WireValue (*get)(const msg::ShapeCommand& m);      ///< the field's value
  void (*set)(msg::ShapeCommand& m, WireValue&& v);  ///< v holds the field's own alternative
  const core::params::Param<core::Command>* param;   ///< the entry ("shape.centre")
  std::size_t component;  ///< which of param->wire this field is (Vec2: 0 = x, 1 = y; otherwise 0)
};

/// Every bound field, in IDL order (the order in which a refused command lists its problems), built
/// once. Throws std::logic_error when a bound field is named by no entry's `wire`, an entry's `wire`
/// name is bound not exactly once, or a field's IDL type is not the one its entry's type travels as
/// (Real and Vec2: double; Bool: boolean; Text and Choice: string; Vec2List and ZoneList: sequence<double>).
const std::vector<CommandWireField>& command_wire();

}  // namespace shapeform::dds
