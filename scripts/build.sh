#!/usr/bin/env bash
# Installs the Debian dependencies (as root; without root it stops if any is missing) and builds
# shapeform into build/ (Release).
# Idempotent: a second run only rebuilds what changed. Extra arguments go to the configure step.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install_deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build -j"$(nproc)"
