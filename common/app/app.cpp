#include "app/app.hpp"

#include <iostream>
#include <string>

#include "dds/transport.hpp"

#include "shapeform_version.hpp"  // generated in the build tree

namespace shapeform::app {

App::App(std::string prog, const std::string& description) : prog_(std::move(prog)), cli_(description) {
  cli_.set_version_flag("--version", version_line(prog_), "print the program's version and exit");
}

std::string version_line(const std::string& prog) { return prog + " " + kVersion; }

void App::add_config_options(const std::string& config_help, bool with_domain) {
  cli_.add_option("--config", config_path_, config_help);
  if (with_domain) domain_option_ = cli_.add_option("--domain", domain_, "DDS domain id 0.." + std::to_string(dds::kMaxDomainId) + " (overrides transport.domain)");
  cli_.add_option("--set", sets_, "override any config key: dotted.key=value (repeatable)");
}

std::optional<int> App::parse(int argc, char** argv) {
  try {
    cli_.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return cli_.exit(e);  // --help, --version
    return usage_error(e.what());
  }
  return std::nullopt;
}

std::optional<config::Config> App::load_config(const std::vector<std::string>& extra) const {
  std::vector<std::string> sets = sets_;
  // The loader checks the domain's range like any other key's.
  if (domain_option_ && domain_option_->count() > 0) sets.push_back("transport.domain=" + std::to_string(domain_));
  sets.insert(sets.end(), extra.begin(), extra.end());
  try {
    return config::load(config_path_, sets);
  } catch (const config::ConfigError& e) {
    for (const auto& p : e.problems()) std::cerr << prog_ << ": " << p << '\n';
    return std::nullopt;
  }
}

int App::run(const std::function<int()>& body) const {
  try {
    return body();
  } catch (const std::exception& e) {
    std::cerr << prog_ << ": " << e.what() << std::endl;
    return 1;
  }
}

int App::usage_error(const std::string& message) const {
  std::cerr << prog_ << ": " << message << '\n';
  return kExitUsage;
}

}  // namespace shapeform::app
