#!/usr/bin/env bash
# Installs the Debian dependencies (as root; without root it stops if any is missing) and builds
# shapeform into build/ (Release).
#
#   scripts/build.sh [CMAKE_CONFIGURE_ARGS...]
#
# Idempotent: a second run only rebuilds what changed. Extra arguments go to the configure step.
case "${1-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;; esac
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install_deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build -j"$(nproc)"
