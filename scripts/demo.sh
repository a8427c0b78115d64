#!/usr/bin/env bash
# The main job: set-up, then the built-in demo. Extra arguments go to `vrneural`.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/setup.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
if [ "$#" -eq 0 ]; then set -- info; fi
exec .venv/bin/vrneural "$@"
