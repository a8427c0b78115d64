"""Main-thread CPU per frame, the frame loop at an earlier commit against this one, in one
process: ``bash docs/results/frame-ab/mkold.sh /tmp/ab41/COMMIT COMMIT && python
docs/results/frame-ab/ab_commit.py COMMIT [ROUNDS]`` (tiny profile: 96x96 eyes, 128^2, 2 lights,
2 frames in flight; ROUNDS interleaved rounds of 30 frames, default 6)."""
import importlib, os, sys, time
import numpy as np
commit = sys.argv[1]
sys.path.insert(0, f"/tmp/ab41/{commit}")  # mkold.sh's folder
old = importlib.import_module(f"vrneural_{commit}.runtime.renderer")
old_scene = importlib.import_module(f"vrneural_{commit}.runtime.scene").builtin_scene
import vrneural.runtime.renderer as new
from vrneural.runtime.scene import builtin_scene
kw = dict(eyes=2, reuse=4, texture_res=128, eye_res=(96, 96), n_lights=2, fov_y=90.0, frames_in_flight=2)
rs = {commit: old.Renderer(old_scene(2), old.Settings(**kw)), "new": new.Renderer(builtin_scene(2), new.Settings(**kw))}
for r in rs.values(): r.frame(0); r.wait()
n, res = 30, {}
for rep in range(int(sys.argv[2]) if len(sys.argv) > 2 else 6):
    for name, r in rs.items():
        c0, f0 = time.thread_time(), 1 + rep * n
        sts = [r.frame(f) for f in range(f0, f0 + n)]
        r.wait()
        for st in sts: st.blocks_shaded, st.gpu_ms
        res.setdefault(name, []).append((time.thread_time() - c0) / n * 1e3)
for k, v in res.items(): print(k, "main-thread CPU ms/frame, median %.3f" % np.median(v), np.round(v, 2))
print(f"{commit}/new %.3f" % (np.median(res[commit]) / np.median(res["new"])), "load", os.getloadavg())
