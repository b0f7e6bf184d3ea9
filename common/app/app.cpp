#include "app/app.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include "protocol/transport.hpp"
#include "util/text.hpp"

#include "shapeform_version.hpp"  // generated in the build tree

namespace shapeform::app {

App::App(std::string prog, const std::string& description) : prog_(std::move(prog)), cli_(description) {
  cli_.set_version_flag("--version", version_line(prog_), "print the program's version and exit");
}

std::string version_line(const std::string& prog) { return prog + " " + kVersion; }

std::string writable_dir_problem(const std::string& dir) {
  if (dir.empty()) return "";
  const std::string shown = "'" + util::excerpt(dir) + "'";
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec))
    return shown + " is not a folder: give a writable folder";
  std::filesystem::create_directories(dir, ec);
  if (ec) return "cannot create the folder " + shown + " (" + ec.message() + "): give a writable folder";
  std::string probe = (std::filesystem::path(dir) / ".shapeform_write_probe_XXXXXX").string();
  std::vector<char> name(probe.begin(), probe.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) {
    const int err = errno;
    return "cannot write into the folder " + shown + " (" + std::strerror(err) + "): give a writable folder";
  }
  ::close(fd);
  ::unlink(name.data());
  return "";
}

std::string writable_file_problem(const std::string& file) {
  if (file.empty()) return "";
  std::error_code ec;
  const std::filesystem::path p(file);
  if (std::filesystem::exists(p, ec) && !std::filesystem::is_regular_file(p, ec))
    return "'" + util::excerpt(file) + "' exists and is not a regular file: give a file path to write";
  const std::filesystem::path parent = p.has_parent_path() ? p.parent_path() : std::filesystem::path(".");
  return writable_dir_problem(parent.string());
}

bool parse_id_list(const std::string& text, int max_id, std::size_t max_count, std::vector<std::int32_t>& ids,
                   std::string& error) {
  ids.clear();
  std::set<std::int32_t> seen;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t comma = std::min(text.find(',', pos), text.size());
    const std::string part = text.substr(pos, comma - pos);
    long a = -1, b = -1;
    char extra = 0;
    if (std::sscanf(part.c_str(), "%ld-%ld%c", &a, &b, &extra) == 2) {
    } else if (std::sscanf(part.c_str(), "%ld%c", &a, &extra) == 1) {
      b = a;
    } else {
      error = "expected ids like 0-49 or 0,5,7, got '" + part + "'";
      return false;
    }
    if (a < 0 || b > max_id || a > b) {
      error = "ids must be in 0.." + std::to_string(max_id) + " with first <= last, got '" + part + "'";
      return false;
    }
    for (long i = a; i <= b; ++i) {
      if (!seen.insert(static_cast<std::int32_t>(i)).second) {
        error = "id " + std::to_string(i) + " listed twice";
        return false;
      }
      ids.push_back(static_cast<std::int32_t>(i));
    }
    pos = comma + 1;
  }
  if (ids.size() > max_count) {
    error = "at most " + std::to_string(max_count) + " agents per process, got " + std::to_string(ids.size());
    return false;
  }
  return !ids.empty();
}

namespace {

CLI::Validator path_check(std::string name, std::string (*problem)(const std::string&)) {
  return CLI::Validator([problem](std::string& value) { return problem(value); }, "PATH", std::move(name));
}

}  // namespace

CLI::Validator writable_dir() { return path_check("writable folder", writable_dir_problem); }
CLI::Validator writable_file() { return path_check("writable file", writable_file_problem); }

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
  } catch (const dds::SecurityError& e) {
    // A key file, keystore or identity that cannot work: a bad configuration, never a silent unsecured run.
    std::cerr << prog_ << ": " << util::bounded_line(e.what()) << std::endl;
    return kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << prog_ << ": " << util::bounded_line(e.what()) << std::endl;
    return 1;
  }
}

int App::usage_error(const std::string& message) const {
  // A flag's value is untrusted input: the line quotes at most about util::kQuoteMax of it.
  std::cerr << prog_ << ": " << util::bounded_line(message) << '\n';
  return kExitUsage;
}

}  // namespace shapeform::app
