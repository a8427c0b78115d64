#!/usr/bin/env bash
# #41 on a GPU: the quest3 main job at HEAD vs e90c611 (interleaved), frames in flight 1/2/3,
# a cProfile of HEAD's loop, and bench frame. Everything lands in $OUT/r.tgz + $OUT/log.txt.
set -u
T0=$(date +%s); t() { echo "== [$(( $(date +%s) - T0 )) s] $*"; }
R=/tmp/r; mkdir -p $R
exec > >(tee $OUT/log.txt) 2>&1
t setup
if [ -z "${LOCAL:-}" ]; then for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; fi
[ -n "${LOCAL:-}" ] || python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 3
export PYTHONPATH=${LOCAL:+$LOCAL:}/tmp/site:$PWD:$PWD/.abold XDG_RUNTIME_DIR=/tmp VRNEURAL_CACHE=/tmp/vc PYTHONUNBUFFERED=1
j=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f $j ] && export VK_DRIVER_FILES=$j __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.mem --format=csv
nproc; python3 -c "import wgpu, numpy; print(wgpu.__version__, numpy.__version__)"
timeout 60 python3 -m vrneural info 2>&1 | head -20
(while sleep 1; do nvidia-smi --query-gpu=timestamp,clocks.sm,utilization.gpu,power.draw --format=csv,noheader 2>/dev/null; done > $R/smi.csv) &
SMI=$!
keep() { rm -f $R/$1/*.exr; case $1 in new_1|old_1) rm -f $R/$1/frame0*_eye1.png;; *) rm -f $R/$1/*.png;; esac; }
new() { n=$1; shift; t "new $n $*"; timeout 150 python3 -m vrneural run --eyes 2 --reuse 4 --no-video --quiet --force --out $R/$n ${EXTRA:-} "$@" 2>&1 | grep -v "^ *frames  \|^wrote\|summary "; keep $n; }
old() { n=$1; shift; t "old $n $*"; timeout 150 python3 -m vrneural_e90c611 run --eyes 2 --reuse 4 --no-video --quiet --force --out $R/$n ${EXTRA:-} "$@" 2>&1 | grep -v "^ *frames  \|^wrote\|summary "; keep $n; }
new new_warm --frames ${F1:-300}
old old_warm --frames ${F1:-300}
for i in 1 2 3; do new new_$i --frames ${F2:-600}; old old_$i --frames ${F2:-600}; done
new new_fif1 --frames ${F2:-600} --frames-in-flight 1
new new_fif3 --frames ${F2:-600} --frames-in-flight 3
new new_screen --frames ${F1:-300} --mode screen
old old_screen --frames ${F1:-300} --mode screen
t cprofile
timeout 150 python3 -m cProfile -o $R/new_prof.out -m vrneural run --eyes 2 --reuse 4 --no-video --quiet --force --out $R/new_prof ${EXTRA:-} --frames ${F2:-600} 2>&1 | tail -4
python3 -c "import pstats; p=pstats.Stats('$R/new_prof.out'); p.sort_stats('tottime').print_stats(35); p.sort_stats('cumulative').print_stats(45)" > $R/new_prof.txt 2>&1
keep new_prof
t bench frame
timeout 200 python3 -m vrneural bench frame --lights 3 --out $R/bench-frame --no-progress ${BF:-} 2>&1 | tail -40
t done
kill $SMI
tar -czf $OUT/r.tgz -C /tmp r
ls -la $OUT
