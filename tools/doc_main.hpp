#pragma once
/// The one main of the programs that rewrite (or check) a file generated from a declared table:
/// `PROGRAM [--check] FILE` (shapeform_config_doc, shapeform_topic_doc).
#include <functional>
#include <string>

namespace shapeform::tools {

/// What one such program generates.
struct DocProgram {
  std::string name;    ///< "shapeform_config_doc"
  std::string files;   ///< the usage lines that say which FILE gets what
  std::string source;  ///< what it generates from, for the stale message: "the config table"
  std::string script;  ///< what rewrites the files: "scripts/gen_config_doc.sh"
  /// The new text of FILE (path) from its current text; throws std::exception when it cannot.
  std::function<std::string(const std::string& path, const std::string& text)> generate;
};

/// Parses argc/argv (--check, --help, --version, FILE) and rewrites FILE, or with --check only
/// compares. Exit status: 0 up to date or rewritten, 1 stale (--check), 2 bad usage, a file that
/// cannot be read or written, or generate failed (the message names the file).
int doc_main(int argc, char** argv, const DocProgram& program);

}  // namespace shapeform::tools
