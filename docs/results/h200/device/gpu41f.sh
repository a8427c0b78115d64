#!/usr/bin/env bash
# #41/#39 on a GPU, sixth run: the release's main job (the depth sliced, varyings at the
# centroid) against 4x MSAA, interleaved; frame 0 against the fifth run's; bench frame.
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
run() { n=$1; shift; t "$n $*"; timeout 100 python3 -m vrneural run --no-video --quiet --force --save-frames none --out $R/$n "$@" 2>&1 | filt; }
run warm --frames ${F1:-300}
for i in 1 2 3; do
  run now_$i --frames ${F2:-600}
  run msaa_$i --frames ${F2:-600} --msaa 4
done
run pass --frames ${F2:-600} --depth-clear pass
python3 docs/results/h200/steady_state.py $R/main-job-msaa.json now=$R/now_1 now=$R/now_2 now=$R/now_3 msaa4=$R/msaa_1 msaa4=$R/msaa_2 msaa4=$R/msaa_3 depth_pass=$R/pass
t frames
run fr --frames 2 --save-frames first
run fr_msaa --frames 2 --save-frames first --msaa 4
md5sum $R/fr/frame0000_eye0.png $R/fr_msaa/frame0000_eye0.png
python3 docs/results/h200/compare_frames.py $R/fr $R/fr_msaa $R/compare-msaa.json
cp $R/fr_msaa/frame0000_eye0.png $OUT/msaa_frame0000_eye0.png
cp $R/fr/frame0000_eye0.png $OUT/frame0000_eye0.png
rm -rf $R/fr*/*.exr $R/fr*/*.png
t bench frame
[ -n "${NOBF:-}" ] || timeout 90 python3 -m vrneural bench frame --lights 3 --out $R/bench-frame --no-progress 2>&1 | tail -2
t done
cp $R/main-job-msaa.json $R/compare-msaa.json $OUT/ 2>/dev/null
tar -czf $OUT/r.tgz -C /tmp r
