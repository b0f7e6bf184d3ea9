#!/usr/bin/env bash
# Rewrites what is generated from the topic table (common/dds/topic_table.hpp): the topic table of
# README.md, the table of access of docs/SECURITY.md and the permissions (rules()) of
# scripts/make_keystore.sh, each the block between a line holding "BEGIN GENERATED topics: SECTION"
# and the next line holding "END GENERATED"; everything else stays as written.
set -euo pipefail

usage='usage: scripts/gen_topic_docs.sh [--check] [--build-dir DIR]
  Builds shapeform_topic_doc in DIR (default: build, configured already) and regenerates the topic
  table of README.md, the access table of docs/SECURITY.md and the permissions of
  scripts/make_keystore.sh from the topic table.
  --check          change nothing; exit 1 when a file is stale
  --build-dir DIR  the CMake build directory (default: build)
  -h, --help       this text'

. "$(dirname "$0")/lib/gen_doc.sh"
gen_doc "$usage" shapeform_topic_doc "README.md docs/SECURITY.md scripts/make_keystore.sh" "$@"
