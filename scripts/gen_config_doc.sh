#!/usr/bin/env bash
# Rewrites what is generated from the declared parameter table: the key tables of config/README.md (the
# blocks between "<!-- BEGIN GENERATED keys: SECTION -->" and "<!-- END GENERATED -->"; the prose stays as
# written) and config/default.yaml (every key with its default and a comment).
set -euo pipefail

usage() {
  cat <<'USAGE'
usage: scripts/gen_config_doc.sh [--check] [--build-dir DIR]
  Builds shapeform_config_doc in DIR (default: build, configured already) and regenerates the key
  tables of config/README.md and config/default.yaml from the config table.
  --check          change nothing; exit 1 when either file is stale
  --build-dir DIR  the CMake build directory (default: build)
  -h, --help       this text
USAGE
}

root=$(cd "$(dirname "$0")/.." && pwd)
build="$root/build"
check=()
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --check) check=(--check); shift ;;
    --build-dir) [ $# -ge 2 ] || { usage >&2; exit 2; }; build=$(cd "$2" && pwd); shift 2 ;;
    *) usage >&2; exit 2 ;;
  esac
done

[ -f "$build/CMakeCache.txt" ] || { echo "gen_config_doc: $build is not a configured build directory" >&2; exit 2; }
cmake --build "$build" --target shapeform_config_doc >/dev/null
status=0
for f in "$root/config/README.md" "$root/config/default.yaml"; do
  "$build/bin/shapeform_config_doc" "${check[@]}" "$f" || status=$?
done
exit $status
