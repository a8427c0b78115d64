"""`vrneural bench runtime`: the runtime performance targets, measured in one run on the
adapter at hand; writes results.json and results.md.

1. ``texture_vs_screen``: neural shading GPU ms per displayed frame on the built-in scene, both
   eyes: texture space (full update at ``texture_res``^2 per eye per object, divided by N + 1)
   vs the same student per pixel in screen space at ``eye_res`` (target >= 12x).
2. ``constants_vs_buffer``: the texture-space kernel with unrolled constant weights vs the same
   kernel reading weights from a storage buffer (target >= 10x).
3. ``vs_torch``: the texture-space kernel vs PyTorch CPU evaluating only the networks (coarse per
   block, fine per texel, f32) on the same blocks (target >= 3x).
4. ``mlp_only``: the student's two networks alone: constants vs storage-buffer kernel vs torch.
5. ``schedules``: frame-time distribution (p99 / median; target <= 1.2 for staggered), by wall
   clock and by process CPU time (on a CPU adapter the latter excludes the time other jobs take
   from the frame), beside a constant-work control of the same cost (a full update every frame
   of a texture with 1 / (N + 1) of the texels) that shows the machine's own noise; and the
   quality of burst vs staggered: mean |displayed - every-frame-updated| per frame.
GPU times are medians over repeats, from timestamps (one compute pass per measured step).
"""

from __future__ import annotations

import time

import numpy as np
from tqdm import tqdm

from vrneural.bench.configs import MEASUREMENTS, RuntimeConfig
from vrneural.bench.report import adapter_line, finish, header, prepare_out, table
from vrneural.bench.runtime_frames import make_renderer, median_ms, schedules, wall_ms
from vrneural.material import half_vector, random_material, sample_bilinear_wrap


def texture_vs_screen(texture_res=1200, eye_res=(2064, 2208), reuse=4, frames=3) -> dict:
    tex = make_renderer("texture", texture_res, eye_res)
    scr = make_renderer("screen", texture_res, eye_res)
    for r in (tex, scr):  # timestamps that miss the compute passes (lavapipe): the wall clock
        if r.untimed:
            r.pass_clock = "wall"
    t_ms, s_ms = [], []
    for f in range(frames + 1):  # frame 0 compiles; a, b: the last frame's statistics
        a = tex.frame(f)
        b = scr.frame(f)
        if f:
            t_ms.append(a.gpu_ms["texture"])
            s_ms.append(b.gpu_ms["screen"])
    upd = float(np.median(t_ms))
    per_frame_tex = upd / (reuse + 1)
    scr_ms = float(np.median(s_ms))
    return {
        "texture_res": texture_res,
        "eye_res": list(eye_res),
        "reuse": reuse,
        "texture_update_ms": upd,
        "texture_ms_per_displayed_frame": per_frame_tex,
        "screen_ms_per_frame": scr_ms,
        "ratio": scr_ms / per_frame_tex,
        "target": 12.0,
        "texture_blocks_shaded_per_update": a.blocks_shaded,
        "texture_mlp_evals_per_update": a.mlp_coarse + a.mlp_fine,
        "screen_pixels_shaded_per_frame": b.pixels_shaded,
        "screen_mlp_evals_per_frame": b.mlp_coarse + b.mlp_fine,
        "screen_coverage": b.pixels_shaded / (2 * eye_res[0] * eye_res[1]),
    }


def _plane_case(res: int, n_lights: int = 1):
    from vrneural.atlas import build_atlas
    from vrneural.runtime.assets import get_mesh

    atlas = build_atlas(get_mesh("plane"), res)
    mat = random_material(5)
    model = np.eye(4)
    eye = np.float32([0.1, 1.0, 0.3])
    lp = np.float32([[0.3, 0.8, -0.2], [-0.4, 0.6, 0.1], [0.0, 1.2, 0.5]])[:n_lights]
    return atlas, mat, model, eye, lp, np.ones((n_lights, 3), np.float32)


class _PassTimer:
    """One texture-space target on a case of :func:`_plane_case`; ``once()`` runs a full pass and
    returns its GPU ms (timestamps; wall ms where the adapter has none)."""

    def __init__(self, atlas, mat, model, eye, lp, lc, weights):
        from vrneural.gpu.timing import GpuTimer
        from vrneural.runtime.gpu_material import GpuAtlas
        from vrneural.runtime.texture_pass import CounterBuffer, TextureSpacePass, TextureTarget

        tp = TextureSpacePass(mat, "f32", len(lp), weights)
        self.cnt = CounterBuffer(1)
        self.tgt = TextureTarget(tp, GpuAtlas(atlas), self.cnt)
        self.tgt.update(model, eye, (1, 1, 0, 0), lp, lc)
        self.timer = GpuTimer(4)
        self.once()  # compile and warm up

    def once(self) -> float:
        from vrneural.gpu.device import get_device

        self.cnt.clear()
        enc = get_device().create_command_encoder()
        self.tgt.encode(enc, timestamp_writes=self.timer.writes("t"))
        self.timer.resolve(enc)
        t0 = time.perf_counter()
        get_device().queue.submit([enc.finish()])
        g = self.timer.read().get("t")
        return g if g else (time.perf_counter() - t0) * 1e3

    def counters(self) -> list:
        return self.cnt.read()[0].tolist()


def _gpu_pass_ms(atlas, mat, model, eye, lp, lc, weights, repeats) -> tuple[float, list]:
    pt = _PassTimer(atlas, mat, model, eye, lp, lc, weights)
    ms = [pt.once() for _ in range(repeats)]
    return float(np.median(ms)), pt.counters()


def constants_vs_buffer(res=512, repeats=3) -> dict:
    case = _plane_case(res)
    c_ms, cnt = _gpu_pass_ms(*case, "constants", repeats)
    b_ms, cnt_b = _gpu_pass_ms(*case, "storage", max(1, repeats - 1))
    assert cnt == cnt_b
    return {
        "texture_res": res,
        "constants_ms": c_ms,
        "buffer_ms": b_ms,
        "ratio": b_ms / c_ms,
        "counters": cnt,
        "target": 10.0,
    }


def vs_torch(res=512, repeats=7, n_lights=3) -> dict:
    """The whole texture-space pass (geometry, sampling, lights, stores) vs PyTorch CPU running
    only the networks on the same number of evaluations the pass's counters report (inputs
    precomputed and excluded from torch's time).

    Two PyTorch baselines: ``torch_networks_ms`` runs the model as trained (coarse on every
    (block, light), fine on every (texel, light)); ``torch_factored_ms`` does the same algebra as
    the kernel (first layers split, the light-independent part once per block / texel, W_z z_c
    once per (block, light)), so the kernel gets no credit for arithmetic torch could skip too.
    ``ratio`` is the median over repeats of (faster torch variant) / kernel, each repeat running
    the three back to back. Seven repeats by default: torch's time on a shared CPU varies far
    more between runs than the kernel's."""
    import torch

    case = _plane_case(res, n_lights)
    mat = case[1]
    pt = _PassTimer(*case, "constants")
    cnt = pt.counters()
    n = int(cnt[2])  # coarse evaluations (blocks x lit lights); fine: 4 n
    rng = np.random.default_rng(0)
    wi = rng.normal(size=(n, 3)).astype(np.float32)
    wi[:, 2] = np.abs(wi[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo = wi[::-1].copy()
    uv = rng.random((n, 4, 2)).astype(np.float32)
    dirs = np.concatenate([wi, wo, half_vector(wi, wo)], -1)
    xc = np.concatenate([dirs, sample_bilinear_wrap(mat.textures["coarse"], uv.mean(1))], -1)
    ff = sample_bilinear_wrap(mat.textures["fine"], uv.reshape(-1, 2))

    coarse, fine = torch_net(mat.networks["coarse"]), torch_net(mat.networks["fine"])
    txc, tff = torch.from_numpy(xc), torch.from_numpy(ff)

    def run_torch():
        with torch.no_grad():
            z = coarse(txc)
            y = fine(torch.cat([z.repeat_interleave(4, 0), tff], 1)).clamp_min(0)
        return y

    # factored: per block / texel once (n_lights blocks share one texel set here, as in the pass)
    nb = max(1, n // n_lights)
    wc0, wf0 = mat.networks["coarse"][0], mat.networks["fine"][0]
    zd = mat.networks["coarse"][-1].n_out  # the coarse net's output: the fine net's first inputs

    def t(a):  # numpy -> torch
        return torch.from_numpy(np.ascontiguousarray(a))

    # the first layers split: coarse by directions / features, fine by z_c / features
    w_cd, w_cf, b_c = t(wc0.weight[:, :9]), t(wc0.weight[:, 9:]), t(wc0.bias)
    w_fz, w_ff, b_f = t(wf0.weight[:, :zd]), t(wf0.weight[:, zd:]), t(wf0.bias)
    c_rest, f_rest = torch_net(mat.networks["coarse"][1:]), torch_net(mat.networks["fine"][1:])
    c_act, f_act = _torch_act(wc0.act), _torch_act(wf0.act)
    tdir = t(dirs)
    tfc = t(xc[:nb, 9:])
    tff_b = tff[: 4 * nb]

    def run_factored():
        with torch.no_grad():
            pa = torch.addmm(b_c, tfc, w_cf.T).repeat(n_lights, 1)[:n]  # per block
            pb = torch.addmm(b_f, tff_b, w_ff.T)  # per texel, [4 nb, H]
            z = c_rest(c_act(pa + tdir @ w_cd.T))  # per (block, light)
            zz = (z @ w_fz.T).repeat_interleave(4, 0)  # per (block, light), to texels
            h = f_act(zz + pb.repeat(n_lights, 1)[: 4 * n])
            y = f_rest(h).clamp_min(0)
        return y

    # interleaved repeats: the kernel and both torch baselines run back to back in each, so a
    # slow spell of the shared machine hits all three; the ratio is taken per repeat
    run_torch(), run_factored()  # warm-up
    g, t, f = [], [], []
    for _ in range(repeats):
        g.append(pt.once())
        t.append(wall_ms(run_torch))
        f.append(wall_ms(run_factored))
    g, t, f = (np.asarray(x) for x in (g, t, f))
    per = np.minimum(t, f) / g
    g_ms, t_ms, f_ms = (float(np.median(x)) for x in (g, t, f))
    return {
        "texture_res": res,
        "lights": n_lights,
        "coarse_evals": n,
        "fine_evals": int(cnt[3]),
        "gpu_pass_ms": g_ms,
        "torch_networks_ms": t_ms,
        "torch_factored_ms": f_ms,
        "torch_threads": torch.get_num_threads(),
        "ratio_vs_torch_as_trained": float(np.median(t / g)),
        "ratio_vs_torch_factored": float(np.median(f / g)),
        "ratio": float(np.median(per)),  # vs the faster torch variant, per repeat
        "ratio_range": [float(per.min()), float(per.max())],
        "repeats": repeats,
        "target": 3.0,
    }


def _torch_act(act: str):
    """The torch module of an activation (:data:`vrneural.mlp.ACTIVATIONS`)."""
    import torch

    return {"relu": torch.nn.ReLU(), "leaky_relu": torch.nn.LeakyReLU(0.01)}.get(
        act, torch.nn.Identity()
    )


def torch_net(layers):
    import torch

    mods = []
    for lay in layers:
        lin = torch.nn.Linear(lay.n_in, lay.n_out)
        lin.weight.data = torch.from_numpy(lay.weight)
        lin.bias.data = torch.from_numpy(lay.bias)
        mods += [lin, _torch_act(lay.act)]
    return torch.nn.Sequential(*mods).eval()


def mlp_only(n_blocks=65536, repeats=3) -> dict:
    """The student's two networks alone on the same inputs (coarse on ``n_blocks`` rows, fine on
    ``4 n_blocks``): generated constant-weight kernel vs storage-buffer kernel vs PyTorch CPU."""
    import torch

    from vrneural.gpu.mlp_kernel import MlpKernel
    from vrneural.gpu.timing import GpuTimer

    mat = random_material(5)
    rng = np.random.default_rng(0)
    xc = rng.standard_normal((n_blocks, mat.networks["coarse"][0].n_in)).astype(np.float32)
    xf = rng.standard_normal((4 * n_blocks, mat.networks["fine"][0].n_in)).astype(np.float32)
    out = {"blocks": n_blocks}
    for name, bw in (("constants", False), ("buffer", True)):
        kc = MlpKernel(mat.networks["coarse"], "f32", bw)
        kf = MlpKernel(mat.networks["fine"], "f32", bw)
        kc.run(xc[:256])
        kf.run(xf[:256])
        ms = []
        for _ in range(repeats):
            timer = GpuTimer(4)
            kc.run(xc, timer=timer)
            a = timer.read()["mlp"]
            kf.run(xf, timer=timer)
            ms.append(a + timer.read()["mlp"])
        out[f"{name}_ms"] = float(np.median(ms))
    tc, tf = torch_net(mat.networks["coarse"]), torch_net(mat.networks["fine"])
    txc, txf = torch.from_numpy(xc), torch.from_numpy(xf)

    def run_torch():
        with torch.no_grad():
            tc(txc)
            tf(txf)

    out["torch_ms"] = median_ms(run_torch, repeats)
    out["torch_threads"] = torch.get_num_threads()
    out["constants_vs_buffer"] = out["buffer_ms"] / out["constants_ms"]
    out["constants_vs_torch"] = out["torch_ms"] / out["constants_ms"]
    return out


RUN = {
    "texture_vs_screen": texture_vs_screen,
    "constants_vs_buffer": constants_vs_buffer,
    "vs_torch": vs_torch,
    "mlp_only": mlp_only,
    "schedules": schedules,
}

#: The headline figures the console report prints per measurement (paths into its result).
HEADLINES = {
    "texture_vs_screen": ("ratio",),
    "constants_vs_buffer": ("ratio",),
    "vs_torch": ("ratio", "ratio_range"),
    "mlp_only": ("constants_vs_buffer", "constants_vs_torch"),
    "schedules": ("burst.p99_over_median", "staggered.p99_over_median"),
}


def measure_all(quick: bool = False, only: list[str] | None = None, progress: bool = False):
    """Run ``only`` (default: every measurement) at full size or, ``quick``, small sizes:
    ``{name: result}`` and ``{name: seconds}``."""
    res, secs = {}, {}
    for name in tqdm(only or MEASUREMENTS, desc="bench runtime", disable=not progress):
        t0 = time.perf_counter()
        res[name] = RUN[name](**(MEASUREMENTS[name] if quick else {}))
        secs[name] = time.perf_counter() - t0
    return res, secs


def headline(result: dict, paths) -> str:
    """``path value, ...`` of the figures at ``paths`` (``a.b``: a nested key) in ``result``."""
    parts = []
    for path in paths:
        v = result
        for key in path.split("."):
            v = v.get(key) if isinstance(v, dict) else None
        if v is not None:
            parts.append(f"{path} {_fmt(v)}")
    return ", ".join(parts)


def run_runtime(cfg: RuntimeConfig, out: str) -> dict:
    """Check ``--only`` and the output folder, measure, write ``results.json`` (``quick``, one
    key per measurement with its result, and one record per measurement: headline figures,
    target, seconds) and ``results.md`` into ``out``; returns the document."""
    names = cfg.only
    with prepare_out(out, cfg.force, "runtime") as root:
        t0 = time.perf_counter()
        doc = header("runtime", cfg)
        doc["quick"] = cfg.quick
        res, secs = measure_all(cfg.quick, names, cfg.progress)
        rows = []
        for name in names:
            doc[name] = res[name]
            target = res[name].get("target", res[name].get("target_staggered_p99_over_median"))
            line = headline(res[name], HEADLINES[name])
            doc["records"].append(
                {"measurement": name, "headline": line, "target": target, "seconds": secs[name]}
            )
            rows.append([name, line, "-" if target is None else target, secs[name]])
        md = [
            "# vrneural bench runtime",
            "",
            adapter_line(doc),
            f"Mode: {'--quick (smoke sizes)' if cfg.quick else 'full'}. Targets: ratios >= "
            "target, schedules: staggered p99 / median <= target. Every figure: results.json.",
            "",
            *table(["measurement", "headline", "target", "s"], rows),
        ]
        return finish(root, doc, md, t0)


def _fmt(v) -> str:
    if isinstance(v, list):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return f"{v:.3g}" if isinstance(v, float) else str(v)
