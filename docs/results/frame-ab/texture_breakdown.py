"""Where a full texture-space update's time goes (issue #41), on the bench frame's scene and
renderer: the pass's kernels with parts taken out by rewriting the generated WGSL, timed
interleaved with the bare kernel, by the CPU time of all of the process's threads from submit to
completion (on lavapipe the passes' work; the wall clock is stretched by other processes).

    python docs/results/frame-ab/texture_breakdown.py [texture side] [rounds] [variants]

Variants (joined with +): full (as shipped); nocount (the counters' sums and atomics left out);
nonet (the MLPs replaced by a few adds of their inputs); noload (the neural-texture loads
replaced by values computed from the taps); nosample (the whole lookups replaced);
buf (the neural textures as storage buffers, array<vec4<u32>>, instead of rgba32uint
textures); share (one set of 4 loads for a block whose 4 texels share their bilinear taps);
nounpack (the float16 unpacking replaced by a bitcast); direct (every update as one dispatch,
no compaction).
The images of the rewritten kernels are wrong by design: timing only.
"""
import os, sys, re, numpy as np
from vrneural.bench import timing
from vrneural.bench.frame import _renderer, texture_update
import time
class NT:
    @staticmethod
    def writes(name): return None
def time_passes(r, encode, repeats):
    cpus, walls = [], []
    for i in range(repeats + 1):
        enc = r.dev.create_command_encoder()
        encode(enc, NT)
        r.arena.flush()
        t0 = time.process_time(); w0 = time.perf_counter()
        r.dev.queue.submit([enc.finish()])
        r.dev.queue.read_buffer(r.counters.buf, 0, 16)
        if i: cpus.append((time.process_time() - t0) * 1e3); walls.append((time.perf_counter() - w0) * 1e3)
    return {"cpu_ms": float(np.median(cpus)), "wall_ms": float(np.median(walls))}
from vrneural.gpu.pipelines import compute_pipeline

res = int(sys.argv[1]) if len(sys.argv) > 1 else 512
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 5
class C: reuse=4; texture_res=res; lights=1
scene = timing.bench_scene(1)
r = _renderer(scene, C, (1032, 1104), "hdr", neural_filter="exact")  # its rewrites target the exact filter
print("non-empty blocks", [n.gatlas.non_empty_blocks for n in r.neural])

def replace_fn(code, name, body):
    m = re.search(r"\nfn " + name + r"\(([^\n]*)\{\n.*?\n}\n", code, re.S)
    assert m, name
    return code[:m.start()] + "\nfn " + name + "(" + m.group(1) + "{\n" + body + "\n}\n" + code[m.end():]

SHARE_FN = '\nfn sample_b4(uv0: vec2<f32>, uv1: vec2<f32>, uv2: vec2<f32>, uv3: vec2<f32>) -> array<array<f32, 8>, 4> {\n    let dims = vec2<i32>(textureDimensions(tex_b));\n    let p0 = bilinear_taps(uv0, dims);\n    let p1 = bilinear_taps(uv1, dims);\n    let p2 = bilinear_taps(uv2, dims);\n    let p3 = bilinear_taps(uv3, dims);\n    var out: array<array<f32, 8>, 4>;\n    if (all(p0.i0 == p1.i0) && all(p0.i0 == p2.i0) && all(p0.i0 == p3.i0)) {\n        let t00 = textureLoad(tex_b, vec2<i32>(p0.i0.x, p0.i0.y), 0, 0);\n        let t10 = textureLoad(tex_b, vec2<i32>(p0.i1.x, p0.i0.y), 0, 0);\n        let t01 = textureLoad(tex_b, vec2<i32>(p0.i0.x, p0.i1.y), 0, 0);\n        let t11 = textureLoad(tex_b, vec2<i32>(p0.i1.x, p0.i1.y), 0, 0);\n        { let fx = p0.f.x; let fy = p0.f.y;\n        {\n            let top = unpack2x16float(t00[0]) * (1.0 - fx) + unpack2x16float(t10[0]) * fx;\n            let bot = unpack2x16float(t01[0]) * (1.0 - fx) + unpack2x16float(t11[0]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[0][0] = v.x;\n            out[0][1] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[1]) * (1.0 - fx) + unpack2x16float(t10[1]) * fx;\n            let bot = unpack2x16float(t01[1]) * (1.0 - fx) + unpack2x16float(t11[1]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[0][2] = v.x;\n            out[0][3] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[2]) * (1.0 - fx) + unpack2x16float(t10[2]) * fx;\n            let bot = unpack2x16float(t01[2]) * (1.0 - fx) + unpack2x16float(t11[2]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[0][4] = v.x;\n            out[0][5] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[3]) * (1.0 - fx) + unpack2x16float(t10[3]) * fx;\n            let bot = unpack2x16float(t01[3]) * (1.0 - fx) + unpack2x16float(t11[3]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[0][6] = v.x;\n            out[0][7] = v.y;\n        }\n        }\n        { let fx = p1.f.x; let fy = p1.f.y;\n        {\n            let top = unpack2x16float(t00[0]) * (1.0 - fx) + unpack2x16float(t10[0]) * fx;\n            let bot = unpack2x16float(t01[0]) * (1.0 - fx) + unpack2x16float(t11[0]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[1][0] = v.x;\n            out[1][1] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[1]) * (1.0 - fx) + unpack2x16float(t10[1]) * fx;\n            let bot = unpack2x16float(t01[1]) * (1.0 - fx) + unpack2x16float(t11[1]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[1][2] = v.x;\n            out[1][3] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[2]) * (1.0 - fx) + unpack2x16float(t10[2]) * fx;\n            let bot = unpack2x16float(t01[2]) * (1.0 - fx) + unpack2x16float(t11[2]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[1][4] = v.x;\n            out[1][5] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[3]) * (1.0 - fx) + unpack2x16float(t10[3]) * fx;\n            let bot = unpack2x16float(t01[3]) * (1.0 - fx) + unpack2x16float(t11[3]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[1][6] = v.x;\n            out[1][7] = v.y;\n        }\n        }\n        { let fx = p2.f.x; let fy = p2.f.y;\n        {\n            let top = unpack2x16float(t00[0]) * (1.0 - fx) + unpack2x16float(t10[0]) * fx;\n            let bot = unpack2x16float(t01[0]) * (1.0 - fx) + unpack2x16float(t11[0]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[2][0] = v.x;\n            out[2][1] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[1]) * (1.0 - fx) + unpack2x16float(t10[1]) * fx;\n            let bot = unpack2x16float(t01[1]) * (1.0 - fx) + unpack2x16float(t11[1]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[2][2] = v.x;\n            out[2][3] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[2]) * (1.0 - fx) + unpack2x16float(t10[2]) * fx;\n            let bot = unpack2x16float(t01[2]) * (1.0 - fx) + unpack2x16float(t11[2]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[2][4] = v.x;\n            out[2][5] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[3]) * (1.0 - fx) + unpack2x16float(t10[3]) * fx;\n            let bot = unpack2x16float(t01[3]) * (1.0 - fx) + unpack2x16float(t11[3]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[2][6] = v.x;\n            out[2][7] = v.y;\n        }\n        }\n        { let fx = p3.f.x; let fy = p3.f.y;\n        {\n            let top = unpack2x16float(t00[0]) * (1.0 - fx) + unpack2x16float(t10[0]) * fx;\n            let bot = unpack2x16float(t01[0]) * (1.0 - fx) + unpack2x16float(t11[0]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[3][0] = v.x;\n            out[3][1] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[1]) * (1.0 - fx) + unpack2x16float(t10[1]) * fx;\n            let bot = unpack2x16float(t01[1]) * (1.0 - fx) + unpack2x16float(t11[1]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[3][2] = v.x;\n            out[3][3] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[2]) * (1.0 - fx) + unpack2x16float(t10[2]) * fx;\n            let bot = unpack2x16float(t01[2]) * (1.0 - fx) + unpack2x16float(t11[2]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[3][4] = v.x;\n            out[3][5] = v.y;\n        }\n        {\n            let top = unpack2x16float(t00[3]) * (1.0 - fx) + unpack2x16float(t10[3]) * fx;\n            let bot = unpack2x16float(t01[3]) * (1.0 - fx) + unpack2x16float(t11[3]) * fx;\n            let v = top * (1.0 - fy) + bot * fy;\n            out[3][6] = v.x;\n            out[3][7] = v.y;\n        }\n        }\n    } else {\n        out[0] = sample_b(uv0);\n        out[1] = sample_b(uv1);\n        out[2] = sample_b(uv2);\n        out[3] = sample_b(uv3);\n    }\n    return out;\n}\n'
Z8 = "array<f32, 8>(" + ", ".join("f[%d]" % i for i in range(8)) + ")"
def variant(code, name):
    parts = name.split("+")
    for p in parts:
        if p == "full": pass
        elif p == "nocount":
            code = replace_fn(code, "count4", "    if (c.x == 123456789u) { atomicAdd(&counters[0], 1u); }")
        elif p == "nonet":   # keep sampling + frames, drop MLP arithmetic
            code = replace_fn(code, "pre_a", "    return f;")
            code = replace_fn(code, "pre_b", "    return f;")
            code = replace_fn(code, "fine_z", "    return z;")
            code = replace_fn(code, "eval_coarse", "    var o = pa; o[0] += d[0] + d[4]; return o;")
            code = replace_fn(code, "fine_net", "    return vec3<f32>(zz[0] + pb[0] + pb[3] + pb[6], zz[1] + pb[1]+ pb[4] + pb[7], zz[2] + pb[2] + pb[5]);")
        elif p == "nosample":
            for s in ("sample_a", "sample_b"):
                code = replace_fn(code, s, "    let dd = vec2<f32>(textureDimensions(tex_" + s[-1] + ")).x * 1e-9; return array<f32, 8>(uv.x + dd, uv.y, uv.x * uv.y, uv.x + uv.y, uv.x - uv.y, uv.y * 2.0, uv.x * 3.0, 1.0);")
        elif p == "nounpack":
            code = code.replace("unpack2x16float(", "bitcast<vec2<f32>>(vec2<u32>(0x3f800000u) ^ vec2<u32>(").replace(") * (1.0 - fx)", ")) * (1.0 - fx)").replace(") * fx;", ")) * fx;")
        elif p == "noload":
            code = re.sub(r"textureLoad\((tex_[ab]), vec2<i32>\((xi.), (yi.)\), 0, 0\)", r"(vec4<u32>(u32(\2), u32(\3), 7u, 9u) + vec4<u32>(textureDimensions(\1).x))", code)
        elif p == "direct":
            pass  # install() sets texture_pass.COMPACT_MIN
        elif p == "buf":
            code = code.replace("var tex_a: texture_2d_array<u32>;", "var<storage, read> tex_a: array<vec4<u32>>;")
            code = code.replace("var tex_b: texture_2d_array<u32>;", "var<storage, read> tex_b: array<vec4<u32>>;")
            code = code.replace("vec2<i32>(textureDimensions(tex_a))", "vec2<i32>(%d, %d)" % DIMS["a"])
            code = code.replace("vec2<i32>(textureDimensions(tex_b))", "vec2<i32>(%d, %d)" % DIMS["b"])
            code = re.sub(r"textureLoad\((tex_[ab]), vec2<i32>\((xi.), (yi.)\), 0, 0\)", lambda m: "%s[%s * %d + %s]" % (m.group(1), m.group(3), DIMS[m.group(1)[-1]][0], m.group(2)), code)
        elif p == "share":
            i = code.index("// Output transform")
            code = code[:i] + SHARE_FN + code[i:]
            old = "".join("    let pb%d = pre_b(sample_b(uv%d));\n" % (k, k) for k in range(4))
            assert old in code
            code = code.replace(old, "    let fb = sample_b4(uv0, uv1, uv2, uv3);\n" + "".join("    let pb%d = pre_b(fb[%d]);\n" % (k, k) for k in range(4)))
        else: raise SystemExit(f"unknown variant {p!r}; see the docstring")
    return code

names = sys.argv[3].split(",") if len(sys.argv) > 3 else ["full", "nocount", "nonet", "nosample", "nonet+nosample+nocount"]
codes = {n.tpass: n.tpass.code for n in r.neural}
import wgpu
from vrneural.gpu.readback import upload_buffer
from vrneural.runtime.gpu_material import _words
orig_res = {}
import vrneural.runtime.texture_pass as tpass
COMPACT_MIN = tpass.COMPACT_MIN
def install(name):
    tpass.COMPACT_MIN = 10**9 if "direct" in name.split("+") else COMPACT_MIN
    for n in r.neural:
        gm = n.tpass.gmat
        if gm not in orig_res:
            orig_res[gm] = gm.resources
            m = n.tpass.mat
            bufs = {"tex_a": {"buffer": upload_buffer(_words(m.textures["coarse"]).ravel(), wgpu.BufferUsage.STORAGE)},
                    "tex_b": {"buffer": upload_buffer(_words(m.textures["fine"]).ravel(), wgpu.BufferUsage.STORAGE)}}
            gm._bufs = bufs
        global DIMS
        DIMS = {"a": n.tpass.mat.textures["coarse"].shape[1::-1], "b": n.tpass.mat.textures["fine"].shape[1::-1]}
        if "buf" in name:
            gm.resources = (lambda gm=gm: {**orig_res[gm](), **gm._bufs})
        else:
            gm.resources = orig_res[gm]
        c = variant(codes[n.tpass], name)
        for t in n.targets:
            for e in ("main", "cull", "args", "main_compacted"):
                t.pipes[e] = compute_pipeline(c, e, label=name + e)
            t.binds = {}

f = 20
out = {k: [] for k in names + ["bare_loads", "bare"]}
for rnd in range(rounds):
    for name in names:
        install(name)
        out[name].append(time_passes(r, texture_update(r, "main", 0, 1, f), 3))
    for floor in ("bare_loads", "bare"):
        out[floor].append(time_passes(r, texture_update(r, floor, 0, 1, f), 3))
bare = np.median([x["cpu_ms"] for x in out["bare"]])
for k, v in out.items():
    ts = [x["cpu_ms"] for x in v]; w = [x["wall_ms"] for x in v]
    print(f"{k:26s} cpu {np.median(ts):7.2f} ms  wall {np.median(w):7.2f} ms  cpu / bare {np.median(ts)/bare:.2f}")
print("load", os.getloadavg())
