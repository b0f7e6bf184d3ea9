/// shapeform_config_doc: rewrites (or checks) what is generated from the config table: the key tables
/// of config/README.md and the whole of config/default.yaml. Usage: shapeform_config_doc [--check] FILE
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "config/config.hpp"
#include "shapeform_version.hpp"  // generated in the build tree

int main(int argc, char** argv) {
  const std::string usage =
      "usage: shapeform_config_doc [--check] FILE\n"
      "  FILE.md (config/README.md): replaces every block between '<!-- BEGIN GENERATED keys: SECTION -->'\n"
      "  and '<!-- END GENERATED -->' by the key table of SECTION generated from the config table.\n"
      "  FILE.yaml (config/default.yaml): writes every key with its default and a comment.\n"
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
      std::cout << "shapeform_config_doc " << shapeform::kVersion << "\n";
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
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::cerr << "shapeform_config_doc: cannot read " << path << "\n";
    return 2;
  }
  std::ostringstream text;
  text << in.rdbuf();
  std::string generated;
  try {
    const bool yaml = path.size() >= 5 && path.compare(path.size() - 5, 5, ".yaml") == 0;
    generated = yaml ? shapeform::config::default_yaml() : shapeform::config::regenerate_doc(text.str());
  } catch (const std::exception& e) {
    std::cerr << "shapeform_config_doc: " << path << ": " << e.what() << "\n";
    return 2;
  }
  if (generated == text.str()) return 0;
  if (check) {
    std::cerr << path
              << " is stale: it differs from what the config table generates; run scripts/gen_config_doc.sh\n";
    return 1;
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << generated;
  if (!out) {
    std::cerr << "shapeform_config_doc: cannot write " << path << "\n";
    return 2;
  }
  std::cerr << "rewrote " << path << "\n";
  return 0;
}
