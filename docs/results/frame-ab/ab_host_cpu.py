"""Host CPU per frame, the frame loop at e90c611 against this one (issue #41), in one process:
``bash docs/results/frame-ab/mkold.sh && python docs/results/frame-ab/ab_host_cpu.py [EYES]
[TEXTURE SIDE]`` (default 96x96, 128; the frozen copy from mkold.sh's folder, or $AB_OLD).
Three interleaved rounds of 30 frames each; per frame: the main thread's CPU time, and the host
CPU time with wgpu-py's device-poll thread added (it polls the device and runs the map
callbacks for the frames' read-backs: host work the frame causes, on another thread), and the
wall time (on a CPU adapter the GPU's work shares the cores, so it does not fall with it)."""
import sys, time, os
sys.path.insert(0, os.environ.get("AB_OLD", "/tmp/ab41/old"))  # mkold.sh's folder
import numpy as np
import vrneural_e90c611.runtime.renderer as old
import vrneural.runtime.renderer as new
from vrneural.gpu.device import poll_thread_cpu as poll_cpu  # wgpu-py's device-poll thread
from vrneural.runtime.scene import builtin_scene
from vrneural_e90c611.runtime.scene import builtin_scene as old_scene
eye = tuple(int(x) for x in (sys.argv[1] if len(sys.argv) > 1 else "96x96").split("x"))
tex = int(sys.argv[2]) if len(sys.argv) > 2 else 128
kw = dict(eyes=2, reuse=4, texture_res=tex, eye_res=eye, n_lights=2, fov_y=90.0)
ro = old.Renderer(old_scene(2), old.Settings(**kw)); ro.frame(0)
rn = {d: new.Renderer(builtin_scene(2), new.Settings(**kw, frames_in_flight=d)) for d in (1, 2, 3)}
for r in rn.values(): r.frame(0); r.wait()
n = 30
res = {}
for rep in range(3):
    for name, r in [("old", ro), *[(f"new{d}", r) for d, r in rn.items()]]:
        c0, t0, p0 = time.thread_time(), time.perf_counter(), poll_cpu()
        f0 = 1 + rep * n
        sts = [r.frame(f) for f in range(f0, f0 + n)]
        if name != "old": r.wait()
        for st in sts: st.blocks_shaded, st.gpu_ms  # decoded inside the timed loop, as old does
        w = (time.perf_counter() - t0) / n * 1e3; c = (time.thread_time() - c0) / n * 1e3
        pc = (poll_cpu() - p0) / n * 1e3
        res.setdefault(name, []).append((w, c, c + pc))
        print(f"{name}: wall {w:.2f} ms/frame, cpu: main thread {c:.2f}, with the poll thread {c + pc:.2f} ms/frame")
for k, v in res.items():
    v = np.array(v); print(k, "median wall %.2f cpu: main %.2f, with poll %.2f" % tuple(np.median(v, 0)))
med = {k: np.median(np.array(v), 0) for k, v in res.items()}
print("cpu ratio old/new2: main thread %.2f, with the poll thread %.2f" % (med["old"][1] / med["new2"][1], med["old"][2] / med["new2"][2]))
print("load", os.getloadavg())
