/// shapeform_topic_doc: rewrites (or checks) what is generated from the topic table: README.md's topic
/// table, docs/SECURITY.md's table of access, scripts/make_keystore.sh's permissions.
/// Usage: shapeform_topic_doc [--check] FILE
#include "doc_main.hpp"
#include "topic_doc.hpp"

int main(int argc, char** argv) {
  using namespace shapeform;
  return tools::doc_main(
      argc, argv,
      {"shapeform_topic_doc",
       "  Replaces every block between a line holding 'BEGIN GENERATED topics: SECTION' and the next line\n"
       "  holding 'END GENERATED' by SECTION generated from the topic table (common/dds/topic_table.hpp):\n"
       "  table (README.md), access (docs/SECURITY.md) or permissions (scripts/make_keystore.sh).\n",
       "the topic table", "scripts/gen_topic_docs.sh",
       [](const std::string&, const std::string& text) { return tools::regenerate_topic_doc(text); }});
}
