#!/usr/bin/env bash
# #41 on a GPU, fifth run: the depth cleared by one frame in four (depth_clear "slices") against
# every frame ("pass"), interleaved; the raster floor with it; frames compared; bench frame.
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
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
filt() { grep -v "^ *frames  \|^wrote\|summary \|^adapter\|^objects\|^run  "; }
run() { n=$1; shift; t "$n $*"; timeout 100 python3 -m vrneural run --no-video --quiet --force --save-frames none --out $R/$n "$@" 2>&1 | filt; }
run warm --frames ${F1:-300}
t raster floor
timeout 60 python3 docs/results/h200/raster_floor.py ${RF:-4128x2208} $R/raster_floor.json 2>&1
for i in 1 2 3; do
  run pass_$i --frames ${F2:-600} --depth-clear pass
  run slices_$i --frames ${F2:-600} --depth-clear slices
done
run auto --frames ${F2:-600}
run slices_fif3 --frames ${F2:-600} --depth-clear slices --frames-in-flight 3
run slices_disp --frames ${F2:-600} --depth-clear slices --target display
python3 -c "import json; print('auto resolved:', json.load(open('$R/auto/summary.json'))['resolved']['depth_clear'])"
python3 docs/results/h200/steady_state.py $R/main-job-slices.json pass=$R/pass_1 pass=$R/pass_2 pass=$R/pass_3 slices=$R/slices_1 slices=$R/slices_2 slices=$R/slices_3 auto=$R/auto slices_fif3=$R/slices_fif3 slices_display=$R/slices_disp
t frames compared
run fr_pass --frames 9 --depth-clear pass --save-frames all
run fr_slices --frames 9 --depth-clear slices --save-frames all
python3 docs/results/h200/compare_frames.py $R/fr_pass $R/fr_slices $R/compare.json
md5sum $R/fr_pass/frame0000_eye0.png $R/fr_slices/frame0000_eye0.png $R/fr_pass/frame0008_eye1.png $R/fr_slices/frame0008_eye1.png
rm -rf $R/fr_*/*.exr $R/fr_*/*.png
t bench frame
[ -n "${NOBF:-}" ] || timeout 90 python3 -m vrneural bench frame --lights 3 --out $R/bench-frame --no-progress 2>&1 | tail -3
t done
cp $R/main-job-slices.json $R/raster_floor.json $R/compare.json $OUT/ 2>/dev/null
tar -czf $OUT/r.tgz -C /tmp r
