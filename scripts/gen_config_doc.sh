#!/usr/bin/env bash
# Rewrites what is generated from the declared parameter table: the key tables of config/README.md (the
# blocks between "<!-- BEGIN GENERATED keys: SECTION -->" and "<!-- END GENERATED -->"; the prose stays as
# written) and config/default.yaml (every key with its default and a comment).
set -euo pipefail

usage='usage: scripts/gen_config_doc.sh [--check] [--build-dir DIR]
  Builds shapeform_config_doc in DIR (default: build, configured already) and regenerates the key
  tables of config/README.md and config/default.yaml from the config table.
  --check          change nothing; exit 1 when either file is stale
  --build-dir DIR  the CMake build directory (default: build)
  -h, --help       this text'

. "$(dirname "$0")/lib/gen_doc.sh"
gen_doc "$usage" shapeform_config_doc "config/README.md config/default.yaml" "$@"
