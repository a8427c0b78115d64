#!/usr/bin/env bash
# #41 on a GPU, second run: the raster floor, and the main job before/after the colour target
# lost its storage usage, with --target display, and with other depth formats.
set -u
T0=$(date +%s); t() { echo "== [$(( $(date +%s) - T0 )) s] $*"; }
R=/tmp/r; mkdir -p $R
exec > >(tee $OUT/log.txt) 2>&1
t setup
if [ -z "${LOCAL:-}" ]; then for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; fi
[ -n "${LOCAL:-}" ] || python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 3
export PYTHONPATH=${LOCAL:+$LOCAL:}/tmp/site:$PWD:$PWD/.abold2 XDG_RUNTIME_DIR=/tmp VRNEURAL_CACHE=/tmp/vc PYTHONUNBUFFERED=1
j=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f $j ] && export VK_DRIVER_FILES=$j __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
nvidia-smi --query-gpu=name,driver_version,clocks.sm --format=csv 2>/dev/null
(while sleep 1; do nvidia-smi --query-gpu=timestamp,clocks.sm,utilization.gpu,power.draw --format=csv,noheader 2>/dev/null; done > $R/smi.csv) &
SMI=$!
keep() { rm -f $R/$1/*.exr; case $1 in *_1) ;; *) rm -f $R/$1/*.png;; esac; rm -f $R/$1/frame0*_eye1.png; }
filt() { grep -v "^ *frames  \|^wrote\|summary \|^adapter\|^objects"; }
new() { n=$1; shift; t "new $n $*"; timeout 150 python3 -m vrneural run --no-video --quiet --force --out $R/$n ${EXTRA:-} "$@" 2>&1 | filt; keep $n; }
bef() { n=$1; shift; t "before $n $*"; timeout 150 python3 -m vrneural_682f982 run --no-video --quiet --force --out $R/$n ${EXTRA:-} "$@" 2>&1 | filt; keep $n; }
dep() { n=$1; d=$2; shift 2; t "depth $d $n $*"; timeout 150 python3 .devrun/patched_run.py $d run --no-video --quiet --force --out $R/$n ${EXTRA:-} "$@" 2>&1 | filt; keep $n; }
new new_warm --frames ${F1:-300}
bef bef_warm --frames ${F1:-300}
t raster floor
timeout 120 python3 docs/results/h200/raster_floor.py ${RF:-4128x2208} $R/raster_floor.json 2>&1
for i in 1 2; do
  bef bef_$i --frames ${F2:-600}
  new new_$i --frames ${F2:-600}
  new disp_$i --frames ${F2:-600} --target display
  dep d24_$i depth24plus --frames ${F2:-600}
  dep d16_$i depth16unorm --frames ${F2:-600}
done
new half_1 --frames ${F2:-600} --eye-res 1032x1104
new disp_half_1 --frames ${F2:-600} --eye-res 1032x1104 --target display
t bench frame
timeout 200 python3 -m vrneural bench frame --lights 3 --out $R/bench-frame --no-progress ${BF:-} 2>&1 | tail -3
t done
kill $SMI
tar -czf $OUT/r.tgz -C /tmp r
ls -la $OUT
