"""The frame loop of #41: frames in flight, one submit, the fused texture-space dispatch, the
uniform arena, the display target, and the images: bit for bit those of the loop before it
(plain objects' pixels within one float16 ulp)."""

import numpy as np
import pytest
from frame_refs import COUNTERS, DATA, configs, render

from vrneural.runtime.scene import builtin_scene


@pytest.fixture(scope="module")
def refs():
    return np.load(DATA)


@pytest.mark.gpu
@pytest.mark.parametrize("name", list(configs()))
def test_frames_are_bit_for_bit_those_of_the_loop_before_41(refs, name):
    """Every configuration (texture, f16, shared radiance with adaptive reuse, crop + jitter,
    screen, reference, a plain floor under one light, no lights): the same counters, and the
    same bits in every frame's eyes but where the plain objects' shading changed its arithmetic
    (reciprocals for divisions, forward.wgsl: plain_colour): there at most one float16 unit in
    the last place, in a few values (1-3 pixels per configuration when it changed).

    In mode texture the eyes are drawn side by side into one target since (one pass): the
    second eye's columns lie further right, and the rasteriser's interpolation of its varyings
    rounds differently there (lavapipe: 40-100 values of 30-60 thousand, at most 0.22% of the
    value). That eye is held to 0.3% in at most 0.5% of its values; the first, and every eye
    of the screen modes (a target each), to the bits above."""
    eyes, cnt = render(name, wait=lambda r: r.wait())
    np.testing.assert_array_equal(cnt, refs[f"{name}/counters"], err_msg=str(COUNTERS))
    ref = refs[f"{name}/eyes"]
    if configs()[name][1].get("mode", "texture") == "texture" and eyes.shape[1] > 1:
        _assert_old_frames(eyes[:, :1], ref[:, :1])
        _assert_interpolation_roundoff(eyes[:, 1:], ref[:, 1:])
    else:
        _assert_old_frames(eyes, ref)


def _assert_old_frames(eyes, ref):
    ulps = np.abs(eyes.view(np.uint16).astype(np.int32) - ref.view(np.uint16))
    assert ulps.max() <= 1 and np.count_nonzero(ulps) <= 1e-3 * ulps.size


def _assert_interpolation_roundoff(eyes, ref):
    e, r = eyes.astype(np.float32), ref.astype(np.float32)
    rel = np.abs(e - r) / (np.abs(r) + 1e-3)
    assert rel.max() <= 3e-3 and np.count_nonzero(rel) <= 5e-3 * rel.size


@pytest.mark.gpu
@pytest.mark.parametrize("compact_min", [0, 1 << 30], ids=["compacted", "one-dispatch"])
def test_both_texture_update_paths_give_the_same_frames(refs, monkeypatch, compact_min):
    """cull + args + main_compacted (long spans) and the single fused dispatch (short ones)
    shade the same blocks: identical bits and counters, forced either way."""
    from vrneural.runtime import texture_pass

    monkeypatch.setattr(texture_pass, "COMPACT_MIN", compact_min)
    eyes, cnt = render("texture", wait=lambda r: r.wait())
    np.testing.assert_array_equal(cnt, refs["texture/counters"])
    _assert_old_frames(eyes, refs["texture/eyes"])


def _renderer(**kw):
    from vrneural.runtime.renderer import Renderer, Settings

    s = Settings(**{"eyes": 2, "reuse": 2, "texture_res": 128, "eye_res": (48, 40),
                    "n_lights": 2, **kw})  # fmt: skip
    return Renderer(builtin_scene(2), s)


def _counts(st) -> tuple:
    return (st.blocks_shaded, st.blocks_backfacing, st.mlp_coarse, st.mlp_fine)


@pytest.mark.gpu
def test_stats_arrive_later_and_equal_those_of_a_waiting_loop():
    """With 3 frames in flight frame() returns before the GPU is done; the statistics come
    back in order, never more than 2 frames queued behind the one submitted, and equal frame
    for frame those of a renderer that waits for every frame (1 in flight)."""
    a, b = _renderer(frames_in_flight=3), _renderer(frames_in_flight=1)
    sa, sb = [], []
    for f in range(8):
        sa.append(a.frame(f))
        assert sa[-1].in_flight <= 2
        late = a.latest_stats()
        assert late is None or (late.ready and late.frame < f + 1)
        sb.append(b.frame(f))
        _counts(sb[-1])  # read at once: waits for that frame
    a.wait()
    assert all(st.ready for st in sa)
    assert [_counts(x) for x in sa] == [_counts(x) for x in sb]
    assert any(st.blocks_shaded for st in sa)
    for st in sa:
        assert st.wall_ms > 0 and st.host_ms > 0 and st.cpu_ms >= 0
        assert set(st.gpu_ms).isdisjoint(st.untimed)
    assert a.latest_stats() is sa[-1]
    # reading a field of a frame in flight waits for it, and gives its value
    st = a.frame(8)
    twin = b.frame(8)
    assert _counts(st) == _counts(twin) and st.ready
    np.testing.assert_array_equal(a.read_eyes()[0], b.read_eyes()[0])


@pytest.mark.gpu
def test_wall_clock_passes_render_the_same_frames():
    """``pass_clock = "wall"`` (a submit per pass, each timed by the wall clock) changes the
    timing, not the frame: same bits and counters; every pass run has a time."""
    a, b = _renderer(), _renderer()
    b.pass_clock = "wall"
    for f in range(3):
        sa, sb = a.frame(f), b.frame(f)
        assert _counts(sa) == _counts(sb)
        assert sb.clock == "wall" and not sb.untimed
        assert set(sb.gpu_ms) == ({"texture", "forward"} if sb.updated_objects else {"forward"})
    np.testing.assert_array_equal(a.read_eyes()[1], b.read_eyes()[1])


@pytest.mark.gpu
@pytest.mark.parametrize("clear", ["pass", "compute"])
def test_display_target_is_the_tonemap_of_the_hdr_frame_within_one_level(clear):
    """The 8-bit display target (Reinhard in the fragment shader; sRGB by an rgba8unorm-srgb
    target where the render pass clears it, by the shader into rgba8unorm where a compute pass
    does) against output.tonemap of the HDR frame: at most 1 level apart (the HDR path rounds
    to f16 first; the sRGB encoders round differently), nearly always equal."""
    from vrneural.errors import VrnError

    hdr, disp = _renderer(), _renderer(target="display", colour_clear=clear)
    want_fmt = {"pass": "rgba8unorm-srgb", "compute": "rgba8unorm"}[clear]
    assert disp.eye_t[0].colour.format == want_fmt
    for f in range(2):
        hdr.frame(f)
        disp.frame(f)
    want, got = hdr.read_display(), disp.read_display()
    for w, g in zip(want, got, strict=True):
        d = np.abs(w.astype(int) - g.astype(int))
        assert d.max() <= 1 and (d == 0).mean() > 0.9
        assert g.shape == w.shape and g.dtype == np.uint8 and g.max() > 50
    with pytest.raises(VrnError, match="read_display gives the display colours"):
        disp.read_eyes()
    with pytest.raises(VrnError, match="needs mode 'texture'"):
        _renderer(target="display", mode="screen")


@pytest.mark.gpu
@pytest.mark.parametrize("name", ["texture", "screen", "bench_1light"])
def test_a_compute_cleared_colour_gives_the_same_frames_as_the_passes_clear(name):
    """Settings.colour_clear: the compute clear (GPUs' default) and the render pass's own
    clear (CPU adapters') give the same bits and counters, frame after frame (a colour not
    cleared would keep the last frame's pixels where nothing is drawn now)."""
    got = {c: render(name, colour_clear=c) for c in ("compute", "pass")}
    for a, b in zip(got["compute"], got["pass"], strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.gpu
@pytest.mark.parametrize("target", ["hdr", "display"])
def test_the_colour_clear_kernel_blackens_every_texel_of_both_eyes(target):
    """forward.clear_colour (a compute pass; the render pass then loads the colour): every
    texel of the eyes' shared target 0 after it, whatever was there (its twin: np.zeros)."""
    from vrneural.gpu.readback import read_texture
    from vrneural.runtime import forward as fw

    et = fw.EyeTargets.side_by_side(2, 24, 16, 1, target=target)[1]  # the second eye's
    tex = et.colour
    assert tex.format == et.format == fw.colour_format(target, True) and tex.size[:2] == (48, 16)
    from vrneural.gpu.device import get_device

    d = get_device()
    enc = d.create_command_encoder()  # something else first: a render pass's clear to grey
    rp = enc.begin_render_pass(color_attachments=[{
        "view": et.colour_view, "load_op": "clear", "store_op": "store",
        "clear_value": (0.5, 0.25, 1.0, 1.0)}])  # fmt: skip
    rp.end()
    d.queue.submit([enc.finish()])
    assert read_texture(tex).min() > 0
    enc = d.create_command_encoder()
    fw.clear_colour(enc, et)
    d.queue.submit([enc.finish()])
    dtype = np.float16 if target == "hdr" else np.uint8
    np.testing.assert_array_equal(read_texture(tex), np.zeros((16, 48, 4), dtype))


@pytest.mark.gpu
@pytest.mark.parametrize("target", ["hdr", "display"])
def test_bench_frames_raster_floor_covers_every_pixel_of_both_eyes_once(target):
    """bench frame's raster floor (one constant-colour triangle per viewport through the
    renderer's own forward-pass encoding): every pixel of both eyes holds the constant, as
    the twin says (0.5 in HDR; output.tonemap of it on the display target)."""
    from vrneural.bench.frame import screen_floor_bundles
    from vrneural.runtime.output import tonemap

    r = _renderer(target=target)
    r.frame(0)
    r.wait()
    enc = r.dev.create_command_encoder()
    r.encode_forward(enc, None, screen_floor_bundles(r))
    r.dev.queue.submit([enc.finish()])
    want = np.full((40, 48, 3), 0.5, np.float32)
    if target == "display":
        got = r.read_display()
        want = tonemap(want)
    else:
        got = [e[..., :3] for e in r.read_eyes()]
    for g in got:
        assert np.abs(g.astype(np.float32) - want.astype(np.float32)).max() <= (
            1 if target == "display" else 0
        )


@pytest.mark.gpu
def test_settings_errors_are_one_line():
    from vrneural.errors import VrnError

    with pytest.raises(VrnError, match="frames_in_flight = 4 is out of range"):
        _renderer(frames_in_flight=4)
    with pytest.raises(VrnError, match="target = 'ldr' is not allowed"):
        _renderer(target="ldr")
    with pytest.raises(VrnError, match="colour_clear = 'fast' is not allowed"):
        _renderer(colour_clear="fast")


@pytest.mark.gpu
def test_uniform_arena_sends_the_written_span_once():
    """Regions aligned for uniform bindings; one write_buffer per flush carries everything
    written since the last one (read back from the GPU buffer)."""
    from vrneural.gpu.readback import read_buffer
    from vrneural.gpu.uniforms import UniformArena

    ar = UniformArena("test")
    offs = [ar.alloc(n) for n in (176, 96, 32)]
    assert offs[0] == 0 and all(o % ar.align == 0 for o in offs) and offs == sorted(offs)
    ar.binding(offs[0], 176)  # creates the buffer
    ar.view(offs[1], 96)[:] = np.arange(24, dtype=np.float32)
    ar.view(offs[2], 32)[:] = 7.0
    assert (ar.lo, ar.hi) == (offs[1], offs[2] + 32)
    ar.flush()
    assert ar.lo is None
    got = read_buffer(ar.buf, np.float32)
    np.testing.assert_array_equal(got[offs[1] // 4 : offs[1] // 4 + 24], np.arange(24))
    np.testing.assert_array_equal(got[offs[2] // 4 : offs[2] // 4 + 8], 7.0)
    with pytest.raises(RuntimeError, match="alloc after the buffer was created"):
        ar.alloc(16)


@pytest.mark.gpu
def test_poll_thread_cpu_counts_the_read_backs_host_work():
    """bench frame's second host clock: wgpu-py's device-poll thread maps every frame's
    read-back, so its CPU time grows over frames; the main thread's own time is not in it."""
    from vrneural.gpu.device import poll_thread_cpu

    r = _renderer(frames_in_flight=2)
    r.frame(0)
    r.wait()
    p0 = poll_thread_cpu()
    for f in range(1, 9):
        r.frame(f)
    r.wait()
    p1 = poll_thread_cpu()
    assert p0 is not None and p1 > p0  # Linux: per-thread clocks
    t0 = poll_thread_cpu()
    sum(i * i for i in range(300_000))  # main-thread work only
    assert poll_thread_cpu() - t0 < 0.01


def test_depth_slices_are_nearer_each_pass_and_cleared_once_per_cycle():
    """forward.depth_slice: pass n of a cycle of S draws into [1 - (n+1)/S, 1 - n/S]; only
    the first pass of each cycle clears; slices 1 is the whole range, cleared every pass."""
    from vrneural.runtime.forward import depth_slice

    got = [depth_slice(n, 4) for n in range(9)]
    assert [c for c, _, _ in got] == [True, False, False, False] * 2 + [True]
    for n in range(1, 9):
        if not got[n][0]:  # below everything drawn since the clear
            assert got[n][2] <= got[n - 1][1] and got[n][1] < got[n][2]
    assert got[0][1:] == (0.75, 1.0) and got[3][1:] == (0.0, 0.25)
    assert all(depth_slice(n, 1) == (True, 0.0, 1.0) for n in range(3))


def _floor_passes(r, n: int) -> list[np.ndarray]:
    """``n`` of bench frame's raster floors (a constant triangle over each eye, at the same
    depth every pass), each in its own submit; each pass's eyes as read after it."""
    from vrneural.bench.frame import screen_floor_bundles

    r.frame(0)
    r.wait()
    bundles, out = screen_floor_bundles(r), []
    for _ in range(n):
        enc = r.dev.create_command_encoder()
        r.encode_forward(enc, None, bundles)
        r.dev.queue.submit([enc.finish()])
        out.append(np.stack([e[..., :3] for e in r.read_eyes()]))
    return out


@pytest.mark.gpu
def test_sliced_depth_lets_every_pass_draw_over_the_depth_left_by_the_last(monkeypatch):
    """depth_clear "slices": passes that load the depth (three in four) still draw the
    floor's triangle, at the same depth as the pass before left everywhere, over every pixel
    of both eyes. The check can fail: with the depth loaded but the range not moved nearer,
    the second pass draws nothing (its colour stays the clear's black)."""
    from vrneural.runtime import forward as fw
    from vrneural.runtime.settings import DEPTH_SLICES

    r = _renderer(depth_clear="slices")
    assert r.depth_clear == "slices" and r.eye_t[0].depth_slices == DEPTH_SLICES
    for k, got in enumerate(_floor_passes(r, 2 * DEPTH_SLICES + 1)):
        assert (got == 0.5).all(), f"pass {k}"
    monkeypatch.setattr(fw, "depth_slice", lambda n, s: (n == 0, 0.0, 1.0))  # broken on purpose
    broken = _floor_passes(_renderer(depth_clear="slices"), 2)
    assert (broken[0] == 0.5).all() and (broken[1] == 0).all()


@pytest.mark.gpu
@pytest.mark.parametrize("name", ["texture", "screen", "bench_1light"])
def test_sliced_depth_gives_the_frames_of_a_depth_cleared_every_pass(name):
    """depth_clear "slices" against "pass" over more frames than a cycle (the head orbits,
    objects move across the depth left by earlier frames): the same counters and the same
    bits (on lavapipe; elsewhere two surfaces closer than the sliced depth's precision could
    swap)."""
    n = 10
    got = {}
    for d in ("slices", "pass"):
        got[d] = render(name, wait=lambda r: r.wait(), depth_clear=d, frames=n)
    np.testing.assert_array_equal(got["slices"][1], got["pass"][1])
    a, b = got["slices"][0], got["pass"][0]
    assert a.shape[0] == n and (a > 0).mean() > 0.3
    np.testing.assert_array_equal(a, b)


#: WebGPU's standard positions of 4 samples in a pixel (x right, y down)
SAMPLES_4 = ((0.375, 0.125), (0.875, 0.375), (0.125, 0.625), (0.625, 0.875))


def _coverage_twin(w: int, h: int, tri_px) -> np.ndarray:
    """Numpy twin of a 4x multisampled, resolved constant triangle: per pixel, the share of
    the standard sample positions inside triangle ``tri_px`` (pixel coordinates, y down)."""
    (x0, y0), (x1, y1), (x2, y2) = tri_px
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float64)
    cov = np.zeros((h, w))
    area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
    for sx, sy in SAMPLES_4:
        px, py = xs + sx, ys + sy
        e = [((bx - ax) * (py - ay) - (by - ay) * (px - ax)) * np.sign(area)
             for (ax, ay), (bx, by) in (((x0, y0), (x1, y1)), ((x1, y1), (x2, y2)),
                                        ((x2, y2), (x0, y0)))]  # fmt: skip
        assert min(np.abs(x).min() for x in e) > 1e-3  # no sample on an edge (no tie rule)
        cov += np.all([x > 0 for x in e], axis=0)
    return cov / 4


@pytest.mark.gpu
def test_msaa_resolves_a_triangles_edge_to_its_sample_coverage():
    """Settings.msaa 4 through the renderer's own forward-pass encoding (multisampled targets,
    the pass's resolve into the eyes' colour, bundles at 4 samples): a constant 0.5 triangle
    over black, its slanted edge across both eyes, resolves to 0.5 x the share of the standard
    sample positions it covers in every pixel (the numpy twin), 0, 1/8, ... 1/2 exactly; a
    single-sample target gives 0 or 0.5 only."""
    from vrneural.gpu.device import get_device
    from vrneural.runtime import forward as fw

    w, h = 48, 40
    tri = ((-10.0, -10.0), (2.03 * w, -10.0), (-10.0, 1.71 * h))  # pixels, y down
    ndc = [(2 * x / w - 1, 1 - 2 * y / h) for x, y in tri]
    code = f"""
@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {{
    var p = array<vec2<f32>, 3>({", ".join(f"vec2<f32>({x!r}, {y!r})" for x, y in ndc)});
    return vec4<f32>(p[i], 0.5, 1.0);
}}
@fragment fn fs() -> @location(0) vec4<f32> {{ return vec4<f32>(0.5, 0.5, 0.5, 1.0); }}"""
    dev = get_device()
    mod = dev.create_shader_module(code=code)
    for samples in (4, 1):
        r = _renderer(msaa=samples, eye_res=(w, h))
        assert r.eye_t[0].samples == samples
        pipe = dev.create_render_pipeline(
            layout="auto", vertex={"module": mod, "entry_point": "vs"}, **fw._raster_state(),
            fragment={"module": mod, "entry_point": "fs",
                      "targets": [{"format": r.eye_t[0].format}]},
            multisample={"count": samples})  # fmt: skip
        bundles = []
        for et in r.eye_t:
            enc = fw.bundle_encoder(et)
            enc.set_pipeline(pipe)
            enc.draw(3)
            bundles.append(enc.finish())
        enc = dev.create_command_encoder()
        r.encode_forward(enc, None, bundles)
        dev.queue.submit([enc.finish()])
        want = _coverage_twin(w, h, tri) * 0.5
        for eye in r.read_eyes():
            got = eye[..., 0]
            if samples == 4:
                np.testing.assert_array_equal(got, want.astype(np.float32))
                assert set(np.unique(got)) >= {0.0, 0.125, 0.25, 0.375, 0.5}
            else:
                assert set(np.unique(got)) == {0.0, 0.5}
                assert np.abs(got - want).max() <= 0.375  # the same edge


@pytest.mark.gpu
@pytest.mark.parametrize("mips", [False, True])
def test_msaa_frames_differ_from_single_sample_only_where_edges_cross_pixels(mips):
    """The renderer at 4 samples per pixel against 1, frame after frame (the depth sliced
    too): the same counters (shading is unchanged: the texture-space pass never sees the
    samples); most pixels the same bits (covered by one triangle); the rest near their
    single-sample value inside surfaces (triangle edges) or between the two sides of a
    silhouette, and the image's mean within 2%. With radiance mips too (sampled at the
    centroid, the level from the pixel centre's derivatives)."""
    runs = {}
    for m in (1, 4):
        r = _renderer(msaa=m, depth_clear="slices", mips=mips)
        st, eyes = [], []
        for f in range(6):
            st.append(r.frame(f))
            eyes.append(np.stack(r.read_eyes()))
        r.wait()
        runs[m] = ([_counts(x) for x in st], np.stack(eyes))
    assert runs[1][0] == runs[4][0]
    a, b = runs[1][1][..., :3], runs[4][1][..., :3]
    same = np.all(a == b, axis=-1)
    assert 0.5 < same.mean() < 1.0
    assert abs(a.mean() - b.mean()) <= 0.02 * a.mean()  # 1.1% here (tiny eyes: many edges)


@pytest.mark.gpu
def test_msaa_errors_are_one_line():
    from vrneural.errors import VrnError

    with pytest.raises(VrnError, match="msaa = 2 is not allowed; choose 1, 4"):
        _renderer(msaa=2)
    with pytest.raises(VrnError, match="msaa = 4 needs mode 'texture'"):
        _renderer(msaa=4, mode="screen")
