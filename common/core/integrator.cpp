#include "integrator.hpp"

namespace shapeform::core {

std::string_view to_string(Integrator i) { return i == Integrator::Euler ? "euler" : "rk4"; }

bool parse_integrator(std::string_view name, Integrator& out) {
  if (name == "euler") {
    out = Integrator::Euler;
    return true;
  }
  if (name == "rk4") {
    out = Integrator::RK4;
    return true;
  }
  return false;
}

}  // namespace shapeform::core
