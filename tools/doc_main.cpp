#include "doc_main.hpp"

#include <fstream>
#include <iostream>
#include <sstream>

#include "shapeform_version.hpp"  // generated in the build tree

namespace shapeform::tools {
namespace {

/// Reads the whole file into text; false when it cannot be read.
bool read_file(const std::string& path, std::string& text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  text = s.str();
  return true;
}

/// Writes (or with check, compares) the generated text of path. The exit status of doc_main.
int update(const DocProgram& program, const std::string& path, bool check) {
  std::string text, generated;
  if (!read_file(path, text)) {
    std::cerr << program.name << ": cannot read " << path << "\n";
    return 2;
  }
  try {
    generated = program.generate(path, text);
  } catch (const std::exception& e) {
    std::cerr << program.name << ": " << path << ": " << e.what() << "\n";
    return 2;
  }
  if (generated == text) return 0;
  if (check) {
    std::cerr << path << " is stale: it differs from what " << program.source << " generates; run "
              << program.script << "\n";
    return 1;
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << generated;
  if (!out) {
    std::cerr << program.name << ": cannot write " << path << "\n";
    return 2;
  }
  std::cerr << "rewrote " << path << "\n";
  return 0;
}

}  // namespace

int doc_main(int argc, char** argv, const DocProgram& program) {
  const std::string usage =
      "usage: " + program.name + " [--check] FILE\n" + program.files +
      "  --check    change nothing; exit 1 when FILE differs from what would be generated\n"
      "  --version  print the program's version and exit\n";
  bool check = false;
  std::string path;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << usage;
      return 0;
    }
    if (arg == "--version") {
      std::cout << program.name << " " << kVersion << "\n";
      return 0;
    }
    if (arg == "--check") {
      check = true;
    } else if (path.empty() && arg.rfind("-", 0) != 0) {
      path = arg;
    } else {
      std::cerr << usage;
      return 2;
    }
  }
  if (path.empty()) {
    std::cerr << usage;
    return 2;
  }
  return update(program, path, check);
}

}  // namespace shapeform::tools
