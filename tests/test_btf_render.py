"""`vrneural btf render`: Mitsuba 3 path-traced BTFs. The conventions against closed forms (flat
Lambert, flat rough conductor), rectification, tile copies at the edges, a tiny preset end to
end, determinism, Ctrl-C + resume, and the one-line errors. Mitsuba runs for real (the render
extra, which scripts/setup.sh installs); under CI=true a missing Mitsuba fails the run."""

import functools
import json
import os
import subprocess
import sys

import numpy as np
import pytest
from btf_helpers import lambert_btf

from vrneural.btf import read_btf
from vrneural.btf.brdf import ggx_d, smith_lambda
from vrneural.btf.dirs import direction_set, spherical
from vrneural.btf.pt_geometry import Part, Tile, heightfield
from vrneural.btf.pt_presets import PT_PRESETS

if os.environ.get("CI", "").lower() in ("1", "true", "yes"):
    import mitsuba  # noqa: F401  (CI installs the render extra: never skip there)
else:
    pytest.importorskip("mitsuba")

from vrneural.btf import pathtrace as pt

PAIRS = [((0, 0), (0, 0)), ((30, 0), (45, 180)), ((60, 20), (70, 200)), ((75, 90), (20, 300))]


def _dir(theta, phi):
    return spherical(np.radians([theta]), np.radians([phi]))[0].astype(np.float64)


def _flat(bsdf, res=8, bounces=3, z=0.0):
    tile = Tile([Part(heightfield(np.full((4, 4), z)), bsdf)])
    ps = pt.build_scene(tile, bounces, ring=2)
    ps.z_ref = z
    return ps


def test_flat_lambert_is_albedo_over_pi_times_cos():
    """docs/conventions.md section 2: a flat Lambertian patch gives a / pi * wi.z. With a
    directional light there is no Monte Carlo error left on a flat patch (one bounce, the
    light sampled exactly), so the match is to float32 precision at every texel."""
    a = (0.2, 0.5, 0.8)
    ps = _flat({"type": "diffuse", "reflectance": {"type": "rgb", "value": list(a)}})
    for wi, wo in PAIRS:
        wi, wo = _dir(*wi), _dir(*wo)
        img = pt.render_slice(ps, pt.sensor(ps, wo, 8, 4), wi, 4, 7)
        want = lambert_btf(a, wi[2])
        np.testing.assert_allclose(img, np.broadcast_to(want, img.shape), rtol=2e-5, atol=1e-7)


def _ggx_separable(wi, wo, at, ab):
    """GGX with the separable Smith G1(wi) G1(wo) (what Mitsuba's roughconductor uses), built
    from brdf.py's D and Lambda, times cos(theta_i): the BTF value of a perfect conductor."""
    h = (wi + wo) / np.linalg.norm(wi + wo)
    d = ggx_d(h[0], h[1], h[2], at, ab)
    g = 1.0 / ((1.0 + smith_lambda(*wi, at, ab)) * (1.0 + smith_lambda(*wo, at, ab)))
    return d * g / (4.0 * wi[2] * wo[2]) * wi[2]


def test_flat_rough_conductor_is_the_analytic_ggx_value():
    """An anisotropic GGX conductor (F = 1: Mitsuba's ``material: none``) on a flat patch:
    the rendered value is D G1 G1 / (4 cos_i cos_o) * cos_i with brdf.py's D and Lambda, alpha_u
    along u (the mesh's tangent). Mitsuba's G is the separable Smith form; brdf.py's is the
    height-correlated one, which differs by up to a few % at grazing pairs (checked too, so a
    change of either is noticed). Mitsuba's default distribution is Beckmann: the presets
    always name ``ggx``."""
    at, ab = 0.15, 0.45
    bsdf = {"type": "roughconductor", "material": "none", "distribution": "ggx"}
    ps = _flat({**bsdf, "alpha_u": at, "alpha_v": ab})
    from vrneural.btf.brdf import brdf, params

    for wi, wo in PAIRS[1:]:
        wi, wo = _dir(*wi), _dir(*wo)
        img = pt.render_slice(ps, pt.sensor(ps, wo, 8, 4), wi, 4, 3)
        want = _ggx_separable(wi, wo, at, ab)
        np.testing.assert_allclose(img, want, rtol=2e-4)
        corr = brdf(tuple(wi), tuple(wo), params(albedo=(0, 0, 0), f0=(1, 1, 1), alpha=(at, ab)))
        corr = float(np.ravel(corr)[0]) * wi[2]
        assert want * (1 - 1e-6) <= corr <= want * 1.06  # correlated G >= separable G


def test_slices_are_rectified_texel_for_texel():
    """The ray through pixel (x, y) crosses the reference plane at texel (x, y)'s centre: a
    texture's texel (x, y) = row y, column x shows at pixel (x, y) from any view."""
    tex = np.zeros((8, 8, 3), np.float32)
    tex[1, 5] = (0.9, 0.0, 0.0)
    tex[6, 2] = (0.0, 0.9, 0.0)
    bsdf = {
        "type": "diffuse",
        "reflectance": {"type": "bitmap", "data": tex, "filter_type": "nearest"},
    }
    ps = _flat(bsdf, z=0.013)  # the reference plane follows the surface, wherever it is
    for wo in ((0, 0), (60, 30), (75, 250)):
        img = pt.render_slice(ps, pt.sensor(ps, _dir(*wo), 8, 16), _dir(20, 0), 16, 1)
        assert np.argwhere(img[..., 0] > 0.01).tolist() == [[1, 5]]
        assert np.argwhere(img[..., 1] > 0.01).tolist() == [[6, 2]]


def test_edge_texels_are_lit_and_shadowed_like_interior_ones():
    """Copies of the tile around it: the tile rolled by half its width renders the rolled
    slice (a texel at the edge sees, and is shadowed by, the neighbouring tile). Deep grooves,
    a raking light and a grazing view make edge texels depend on the neighbours."""
    n = 16
    x = (np.arange(n) + 0.5) / n
    h = 0.08 * np.cos(2 * np.pi * x)[None, :] * np.cos(2 * np.pi * 2 * x)[:, None]
    bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6, 0.6, 0.6]}}
    wi, wo = _dir(70, 10), _dir(65, 190)

    def rel_diff(ring: int) -> tuple[float, float]:
        """Mean |slice - rolled slice| over the slice mean: all texels, the edge rows."""
        out = []
        for hh in (h, np.roll(h, (n // 2, n // 2), (0, 1))):
            ps = pt.build_scene(Tile([Part(heightfield(hh), bsdf)]), 1, ring=ring)
            ps.z_ref = float(pt.height_field(ps, 32).mean())
            out.append(pt.render_slice(ps, pt.sensor(ps, wo, 8, 256), wi, 256, 5))
        assert out[0].min() < 0.3 * out[0].max()  # shadows: the case is not trivial (0.2)
        d = np.abs(np.roll(out[1], (-4, -4), (0, 1)) - out[0]) / out[0].mean()
        return float(d.mean()), float(d[[0, -1]].mean() + d[:, [0, -1]].mean()) / 2

    # measured: 0.23% (all) and 0.22% (edges) at 256 multi-jittered samples, Monte Carlo
    # noise only (independent samples: 2.8% and 2.6%); without the copies 21-29%
    whole, edges = rel_diff(pt.copy_ring(0.16, 75))
    assert whole < 0.01 and edges < 0.01, (whole, edges)
    assert min(rel_diff(0)) > 0.15  # the negative control: no copies, edges see nothing


def _vrn(*args, timeout=300):
    env = dict(os.environ, XDG_RUNTIME_DIR="/tmp")
    return subprocess.run(
        [sys.executable, "-m", "vrneural", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
    )


TINY = ["--res", 8, "--dirs", 3, "--spp", 4, "--no-progress"]


@pytest.fixture
def vrn_inproc(capsys, monkeypatch):
    """Run `vrneural ...` in this process (``cwd``: where); returns (exit code, stderr)."""
    from vrneural.cli import main

    def run(args, cwd=None):
        if cwd is not None:
            monkeypatch.chdir(cwd)
        capsys.readouterr()
        rc = main([str(a) for a in args])
        return rc, capsys.readouterr().err

    return run


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    out = tmp_path_factory.mktemp("render") / "weave.btf"
    r = _vrn("btf", "render", "weave", *TINY, "-o", out)
    assert r.returncode == 0, r.stderr
    return out


def test_tiny_preset_end_to_end(tiny, tmp_path, capsys):
    b = read_btf(tiny)
    assert b.shape == (3, 3, 8, 8)
    np.testing.assert_allclose(b.light_dirs, direction_set(3), atol=1e-6)
    v = np.asarray(b.values, np.float32)
    assert np.isfinite(v).all() and v.min() >= 0 and v.mean() > 1e-3 and v.std() > 1e-3
    # the height field travels with the data (format version 2), relative to the plane
    assert b.height is not None and b.height.shape == (16, 16)
    assert abs(float(b.height.mean())) < 1e-6 and np.ptp(b.height) > 0.05
    with open(tiny, "rb") as f:
        assert int.from_bytes(f.read(12)[8:12], "little") == 2
    gen = b.meta["generator"]
    assert gen["preset"] == "weave" and gen["spp"] == 4 and gen["mitsuba_variant"] == "scalar_rgb"
    assert gen["sampler"] == "multijitter"
    from vrneural.cli import main

    assert main(["btf", "info", str(tiny)]) == 0
    assert "height    16x16 height field" in capsys.readouterr().out
    cfg = json.loads(tiny.with_name("weave.btf.config.json").read_text())
    assert cfg["config"] == "RenderConfig" and cfg["height_grid_used"] == 16
    # same settings, same bytes; another sample seed: another render of the same material
    again = tmp_path / "again.btf"
    assert _vrn("btf", "render", "weave", *TINY, "-o", again).returncode == 0
    assert again.read_bytes() == tiny.read_bytes()
    other = tmp_path / "other.btf"
    assert _vrn("btf", "render", "weave", *TINY, "--sample-seed", 1, "-o", other).returncode == 0
    w = np.asarray(read_btf(other).values, np.float32)
    np.testing.assert_array_equal(read_btf(other).height, b.height)  # same geometry
    assert not np.array_equal(w, v) and abs(w.mean() - v.mean()) < 0.1 * v.mean()


def test_interrupted_render_resumes_to_the_same_bytes(tiny, tmp_path, monkeypatch):
    from vrneural.btf import pt_render
    from vrneural.btf.pt_render import RenderConfig, render_btf

    cfg = RenderConfig(preset="weave", res=8, dirs=3, spp=4)
    out = tmp_path / "weave.btf"
    real = pt.render_slice
    calls = {"n": 0}

    def stop_after_four(*a, **k):
        calls["n"] += 1
        if calls["n"] > 4:  # inside the second view
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(pt, "render_slice", stop_after_four)
    with pytest.raises(KeyboardInterrupt):
        render_btf(cfg, out, progress=False)
    partial = tmp_path / "weave.btf.partial"
    assert partial.exists() and not out.exists()
    assert partial.with_name("weave.btf.partial.done").read_text() == "0\n"
    monkeypatch.setattr(pt, "render_slice", real)
    with pytest.raises(Exception, match="other settings"):
        render_btf(RenderConfig(preset="weave", res=8, dirs=3, spp=8), out, resume=True)
    # the same settings with another material (a variant's keywords): its fingerprint differs
    with monkeypatch.context() as m:
        m.setitem(PT_PRESETS, "weave", functools.partial(PT_PRESETS["weave"], fibres=4))
        with pytest.raises(Exception, match=r"other settings.*scene: '[0-9a-f]{16}' there"):
            render_btf(cfg, out, resume=True, progress=False)
    assert render_btf(cfg, out, resume=True, progress=False) == out
    assert out.read_bytes() == tiny.read_bytes()
    assert pt_render.GENERATOR in read_btf(out).meta["generator"]["tool"]


@pytest.mark.parametrize(
    "args, needle",
    [
        (["nosuch", "-o", "x.btf"], "preset = 'nosuch' is not allowed; choose one of: bark"),
        (["weave", "--spp", "0", "-o", "x.btf"], "--spp = 0 is out of range"),
        (["weave", "--res", "7", "-o", "x.btf"], "must be even"),
        (["weave", "--bounces", "0", "-o", "x.btf"], "--bounces = 0 is out of range"),
        (["weave", "--spp", "128", "-o", "x.btf"], "a = floor(sqrt(spp)); nearest 121 or 132, "),
        (["weave", "-o", "x.png"], ".btf"),
        # a height field parallax cannot use (it box-averages the grid onto the texels)
        (
            ["weave", "--res", "8", "--height-grid", "12", "-o", "x.btf"],
            "--height-grid = 12 does not nest in the 8x8 texels: parallax could not use it; "
            "give 0 (auto) or a whole multiple of --res (8, 16, 24)",
        ),
        (["weave", "--height-grid", "5000", "-o", "x.btf"], "allowed 0 (auto) or [2, 4096]"),
    ],
)
def test_bad_options_are_one_line_errors(tmp_path, vrn_inproc, args, needle):
    code, err = vrn_inproc(["btf", "render", *args], cwd=tmp_path)
    assert code == 2 and needle in err and len(err.strip().splitlines()) == 1, err
    assert not any(tmp_path.iterdir())


def test_existing_output_is_kept_and_missing_mitsuba_names_the_extra(tiny, tmp_path, vrn_inproc):
    out = tmp_path / "keep.btf"
    out.write_bytes(b"precious")
    code, err = vrn_inproc(["btf", "render", "weave", *map(str, TINY), "-o", str(out)])
    assert code == 2 and "--force" in err and out.read_bytes() == b"precious"
    # without Mitsuba: one line naming the extra, nothing written
    code = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; sys.modules['mitsuba'] = None; from vrneural.cli import main; "
            f"sys.exit(main(['btf', 'render', 'weave', '-o', {str(tmp_path / 'n.btf')!r}]))",
        ],
        capture_output=True,
        text=True,
    )
    err = code.stderr.strip().splitlines()
    assert code.returncode == 2 and len(err) == 1, code.stderr
    assert "vrneural[render]" in err[0] and "Mitsuba 3 is not installed" in err[0]
    assert not (tmp_path / "n.btf").exists() and not (tmp_path / "n.btf.partial").exists()


def test_noise_floor_of_a_render(tiny):
    """Another sample seed of the same settings: a small, nonzero L1 (pure Monte Carlo noise:
    the same material)."""
    from vrneural.btf.pt_render import noise_floor

    r = noise_floor(tiny, views=2, progress=False)
    assert r["views"] == [0, 2] and r["preset"] == "weave" and r["spp"] == 4
    assert 0 < r["l1"] < 0.5 * r["mean"]
    assert r["l1_vs_converged"] == pytest.approx(r["l1"] / 2**0.5)


def test_noise_floor_refuses_another_material(tiny, monkeypatch):
    """The header's scene fingerprint: a preset built with other keywords (a variant, or
    another version of the preset) is not re-rendered against the file, which would measure
    the two materials' difference as noise; a one-line error names both fingerprints."""
    from vrneural.btf.pt_render import noise_floor
    from vrneural.errors import VrnError

    rendered = read_btf(tiny).meta["generator"]["scene"]
    monkeypatch.setitem(PT_PRESETS, "weave", functools.partial(PT_PRESETS["weave"], fibres=4))
    with pytest.raises(VrnError, match="not the material rendered there") as e:
        noise_floor(tiny, views=1, progress=False)
    assert rendered in str(e.value) and "\n" not in str(e.value)


def test_the_auto_height_grid_always_nests_in_the_texels():
    """0 = auto: 2 x res up to res 256 (the grids every render so far has, headers unchanged),
    res itself above (it was min(512, 2 res): 512 at res 300, which parallax refuses)."""
    from vrneural.btf.config import RenderConfig

    for res in (2, 8, 64, 256, 258, 300, 1000, 4096):
        n = RenderConfig(res=res).grid_size
        assert n % res == 0 and n <= 4096 and n == (2 * res if res <= 256 else res), res
    assert RenderConfig(res=8, height_grid=24).grid_size == 24


def test_scene_fingerprint_follows_the_material():
    """The same preset and seed give the same fingerprint; other keywords or seeds another."""
    from vrneural.btf.pt_presets import fur

    def fp(seed, **kw):
        return fur(np.random.default_rng(seed), tufts=4, per_tuft=2, **kw).fingerprint()

    assert fp(0) == fp(0) and len(fp(0)) == 16
    assert len({fp(0), fp(1), fp(0, gloss=0.06), fp(0, bands=(0.4, 0.7))}) == 4


def test_multijittered_samples_are_less_noisy_than_independent_ones(tiny, tmp_path, monkeypatch):
    """The default sampler against `--sampler independent` at the same sample count: the L1
    between two sample seeds (the noise floor, `noise_floor`'s measure) is lower on the weave
    at 16 samples; `noise_floor` re-renders with the file's own sampler, and a header written
    before the option existed counts as independent (what it was rendered with)."""
    from vrneural.btf.config import RENDER_BEFORE, RenderConfig, jitter_grid
    from vrneural.btf.pt_render import build, noise_floor

    assert [jitter_grid(n) for n in (1, 4, 5, 8, 64, 128)] == [1, 4, 6, 8, 64, 132]
    assert RenderConfig(spp=128, sampler="independent").validate() is None
    cfg = RenderConfig(preset="weave", res=16, dirs=3, spp=16)
    ps, _, _ = build(cfg)
    wi, wo = _dir(40, 30), _dir(50, 200)
    l1 = {}
    for kind in ("multijitter", "independent"):
        cam = pt.sensor(ps, wo, 16, 16, kind)
        a, b = (pt.render_slice(ps, cam, wi, 16, seed) for seed in (1, 2))
        l1[kind] = float(np.abs(a - b).mean() / a.mean())
    assert l1["multijitter"] < 0.8 * l1["independent"], l1
    out = tmp_path / "ind.btf"
    args = ["btf", "render", "weave", "--res", 8, "--dirs", 3, "--spp", 5]
    r = _vrn(*args, "--sampler", "independent", "-o", out)
    assert r.returncode == 0, r.stderr
    assert noise_floor(out, views=1, progress=False)["sampler"] == "independent"
    assert noise_floor(tiny, views=1, progress=False)["sampler"] == "multijitter"
    from vrneural.btf import pt_render

    real = pt_render.read_btf

    def before_the_option(path):
        b = real(path)
        del b.meta["generator"]["sampler"]
        return b

    monkeypatch.setattr(pt_render, "read_btf", before_the_option)
    assert RENDER_BEFORE == {"sampler": "independent"}
    assert noise_floor(tiny, views=1, progress=False)["sampler"] == "independent"


def test_render_stops_on_sigterm_and_resumes(tmp_path):
    """`kill` (SIGTERM) stops `btf render` after the current slice: exit 130, the partial
    file kept, and --resume finishes it with the same bytes as a run never stopped."""
    import signal
    import time

    out = tmp_path / "f.btf"
    argv = [sys.executable, "-m", "vrneural", "btf", "render", "fur", "--res", "8"]
    argv += ["--dirs", "12", "--spp", "4", "-o", str(out), "--no-progress"]
    env = dict(os.environ, XDG_RUNTIME_DIR="/tmp")
    proc = subprocess.Popen(argv, stderr=subprocess.PIPE, text=True, env=env)
    done = tmp_path / "f.btf.partial.done"
    deadline = time.monotonic() + 120
    while not done.exists() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.02)
    assert proc.poll() is None, "finished before it could be stopped: make it bigger"
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    said = [line for line in err.splitlines() if "interrupted" in line]  # one line says it all
    assert len(said) == 1 and said[0].startswith("vrneural btf render: interrupted after"), err
    assert "--resume" in said[0] and "f.btf.partial" in said[0], err
    assert (tmp_path / "f.btf.partial").exists() and not out.exists()
    r = subprocess.run([*argv, "--resume"], capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0 and "resuming" in r.stderr, r.stderr
    straight = tmp_path / "g.btf"
    argv[argv.index(str(out))] = str(straight)
    assert subprocess.run(argv, capture_output=True, env=env, timeout=300).returncode == 0
    assert out.read_bytes() == straight.read_bytes()


def test_ctrl_c_inside_a_views_last_slice_keeps_no_part_rendered_slice(tmp_path, monkeypatch):
    """SIGINT while Mitsuba renders a view's last slice: Mitsuba stops that render and returns
    the image part-filled; the view must not be saved as done with it (it was, found by a
    new user's Ctrl-C: --resume kept a slice with hundreds of black texels). A real SIGINT,
    sent by a timer halfway through the real slice."""
    import signal
    import threading
    import time

    from vrneural.btf.pt_render import RenderConfig, render_btf

    cfg = RenderConfig(preset="weave", res=16, dirs=2, spp=256)
    real = pt.render_slice
    seen = {}

    def last_slice_interrupted(ps, cam, wi, spp, seed):
        seen["n"] = seen.get("n", 0) + 1
        if seen["n"] != 4:  # view 1's last light (two lights a view)
            return real(ps, cam, wi, spp, seed)
        t0 = time.perf_counter()
        seen["clean"] = real(ps, cam, wi, spp, seed)
        threading.Timer(
            0.5 * (time.perf_counter() - t0), os.kill, (os.getpid(), signal.SIGINT)
        ).start()
        seen["cut"] = real(ps, cam, wi, spp, seed)
        return seen["cut"]

    for attempt in range(3):  # the timer must land inside the render; say so if it never did
        out = tmp_path / f"w{attempt}.btf"
        seen.clear()
        monkeypatch.setattr(pt, "render_slice", last_slice_interrupted)
        with pytest.raises(KeyboardInterrupt):
            render_btf(cfg, out, progress=False)
        monkeypatch.setattr(pt, "render_slice", real)
        cut_short = not np.array_equal(seen["cut"], seen["clean"])
        done = out.with_name(out.name + ".partial.done").read_text().split()
        assert done == ["0"], done  # view 1 is not done, whether or not its slice was whole
        assert render_btf(cfg, out, resume=True, progress=False) == out
        straight = tmp_path / f"s{attempt}.btf"
        assert out.read_bytes() == render_btf(cfg, straight, progress=False).read_bytes()
        if cut_short:
            assert (seen["cut"].max(-1) == 0).sum() > (seen["clean"].max(-1) == 0).sum()
            return
    pytest.fail("the SIGINT never landed inside Mitsuba's render in three tries")


def test_direct_light_matches_btf_synth_on_a_heightfield():
    """Both renderers on one smooth heightfield (Lambert, albedo 0.5, direct light only):
    `btf synth`'s ray marcher with shadow-height maps and Mitsuba on the triangulated tile
    agree texel by texel (measured: 0.1-0.5% mean relative difference per slice, theta up to
    70 degrees): the same rectification, parallax, masking, shadowing and convention."""
    from btf_helpers import flat_maps

    from vrneural.btf.render import make_scene, render_view

    n = 64
    x = (np.arange(n) + 0.5) / n
    h = 0.03 * np.cos(2 * np.pi * x)[None, :] * np.cos(4 * np.pi * x)[:, None]
    h = (h + 0.02 * np.sin(2 * np.pi * (x[None, :] + x[:, None]))).astype(np.float32)
    maps = flat_maps(n, albedo=(0.5, 0.5, 0.5), f0=(0, 0, 0))
    maps.height = h
    dirs = spherical(np.radians([20, 60, 70, 40]), np.radians([0, 90, 200, 300]))
    synth = make_scene(maps, dirs)
    k = 8  # the same stratified sub-sample positions in both
    cells = (np.stack(np.meshgrid(np.arange(k), np.arange(k)), -1).reshape(-1, 2) + 0.5) / k
    samples = np.broadcast_to(cells - 0.5, (16, 16, k * k, 2)).copy()
    lam = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}}
    ps = pt.build_scene(Tile([Part(heightfield(h), lam)]), 1, ring=2)
    ps.z_ref = float(pt.height_field(ps, 64).mean())
    worst = 0.0
    for wo in dirs[[0, 2]]:
        a = render_view(synth, wo, samples, (16, 16))
        cam = pt.sensor(ps, wo, 16, 256)
        for li, wi in enumerate(dirs):
            b = pt.render_slice(ps, cam, wi, 256, 3)
            worst = max(worst, float(np.abs(a[li] - b).mean() / a[li].mean()))
    assert worst < 0.02, worst


@pytest.mark.parametrize("preset", ["weave", "pebbles", "fur", "bark", "mosaic", "berber"])
def test_every_preset_builds_and_renders_a_slice(preset):
    """Each preset's Mitsuba scene loads (its BSDFs and bitmap textures are valid plugins)
    and a tiny slice from above renders finite, positive, textured values."""
    from vrneural.btf.pt_render import RenderConfig, build

    ps, h, tile = build(RenderConfig(preset=preset, res=8, dirs=3, spp=4))
    assert h.shape == (16, 16) and np.ptp(h) > 0.01 and tile.about
    cam = pt.sensor(ps, np.array([0.0, 0.0, 1.0]), 8, 4)
    img = pt.render_slice(ps, cam, spherical(np.radians(30.0), np.radians(20.0)), 4, 0)
    assert img.shape[:2] == (8, 8) and np.isfinite(img).all() and img.min() >= 0
    assert img.mean() > 1e-3 and img.std() > 0


def _berber_rng():
    """The berber tests' generator: one fixed seed, so two calls build the same tile."""
    return np.random.default_rng([0, 1])


def test_berber_loops_follow_their_heights():
    """The loop pile's geometry: the tallest loop's yarn tops out at the upper height (give or
    take the yarn's radius), lower heights give a lower pile, and the same seed the same tile."""
    from vrneural.btf.pt_presets import berber

    R = 0.3 / 10  # the preset's yarn radius: 0.3 of the row pitch
    top = berber(_berber_rng()).bounds()[1]
    assert 0.12 - 0.5 * R < top < 0.12 + R
    high = berber(_berber_rng(), heights=(0.05, 0.17)).bounds()[1]  # the first version's pile
    assert 0.17 - 0.5 * R < high < 0.17 + R
    a, b = berber(_berber_rng()), berber(_berber_rng())
    assert all(np.array_equal(p.mesh.v, q.mesh.v) for p, q in zip(a.parts, b.parts, strict=True))


def test_berber_knobs_of_its_variants():
    """The variants' knobs (the research scripts' renders): ``shares`` sets how many loops take
    each colour (the charcoal yarn's vertices follow its share), ``yarn`` the yarn's radius
    (the pile's lowest point, the yarn diving half a radius into the backing), ``backing`` the
    backing's albedo."""
    from vrneural.btf.pt_presets import berber

    def charcoal(tile):
        n = {p.name: len(p.mesh.v) for p in tile.parts}
        return n.get("yarn3", 0) / sum(v for k, v in n.items() if k.startswith("yarn"))

    plain = berber(_berber_rng())
    flecked = berber(_berber_rng(), flecks=(12.0, 32.0), shares=(0.3, 0.5, 0.7))
    assert charcoal(plain) == pytest.approx(0.12, abs=0.02)  # loops above the 0.88 quantile
    assert charcoal(flecked) == pytest.approx(0.30, abs=0.02)
    yarn_low = [
        min(p.mesh.v[:, 2].min() for p in t.parts if p.name.startswith("yarn"))
        for t in (plain, berber(_berber_rng(), yarn=0.2))
    ]
    assert yarn_low[1] > yarn_low[0]  # a thinner yarn dives less deep
    jute = berber(_berber_rng(), backing=(0.45, 0.38, 0.26))
    assert jute.parts[-1].name == "backing"
    assert np.allclose(jute.parts[-1].bsdf["reflectance"]["value"], (0.45, 0.38, 0.26))


def test_fur_knobs_of_its_variants():
    """The fur variants' knobs (``fur-variants-render.py``): ``heights`` bounds the strands'
    tips (each strand 0.85-1 of its tuft's height), ``radius`` the strands' root radius (a
    ring's spread about its centre), ``crimp`` waves each strand sideways (its tip-to-root path
    longer than the straight pile's, by more for a larger crimp), ``carve`` cuts that share of
    the tufts down to ``carved`` of their height, the rest unchanged."""
    from vrneural.btf.pt_presets import fur

    def strands(tile):
        return [p.mesh.v for p in tile.parts if p.name.startswith("yarn")]

    plain = fur(np.random.default_rng(3), tufts=16, per_tuft=4)
    low = fur(np.random.default_rng(3), tufts=16, per_tuft=4, heights=(0.05, 0.06))
    tops = [max(v[:, 2].max() for v in strands(t)) for t in (plain, low)]
    assert 0.14 * 0.85 < tops[0] <= 0.17 + 0.002 and 0.05 * 0.85 < tops[1] <= 0.06 + 0.002
    thick = fur(np.random.default_rng(3), tufts=16, per_tuft=4, radius=0.009)
    root_ring = [strands(t)[0][:5] for t in (plain, thick)]  # the first strand's root ring
    spread = [np.linalg.norm(r - r.mean(0), axis=1).mean() for r in root_ring]
    assert spread[1] / spread[0] == pytest.approx(0.009 / 0.002, rel=1e-4)  # float32 vertices

    lengths = []
    for c in (0.0, 0.006, 0.012):
        tile = fur(np.random.default_rng(3), tufts=1, per_tuft=1, crimp=c)
        v = strands(tile)[0]
        rings = v.reshape(-1, 5, 3).mean(1)
        lengths.append(
            np.linalg.norm(np.diff(rings, axis=0), axis=1).sum() / (rings[-1, 2] - rings[0, 2])
        )
    assert lengths[0] < lengths[1] < lengths[2]

    # carve: that share of the tufts (those nearest the patches' borders) at ``carved`` height
    def tips(tile):  # each plain strand 7 rings of 5 vertices; its tip the last ring's height
        return np.concatenate([v.reshape(-1, 35, 3)[:, -5:, 2].mean(1) for v in strands(tile)])

    flat = tips(plain)
    cut = tips(fur(np.random.default_rng(3), tufts=16, per_tuft=4, carve=0.25, carved=0.4))
    low = cut < 0.14 * 0.85
    assert low.sum() == 4 * 4 and not (flat < 0.14 * 0.85).any()  # 4 tufts of 16, 4 strands
    assert cut[low] == pytest.approx(flat[low] * 0.4, rel=1e-5)
    assert cut[~low] == pytest.approx(flat[~low], rel=1e-6)


def test_weave_knobs_of_its_variants():
    """The weave variants' knobs (``weave-variants-render.py``): ``gloss`` is every fibre's
    GGX alpha, ``colours`` replaces the yarns' colours it names; the defaults build the preset
    as it was (its scene fingerprint pinned: renders and partials made before still match)."""
    from vrneural.btf.pt_presets import WEAVE_COLOURS, weave

    def bsdfs(tile):
        return {p.name: p.bsdf for p in tile.parts}

    plain = weave(np.random.default_rng([0, 1]))
    assert plain.fingerprint() == "4e8925106d4bfb0b"  # seed 0's render, before the knobs
    glossy = bsdfs(weave(np.random.default_rng([0, 1]), gloss=0.08))
    assert {n: b.get("alpha") for n, b in glossy.items() if n != "backing"} == dict.fromkeys(
        WEAVE_COLOURS, 0.08
    )
    dark = (0.02, 0.02, 0.025)
    two = bsdfs(weave(np.random.default_rng([0, 1]), colours={"warp_a": dark}))
    base = bsdfs(plain)
    assert two["warp_a"] != base["warp_a"] and two["weft_a"] == base["weft_a"]
    assert weave(np.random.default_rng([0, 1]), colours={"warp_a": dark}).fingerprint() != (
        plain.fingerprint()
    )


def test_a_partial_from_before_the_sampler_option_resumes_only_as_independent(tmp_path):
    """An interrupted render whose header has no `sampler` (written before the option) was
    drawn with independent samples: resuming it with them is allowed, with the new default
    it is the one-line "other settings" error naming the sampler."""
    from vrneural.btf.config import RenderConfig
    from vrneural.btf.format import BtfWriter, check_partial_settings
    from vrneural.config import config_dict
    from vrneural.errors import VrnError

    out = tmp_path / "old.btf"
    gen = config_dict(RenderConfig(preset="weave", res=8, dirs=3, spp=4))
    old = {k: v for k, v in gen.items() if k != "sampler"}
    BtfWriter(out, direction_set(3), direction_set(3), (8, 8), {"generator": old})
    assert (tmp_path / "old.btf.partial").exists()
    check_partial_settings(out, gen | {"sampler": "independent"})
    with pytest.raises(VrnError, match="sampler: 'independent' there, 'multijitter' here"):
        check_partial_settings(out, gen)
