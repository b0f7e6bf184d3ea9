#include "shapes.hpp"

#include <muParser.h>

#include <cmath>
#include <memory>
#include <string>

namespace shapeform::shapes {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr int kSamples = 4096;

/// One muparser expression over named variables. Evaluation is not thread-safe (one agent loop).
class Expression {
 public:
  Expression(const std::string& what, const std::string& text, std::initializer_list<const char*> vars)
      : what_(what), text_(text) {
    if (text.find_first_not_of(" \t") == std::string::npos) throw core::ShapeError(what + ": empty expression");
    try {
      parser_.DefineConst("pi", kPi);
      int k = 0;
      for (const char* v : vars) parser_.DefineVar(v, &values_[k++]);
      parser_.SetExpr(text);
      parser_.Eval();  // parses now: syntax errors and unknown names surface here
    } catch (const mu::Parser::exception_type& e) {
      throw core::ShapeError(what + " = '" + text + "': " + e.GetMsg());
    }
  }
  double operator()(double a, double b = 0.0) {
    values_[0] = a;
    values_[1] = b;
    try {
      return parser_.Eval();
    } catch (const mu::Parser::exception_type& e) {
      throw core::ShapeError(what_ + " = '" + text_ + "': " + e.GetMsg());
    }
  }

 private:
  std::string what_, text_;
  double values_[2] = {0.0, 0.0};
  mu::Parser parser_;
};

void check_finite(const std::string& what, const std::string& text, double v, const char* at) {
  if (!std::isfinite(v)) throw core::ShapeError(what + " = '" + text + "' is not finite at " + at);
}
}  // namespace

std::shared_ptr<const core::Curve> compile_curve(const core::ShapeSpec& s) {
  if (!(s.scale > 0.0) || !std::isfinite(s.scale))
    throw core::ShapeError("shape scale must be finite and > 0, got " + std::to_string(s.scale));
  if (!std::isfinite(s.rotation) || !std::isfinite(s.centre.x()) || !std::isfinite(s.centre.y()))
    throw core::ShapeError("shape centre and rotation must be finite");
  switch (s.kind) {
    case core::ShapeKind::Polar: {
      Expression r("polar: r(phi)", s.r_expr, {"phi"});
      std::vector<double> samples(kSamples);
      for (int k = 0; k < kSamples; ++k) samples[k] = r(2.0 * kPi * k / kSamples);
      return core::make_polar(std::move(samples));
    }
    case core::ShapeKind::Parametric: {
      Expression x("parametric: x(s)", s.x_expr, {"s"});
      Expression y("parametric: y(s)", s.y_expr, {"s"});
      // Closed curves: s = 1 is s = 0 again, so sample [0, 1).
      const int n = kSamples;
      std::vector<core::Vec2> pts(n);
      for (int k = 0; k < n; ++k) {
        const double u = s.closed ? static_cast<double>(k) / n : static_cast<double>(k) / (n - 1);
        pts[k] = core::Vec2(x(u), y(u));
        const std::string at = "s = " + std::to_string(u);
        check_finite("parametric: x(s)", s.x_expr, pts[k].x(), at.c_str());
        check_finite("parametric: y(s)", s.y_expr, pts[k].y(), at.c_str());
      }
      try {
        return core::make_sampled(std::move(pts), s.closed);
      } catch (const core::ShapeError& e) {
        throw core::ShapeError(std::string("parametric: ") + e.what());
      }
    }
    case core::ShapeKind::Implicit: {
      auto f = std::make_shared<Expression>("implicit: f(x, y)", s.f_expr, std::initializer_list<const char*>{"x", "y"});
      try {
        return core::make_implicit([f](double x, double y) { return (*f)(x, y); }, kImplicitHalfBox);
      } catch (const core::ShapeError& e) {
        throw core::ShapeError(std::string(e.what()) + " (f = '" + s.f_expr + "', box [-" +
                               std::to_string(static_cast<int>(kImplicitHalfBox)) + ", " +
                               std::to_string(static_cast<int>(kImplicitHalfBox)) + "]^2 around the centre)");
      }
    }
    default:
      return core::make_curve(s);
  }
}

core::CompiledCommand compile(const core::Command& cmd) { return core::CompiledCommand(cmd, compile_curve(cmd.shape)); }

}  // namespace shapeform::shapes
