#include "compiled_command.hpp"

#include <stdexcept>
#include <utility>

namespace shapeform::core {

CompiledCommand::CompiledCommand() : CompiledCommand(compile(Command{})) {}

CompiledCommand::CompiledCommand(Command cmd, std::shared_ptr<const Curve> curve)
    : Command(std::move(cmd)), curve_(std::move(curve)) {
  if (!curve_) throw std::invalid_argument("CompiledCommand: no curve");
}

CompiledCommand compile(const Command& cmd) { return CompiledCommand(cmd, make_curve(cmd.shape)); }

}  // namespace shapeform::core
