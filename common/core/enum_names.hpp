#pragma once
/// The one name table of each enumeration of the core: the spellings used in config files, console
/// commands, JSON and on the wire. core's to_string / parse_* and the parameter tables use them.
#include "command.hpp"
#include "params.hpp"
#include "vehicle.hpp"

namespace shapeform::core::params {

/// Spellings used in config files, console commands, JSON and on the wire.
inline constexpr Name<ShapeKind> kShapeKindNames[] = {
    {ShapeKind::Line, "line"},         {ShapeKind::Circle, "circle"},  {ShapeKind::Ellipse, "ellipse"},
    {ShapeKind::Square, "square"},     {ShapeKind::Polar, "polar"},    {ShapeKind::Parametric, "parametric"},
    {ShapeKind::Implicit, "implicit"}, {ShapeKind::Polygon, "polygon"}};
inline constexpr Name<CentrePath::Kind> kPathKindNames[] = {{CentrePath::Kind::Fixed, "fixed"},
                                                            {CentrePath::Kind::Line, "line"},
                                                            {CentrePath::Kind::Circle, "circle"}};
inline constexpr Name<Integrator> kIntegratorNames[] = {{Integrator::Euler, "euler"},
                                                        {Integrator::RK4, "rk4"}};
inline constexpr Name<Law> kLawNames[] = {{Law::Paper, "paper"}, {Law::Arc, "arc"}};
inline constexpr Name<BreachAction> kBreachActionNames[] = {
    {BreachAction::Hold, "hold"}, {BreachAction::Stop, "stop"}, {BreachAction::Return, "return"}};
inline constexpr Name<VehicleModel> kVehicleModelNames[] = {{VehicleModel::Integrator, "integrator"},
                                                            {VehicleModel::DoubleIntegrator, "double_integrator"},
                                                            {VehicleModel::Unicycle, "unicycle"}};
inline constexpr Name<Steering> kSteeringNames[] = {{Steering::Exact, "exact"}, {Steering::Linearised, "linearised"}};

}  // namespace shapeform::core::params
