// The preamble's output-path checks: a flag that names an output folder or file is refused at parse
// time (exit 2), before a config is loaded or a DDS participant created.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "app/app.hpp"

namespace app = shapeform::app;
namespace fs = std::filesystem;

namespace {

/// A folder of its own per test case (ctest runs them in parallel processes).
struct TempDir {
  explicit TempDir(const std::string& name) : path(fs::temp_directory_path() / ("shapeform_app_test_" + name)) {
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  fs::path path;
};

/// Exit status of parse() for `prog --record DIR` with writable_dir() on --record.
std::optional<int> parse_record(const std::string& dir) {
  app::App a("shapeform_test", "test");
  std::string record;
  a.cli().add_option("--record", record, "folder")->check(app::writable_dir());
  std::vector<std::string> args{"shapeform_test", "--record", dir};
  std::vector<char*> argv;
  for (auto& s : args) argv.push_back(s.data());
  return a.parse(static_cast<int>(argv.size()), argv.data());
}

}  // namespace

TEST_CASE("writable_dir_problem: a folder that is or can be made writable passes, others are named", "[app]") {
  const TempDir t("problems");
  CHECK(app::writable_dir_problem("").empty());
  CHECK(app::writable_dir_problem(t.path.string()).empty());
  CHECK(app::writable_dir_problem((t.path / "new" / "deeper").string()).empty());  // created, as --record would
  CHECK(fs::is_directory(t.path / "new" / "deeper"));
  CHECK(fs::is_empty(t.path / "new" / "deeper"));  // the probe file is gone
  std::ofstream(t.path / "plain") << "x";
  // Under a regular file, or on a read-only file system: refused even for root.
  CHECK(app::writable_dir_problem((t.path / "plain" / "rec").string()).find("cannot create the folder '") == 0);
  CHECK(app::writable_dir_problem((t.path / "plain").string()).find("is not a folder") != std::string::npos);
  CHECK(app::writable_dir_problem("/proc/shapeform_record").find("cannot create the folder '/proc/shapeform_record'") == 0);
  CHECK(app::writable_dir_problem("/proc").find("cannot write into the folder '/proc'") == 0);
  CHECK(app::writable_file_problem((t.path / "out.csv").string()).empty());
  CHECK(app::writable_file_problem(t.path.string()).find("is not a regular file") != std::string::npos);
  CHECK_FALSE(app::writable_file_problem("/proc/out.csv").empty());
}

TEST_CASE("a flag checked with writable_dir() is a usage error (exit 2) at parse time", "[app]") {
  const TempDir t("parse");
  CHECK_FALSE(parse_record(t.path.string()).has_value());
  CHECK(parse_record("/proc/shapeform_record") == std::optional<int>(app::kExitUsage));
}

TEST_CASE("parse_id_list: ranges and lists in the order given; each bad part named", "[app]") {
  std::vector<std::int32_t> ids;
  std::string error;
  REQUIRE(app::parse_id_list("4-6,0,9", 99, 10, ids, error));
  CHECK(ids == std::vector<std::int32_t>{4, 5, 6, 0, 9});
  REQUIRE(app::parse_id_list("7", 99, 10, ids, error));
  CHECK(ids == std::vector<std::int32_t>{7});

  CHECK_FALSE(app::parse_id_list("1-3,2", 99, 10, ids, error));
  CHECK(error == "id 2 listed twice");
  CHECK_FALSE(app::parse_id_list("5-2", 99, 10, ids, error));
  CHECK(error == "ids must be in 0..99 with first <= last, got '5-2'");
  CHECK_FALSE(app::parse_id_list("0-100", 99, 200, ids, error));
  CHECK(error == "ids must be in 0..99 with first <= last, got '0-100'");
  CHECK_FALSE(app::parse_id_list("0,x1", 99, 10, ids, error));
  CHECK(error == "expected ids like 0-49 or 0,5,7, got 'x1'");
  CHECK_FALSE(app::parse_id_list("1-2-3", 99, 10, ids, error));
  CHECK(error == "expected ids like 0-49 or 0,5,7, got '1-2-3'");
  CHECK_FALSE(app::parse_id_list("", 99, 10, ids, error));
  CHECK_FALSE(app::parse_id_list("0-10", 99, 10, ids, error));
  CHECK(error == "at most 10 agents per process, got 11");
}
