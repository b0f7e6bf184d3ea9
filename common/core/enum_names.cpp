// Every enumeration's to_string / parse_* (declared beside its enumeration) reads its one table here.
#include "enum_names.hpp"

namespace shapeform::core {

std::string_view to_string(Law l) { return params::name_of(params::kLawNames, l); }

bool parse_law(std::string_view name, Law& out) { return params::parse_name(params::kLawNames, name, out); }

std::string_view to_string(BreachAction a) { return params::name_of(params::kBreachActionNames, a); }

bool parse_breach_action(std::string_view name, BreachAction& out) {
  return params::parse_name(params::kBreachActionNames, name, out);
}

std::string_view to_string(ShapeKind kind) { return params::name_of(params::kShapeKindNames, kind); }

bool parse_shape_kind(std::string_view name, ShapeKind& out) {
  return params::parse_name(params::kShapeKindNames, name, out);
}

std::string_view to_string(CentrePath::Kind kind) { return params::name_of(params::kPathKindNames, kind); }

bool parse_path_kind(std::string_view name, CentrePath::Kind& out) {
  return params::parse_name(params::kPathKindNames, name, out);
}

std::string_view to_string(Integrator i) { return params::name_of(params::kIntegratorNames, i); }

bool parse_integrator(std::string_view name, Integrator& out) {
  return params::parse_name(params::kIntegratorNames, name, out);
}

std::string_view to_string(VehicleModel m) { return params::name_of(params::kVehicleModelNames, m); }

bool parse_vehicle_model(std::string_view name, VehicleModel& out) {
  return params::parse_name(params::kVehicleModelNames, name, out);
}

std::string_view to_string(Steering s) { return params::name_of(params::kSteeringNames, s); }

bool parse_steering(std::string_view name, Steering& out) { return params::parse_name(params::kSteeringNames, name, out); }

}  // namespace shapeform::core
