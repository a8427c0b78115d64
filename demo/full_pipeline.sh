#!/usr/bin/env bash
# The whole path on one synthetic material, with small settings (a few minutes on 2 CPU cores):
#   btf synth -> teach (128-wide teacher) -> distill (8-wide coarse-to-fine student) -> run
# Usage: bash demo/full_pipeline.sh [WORK_DIR] [PRESET]
#   WORK_DIR  where everything goes, relative to the current directory (default: the repository's
#             out/pipeline-<date>-<time>); must not exist yet
#   PRESET    leather (default), fabric, wood, carpet, metal or stone
# Writes WORK_DIR/{PRESET.btf, teacher.pt, teacher.vrnm, student.pt, student.vrnm, scene.toml,
# run/ (stereo.mp4, PNG + EXR frames, summary.json)} and WORK_DIR/times.txt (seconds per step).
set -euo pipefail
if [ -n "${1:-}" ]; then  # a relative WORK_DIR is relative to where you are, as usual
    case "$1" in /*) W="$1" ;; *) W="$PWD/$1" ;; esac
fi
cd "$(dirname "${BASH_SOURCE[0]}")/.."
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
W="${W:-out/pipeline-$(date +%Y%m%d-%H%M%S)}"
PRESET="${2:-leather}"
VRN="${VRNEURAL:-.venv/bin/vrneural}"
if [ -e "$W" ]; then
    echo "full_pipeline.sh: $W already exists; give a new work directory" >&2
    exit 2
fi
case "$PRESET" in  # checked before anything is made, so a retry needs no new directory
    leather|fabric|wood|carpet|metal|stone) ;;
    *) echo "full_pipeline.sh: preset '$PRESET' is not one of leather, fabric, wood, carpet, metal, stone" >&2
       exit 2 ;;
esac
mkdir -p "$W"
: > "$W/times.txt"
step() {  # step NAME CMD...: run, print and record the wall time
    local name="$1"; shift
    echo "== $name: $*"
    local t0=$SECONDS
    "$@"
    echo "$name $((SECONDS - t0)) s" | tee -a "$W/times.txt"
}
step synth "$VRN" btf synth --preset "$PRESET" --res 32 --dirs 24 --seed 0 -o "$W/$PRESET.btf"
step teach "$VRN" teach "$W/$PRESET.btf" -o "$W/teacher.pt" --epochs 3
step distill "$VRN" distill "$W/teacher.pt" -o "$W/student.pt" --epochs 3
cat > "$W/scene.toml" <<TOML
# written by demo/full_pipeline.sh: the freshly distilled student on a sphere and a cloth
profile = "preview"
[[objects]]
mesh = "sphere"
position = [-0.3, 0.8, 0.0]
scale = 1.5
[objects.material]
pack = "student.vrnm"
scale = 2.5
[[objects]]
mesh = "cloth"
position = [0.35, 0.34, -0.3]
scale = 1.7
[objects.material]
pack = "student.vrnm"
scale = 3.0
[[objects]]
mesh = "plane"
scale = 6.0
[objects.material]
kind = "plain"
albedo = [0.32, 0.32, 0.34]
[[lights]]
position = [-1.0, 2.0, 1.3]
colour = [1.0, 0.93, 0.85]
intensity = 4.5
[[lights]]
position = [1.4, 1.5, 0.9]
colour = [0.8, 0.88, 1.0]
intensity = 2.2
[[lights]]
position = [0.0, 1.9, -0.4]
intensity = 2.0
motion = "circle"
radius = 0.9
period = 12.0
TOML
step run "$VRN" run "$W/scene.toml" --eyes 2 --reuse 4 --frames 45 --out "$W/run"
echo "== done; times in $W/times.txt:"
cat "$W/times.txt"
