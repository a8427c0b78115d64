#!/usr/bin/env bash
# #41 on a GPU, third run: the raster floor's clears and stores, and the main job with the
# depth discarded after the pass, the colour cleared by a compute pass, and the display target.
set -u
T0=$(date +%s); t() { echo "== [$(( $(date +%s) - T0 )) s] $*"; }
R=/tmp/r; mkdir -p $R
exec > >(tee $OUT/log.txt) 2>&1
t setup
if [ -z "${LOCAL:-}" ]; then for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; fi
[ -n "${LOCAL:-}" ] || python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 3
export PYTHONPATH=${LOCAL:+$LOCAL:}/tmp/site:$PWD XDG_RUNTIME_DIR=/tmp VRNEURAL_CACHE=/tmp/vc PYTHONUNBUFFERED=1
j=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f $j ] && export VK_DRIVER_FILES=$j __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
filt() { grep -v "^ *frames  \|^wrote\|summary \|^adapter\|^objects\|^run  "; }
var() { n=$1; v=$2; shift 2; t "$v $n $*"; timeout 100 python3 .devrun/variant_run.py $v run --no-video --quiet --force --save-frames none --out $R/$n ${EXTRA:-} "$@" 2>&1 | filt; }
var warm none --frames ${F1:-300}
t raster floor
timeout 100 python3 docs/results/h200/raster_floor.py ${RF:-4128x2208} $R/raster_floor.json 2>&1
for i in 1 2; do
  var base_$i none --frames ${F2:-600}
  var disc_$i discard --frames ${F2:-600}
  var cclr_$i cclear,discard --frames ${F2:-600}
  var dispdisc_$i discard --frames ${F2:-600} --target display
done
t done
tar -czf $OUT/r.tgz -C /tmp r
