#pragma once
/// What is generated from the topic table (dds/topic_table.hpp) into files people and scripts read, as
/// pure functions: README.md's topic table, docs/SECURITY.md's table of access and the permissions of
/// scripts/make_keystore.sh. shapeform_topic_doc writes them (scripts/gen_topic_docs.sh); ctests fail
/// while a file differs from what the table generates.
#include <string>

namespace shapeform::tools {

/// The markdown table of every topic: topic | type (with its key) | QoS | publisher | rate.
std::string topics_markdown();

/// The markdown table of access: role | publishes | subscribes to, each role's topics in table order
/// ("nothing", "every topic").
std::string access_markdown();

/// The shell function rules() of scripts/make_keystore.sh: NAME (an enclave) -> the <publish> and
/// <subscribe> allow rules of its role, one echo per line.
std::string keystore_rules();

/// `text` with every block between a line holding "BEGIN GENERATED topics: SECTION" and the next line
/// holding "END GENERATED" regenerated: SECTION "table" (topics_markdown), "access" (access_markdown)
/// or "permissions" (keystore_rules). Throws std::invalid_argument for another section or an
/// unterminated block.
std::string regenerate_topic_doc(const std::string& text);

}  // namespace shapeform::tools
