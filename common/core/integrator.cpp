#include "integrator.hpp"

#include "params.hpp"

namespace shapeform::core {

std::string_view to_string(Integrator i) { return params::name_of(params::kIntegratorNames, i); }

bool parse_integrator(std::string_view name, Integrator& out) {
  return params::parse_name(params::kIntegratorNames, name, out);
}

}  // namespace shapeform::core
