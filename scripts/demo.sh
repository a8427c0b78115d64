#!/usr/bin/env bash
# The main job: set-up, then the built-in demo (3 bundled neural materials, quest3 profile,
# both eyes, reuse N = 4): `vrneural run --eyes 2 --reuse 4`. It writes a side-by-side stereo
# video, PNG + EXR frames of both eyes and summary.json to a new out/run-<date>-<time>/ and
# prints where they are and the timing summary. Arguments replace the default command and go
# to `vrneural`, e.g. `bash scripts/demo.sh run --profile preview` or `bash scripts/demo.sh info`.
# It runs in the directory it was called from, so out/ and relative paths in the arguments are
# yours (the README calls it from the repository root).
set -euo pipefail
here="$PWD"
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
(cd "$repo" && bash scripts/setup.sh)
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
if [ "$#" -eq 0 ]; then
    echo "[demo] vrneural run --eyes 2 --reuse 4   (90 frames at 2064x2208 per eye; a few" \
        "minutes on a CPU adapter, progress below)"
    set -- run --eyes 2 --reuse 4
fi
cd "$here"
exec "$repo/.venv/bin/vrneural" "$@"
