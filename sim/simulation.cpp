#include "simulation.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <ostream>
#include <stdexcept>

#include "core/metric_table.hpp"
#include "record/recorder.hpp"
#include "util/clock.hpp"
#include "util/text.hpp"

namespace shapeform::sim {

SimOptions run_options(const core::ConvergenceParams& converge, const core::VehicleParams& vehicle,
                       std::uint64_t heading_seed) {
  SimOptions opt;
  opt.settle = {converge.band_abs, converge.band_rel, converge.gap_cv_max};
  opt.converge = converge;
  opt.vehicle = vehicle;
  opt.heading_seed = heading_seed;
  return opt;
}

namespace {
/// One CSV fragment with the metric table's values ("" for undefined values).
std::string metric_csv_values(const core::Metrics& m) {
  std::string out;
  for (const core::MetricInfo& info : core::kMetricTable) {
    if (&info != core::kMetricTable) out += ',';  // no comma before the first
    if (const auto v = info.get(m)) out += info.count ? std::to_string(std::llround(*v)) : util::format_g10(*v);
  }
  return out;
}
}  // namespace

namespace {
/// One step of the recording: metrics, the tracked centre and positions.
void record_step(record::Recorder& rec, double wall, long k, std::uint64_t epoch, const core::CompiledCommand& cmd,
                 double t, const core::Swarm& swarm, const core::Metrics& m, bool converged) {
  const std::vector<core::Vec2>& x = swarm.positions();
  // A robot's heading is drawn (an arrow) when it has one of its own: the unicycle's.
  const bool headings = swarm.vehicle().model == core::VehicleModel::Unicycle && swarm.vehicles().size() == x.size();
  rec.write_metrics({wall, t, epoch, static_cast<int>(x.size()), m, converged});
  if (cmd.tracking.enabled) {  // before the positions: the sample's drawing shows this centre
    const core::Vec2 c = core::centre_at(cmd.tracking.path, t);
    rec.write_centre(wall, t, epoch, c.x(), c.y());
  }
  std::vector<record::AgentRow> agents(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    agents[i] = {static_cast<std::int32_t>(i), epoch, x[i].x(), x[i].y(), {}};
    if (headings) agents[i].heading = swarm.vehicles()[i].heading;
  }
  rec.write_positions(wall, t, k, agents);
}
}  // namespace

namespace {
/// The smallest pairwise distance of x (infinity below two agents).
double smallest_distance(const std::vector<core::Vec2>& x) {
  const std::vector<double> nn = core::nearest_distances(x);
  return nn.empty() ? std::numeric_limits<double>::infinity() : *std::min_element(nn.begin(), nn.end());
}

/// The run's safety figures into the metrics of a step (core::Metrics' run fields).
void run_figures(core::Metrics& m, const SeparationRecord& sep, const core::Swarm& swarm) {
  if (sep.min) {
    m.min_separation_run = *sep.min;
    m.min_separation_run_time = sep.model_time;
  }
  const core::SafetyCounts& c = swarm.safety_counts();
  m.filter_interventions = static_cast<int>(c.interventions);
  m.deadlock_sidesteps = static_cast<int>(c.sidesteps);
  m.promises_broken = static_cast<int>(c.broken);
  m.agents_blocked = swarm.blocked_agents();
}
}  // namespace

core::Kernel auto_kernel(int agents, const core::VehicleParams& vehicle) {
  return agents >= 64 && vehicle.model == core::VehicleModel::Integrator ? core::Kernel::Batch : core::Kernel::Agent;
}

SimResult run_simulation(const core::CompiledCommand& cmd, std::vector<core::Vec2> start, long steps,
                         const SimOptions& opt) {
  core::Swarm swarm(cmd, std::move(start));
  swarm.set_kernel(opt.kernel);
  swarm.set_batch(opt.batch);
  swarm.set_vehicle(opt.vehicle, core::start_headings(opt.vehicle, static_cast<int>(swarm.positions().size()),
                                                      opt.heading_seed));
  std::vector<core::Vec2> last = swarm.positions();
  core::ConvergenceDetector verdict(opt.converge);
  verdict.set_command(cmd);
  std::vector<double> err;
  std::vector<std::optional<double>> gap;
  err.reserve(static_cast<std::size_t>(steps) + 1);
  gap.reserve(static_cast<std::size_t>(steps) + 1);
  if (opt.metrics_csv) {
    *opt.metrics_csv << "step,model_time";
    for (const core::MetricInfo& info : core::kMetricTable) *opt.metrics_csv << ',' << info.name;
    *opt.metrics_csv << '\n';
  }
  if (opt.positions_csv) *opt.positions_csv << "step,agent,x1,x2\n";
  const std::int64_t start_ns = util::steady_ns();
  const auto wall_s = [start_ns] { return static_cast<double>(util::steady_ns() - start_ns) * 1e-9; };
  if (opt.recorder) opt.recorder->write_command(wall_s(), swarm.time(), opt.epoch, "", "shapeform_sim", cmd);
  SimResult r;
  const bool separation = opt.separation || core::filters(cmd);
  for (long k = 0;; ++k) {
    const auto& x = swarm.positions();
    if (separation && x.size() >= 2) {
      const double d = smallest_distance(x);
      if (!r.separation.min || d < *r.separation.min) {
        r.separation.min = d;
        r.separation.step = k;
        r.separation.model_time = swarm.time();
      }
    }
    for (const core::Vec2& xi : x)
      for (const core::KeepOutZone& z : cmd.keep_out) {
        const double in = core::depth(z, xi);
        r.separation.zone_entries += in > 1e-9 ? 1 : 0;  // on the boundary, to rounding, is outside
        r.separation.zone_depth = std::max(r.separation.zone_depth, in);
      }
    // The O(N^2) metrics are only needed per step when they are written.
    const bool full = opt.metrics_csv != nullptr || opt.recorder != nullptr;
    core::Metrics m = core::compute_metrics(cmd, x, swarm.time(), full);
    if (separation) run_figures(m, r.separation, swarm);
    err.push_back(m.shape_error_mean.value_or(0.0));
    gap.push_back(core::uniformity(cmd, m));
    // Agents the safety filter holds from the law's step are not where the law sends them: no verdict.
    if (swarm.blocked_agents() > 0)
      verdict.blocked();
    else
      verdict.add(swarm.time(), m.shape_error_mean, gap.back(), core::spread(x));
    if (verdict.converged() && !r.converged_step) r.converged_step = k;
    if (opt.recorder) record_step(*opt.recorder, wall_s(), k, opt.epoch, cmd, swarm.time(), swarm, m, verdict.converged());
    if (opt.metrics_csv) *opt.metrics_csv << k << ',' << util::format_g10(swarm.time()) << ',' << metric_csv_values(m) << '\n';
    if (opt.positions_csv)
      for (std::size_t i = 0; i < x.size(); ++i)
        *opt.positions_csv << k << ',' << i << ',' << util::format_g10(x[i].x()) << ',' << util::format_g10(x[i].y()) << '\n';
    if (k == steps) break;
    if (k + 1 == steps) last = x;
    swarm.step();
  }
  r.metrics = core::compute_metrics(cmd, swarm.positions(), swarm.time());
  if (separation) run_figures(r.metrics, r.separation, swarm);
  r.safety = swarm.safety_counts();
  r.blocked_agents = swarm.blocked_agents();
  r.blocked_by = swarm.blocked_by();
  r.settle_step = core::settle_index(err, gap, opt.settle);
  r.final_positions = swarm.positions();
  r.final_vehicles = swarm.vehicles();
  for (std::size_t i = 0; i < last.size() && steps > 0; ++i)
    r.max_step = std::max(r.max_step, (r.final_positions[i] - last[i]).norm());
  r.converged = verdict.converged();
  r.why = verdict.why();
  r.steps = swarm.steps();
  r.model_time = swarm.time();
  return r;
}

std::vector<core::Vec2> read_positions_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("init file '" + path + "': cannot open");
  std::vector<core::Vec2> out;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos || line[line.find_first_not_of(" \t")] == '#') continue;
    const auto comma = line.find(',');
    const auto where = "init file '" + path + "' line " + std::to_string(lineno) + ": ";
    if (comma == std::string::npos || line.find(',', comma + 1) != std::string::npos)
      throw std::runtime_error(where + "expected two comma-separated numbers x1,x2, got '" + line + "'");
    double v[2];
    const std::string parts[2] = {line.substr(0, comma), line.substr(comma + 1)};
    bool numeric = true;
    for (int k = 0; k < 2; ++k) {
      const char* s = parts[k].c_str();
      char* end = nullptr;
      v[k] = std::strtod(s, &end);
      while (end && (*end == ' ' || *end == '\t')) ++end;
      if (end == s || *end != '\0') numeric = false;
      else if (!std::isfinite(v[k]))
        throw std::runtime_error(where + "non-finite coordinate '" + parts[k] + "'");
    }
    if (!numeric) {
      if (out.empty() && lineno == 1) continue;  // header row
      throw std::runtime_error(where + "not a number in '" + line + "'");
    }
    out.emplace_back(v[0], v[1]);
  }
  if (out.empty()) throw std::runtime_error("init file '" + path + "': no positions");
  return out;
}

}  // namespace shapeform::sim
