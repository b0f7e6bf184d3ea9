/// shapeform_config_doc: rewrites (or checks) what is generated from the config table: the key tables
/// of config/README.md and the whole of config/default.yaml. Usage: shapeform_config_doc [--check] FILE
#include "config/config.hpp"
#include "doc_main.hpp"

int main(int argc, char** argv) {
  using namespace shapeform;
  return tools::doc_main(
      argc, argv,
      {"shapeform_config_doc",
       "  FILE.md (config/README.md): replaces every block between '<!-- BEGIN GENERATED keys: SECTION -->'\n"
       "  and '<!-- END GENERATED -->' by the key table of SECTION generated from the config table.\n"
       "  FILE.yaml (config/default.yaml): writes every key with its default and a comment.\n",
       "the config table", "scripts/gen_config_doc.sh", [](const std::string& path, const std::string& text) {
         const bool yaml = path.size() >= 5 && path.compare(path.size() - 5, 5, ".yaml") == 0;
         return yaml ? config::default_yaml() : config::regenerate_doc(text);
       }});
}
