# Sourced by the scripts that rewrite what a program generates from a declared table
# (scripts/gen_config_doc.sh, scripts/gen_topic_docs.sh): one command line, one way to run it.
#
#   gen_doc USAGE PROGRAM "FILE ..." [--check] [--build-dir DIR]
# builds PROGRAM in DIR (default: build, configured already) and runs it on each FILE (relative to
# the source folder), with --check: changing nothing, exit 1 when a file is stale. Exit status 2 on
# bad usage or a folder that is no configured build.

gen_doc() {
  local usage=$1 program=$2 files=$3 root build status=0 f
  local check=()
  shift 3
  root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
  build="$root/build"
  while [ $# -gt 0 ]; do
    case "$1" in
      -h|--help) echo "$usage"; return 0 ;;
      --check) check=(--check); shift ;;
      --build-dir) [ $# -ge 2 ] || { echo "$usage" >&2; return 2; }; build=$(cd "$2" && pwd); shift 2 ;;
      *) echo "$usage" >&2; return 2 ;;
    esac
  done
  [ -f "$build/CMakeCache.txt" ] || { echo "$(basename "$0" .sh): $build is not a configured build directory" >&2; return 2; }
  cmake --build "$build" --target "$program" >/dev/null
  for f in $files; do
    "$build/bin/$program" "${check[@]}" "$root/$f" || status=$?
  done
  return $status
}
