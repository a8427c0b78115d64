import sys, time, os
sys.path.insert(0, os.environ.get("AB_OLD", "/tmp/ab41/old"))  # mkold.sh's folder
import numpy as np
import vrneural_e90c611.runtime.renderer as old
import vrneural_e90c611.gpu.device as olddev
import vrneural.runtime.renderer as new
from vrneural.gpu.device import get_device
from vrneural.runtime.lights import light_arrays
from vrneural.bench.timing import bench_scene
import vrneural_e90c611.bench.timing as oldtiming
PER = int(os.environ.get("PER", "1")); PH = PER // 2
tex = int(sys.argv[1]) if len(sys.argv) > 1 else 512
nl = int(sys.argv[2]) if len(sys.argv) > 2 else 1
scene_kind = sys.argv[3] if len(sys.argv) > 3 else "bench"
if scene_kind == "bench":
    sn, so = bench_scene(nl), oldtiming.bench_scene(nl)
else:
    from vrneural.runtime.scene import builtin_scene; from vrneural_e90c611.runtime.scene import builtin_scene as ob
    sn, so = builtin_scene(nl), ob(nl)
kw = dict(eyes=2, reuse=0, texture_res=tex, eye_res=(64, 64), n_lights=nl, fov_y=96.0)
ro = old.Renderer(so, old.Settings(**kw)); ro.frame(0)
rn = new.Renderer(sn, new.Settings(**kw, frames_in_flight=1)); rn.frame(0); rn.wait()
import vrneural.gpu.shaders as sh, vrneural.runtime.texture_pass as tp
orig = sh.load_wgsl("texture_space")
a = orig.index("var<workgroup> wg_list"); b = orig.index("// The floor of this pass")
simple = orig[:a] + """@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = thread_index(wid, nwg, lid);
    var c = vec4<u32>(0u);
    if (i < P.sched.y) {
        let k = cand[P.sched.x + i];
        if (block_front(k)) { c = shade_block(k); } else { c.y = 1u; }
    }
    count4(c, lid);
}
""" + orig[b:]
sh.load_wgsl.cache_clear(); _l = sh.load_wgsl
sh.load_wgsl = lambda n: simple if n.startswith("texture_space") else _l(n)
sh._env.cache_clear()
rs = new.Renderer(sn, new.Settings(**kw, frames_in_flight=1)); rs.frame(0); rs.wait()
def pass_ms(r, dev, entry="main", newapi=True):
    eyes = r.eyes_at(5); lp, lc = light_arrays(r.lights, 5 / 90)
    enc = dev.create_command_encoder(); cp = enc.begin_compute_pass()
    for k, n in enumerate(r.neural):
        for e, tgt in enumerate(n.targets):
            tiling = (n.desc.material.tiling,) * 2 + (0.0, 0.0)
            tgt.update(n.desc.model, eyes[e].position, tiling, lp, lc, PH, PER, k * 2 + e, 0.0)
            if newapi: tgt.dispatch(cp, PH, PER, entry)
            else: tgt.dispatch(cp, PH, PER)
    cp.end()
    if newapi: r.arena.flush()
    t0 = time.perf_counter(); dev.queue.submit([enc.finish()]); dev.queue.read_buffer(r.counters.buf, 0, 16)
    return (time.perf_counter() - t0) * 1e3
res = {"old": [], "new": [], "simple": [], "bare": []}
for rep in range(5):
    res["old"].append(pass_ms(ro, olddev.get_device(), newapi=False))
    res["new"].append(pass_ms(rn, get_device()))
    res["bare"].append(pass_ms(rn, get_device(), "bare"))
    res["simple"].append(pass_ms(rs, get_device()))
    print({k: round(v[-1], 1) for k, v in res.items()})
m = {k: float(np.median(v)) for k, v in res.items()}
print(sys.argv[1:], {k: round(v, 1) for k, v in m.items()}, "new/old %.2f simple/old %.2f new/bare %.2f old/bare %.2f" % (m["new"]/m["old"], m["simple"]/m["old"], m["new"]/m["bare"], m["old"]/m["bare"]), "load %.1f" % os.getloadavg()[0])
