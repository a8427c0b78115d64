#!/usr/bin/env bash
# #41 on a GPU, fourth run: the main job before (682f982) and after the compute clear, and with
# --target display (sRGB encoded in the shader, compute-cleared); bench frame after.
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
filt() { grep -v "^ *frames  \|^wrote\|summary \|^adapter\|^objects\|^run  "; }
new() { n=$1; shift; t "new $n $*"; timeout 100 python3 -m vrneural run --no-video --quiet --force --save-frames none --out $R/$n ${EXTRA:-} "$@" 2>&1 | filt; }
bef() { n=$1; shift; t "before $n $*"; timeout 100 python3 -m vrneural_682f982 run --no-video --quiet --force --save-frames none --out $R/$n ${EXTRA:-} "$@" 2>&1 | filt; }
new warm --frames ${F1:-300}
for i in 1 2; do
  bef bef_$i --frames ${F2:-600}
  new new_$i --frames ${F2:-600}
  new disp_$i --frames ${F2:-600} --target display
done
new newfirst --frames 2 --save-frames first; rm -f $R/newfirst/*.exr $R/newfirst/*eye1.png
t bench frame
timeout 60 python3 -m vrneural bench frame --lights 3 --out $R/bench-frame --no-progress ${BF:-} 2>&1 | tail -2
t done
tar -czf $OUT/r.tgz -C /tmp r
