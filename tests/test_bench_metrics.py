"""Trade-off metrics (SSIM, PSNR, HDR-FLIP, Pareto) and bench option parsing: no GPU."""

import numpy as np
import pytest

from vrneural.bench.report import stats
from vrneural.bench.timing import frames_for
from vrneural.bench.tradeoff_report import pareto
from vrneural.config import int_items
from vrneural.errors import VrnError
from vrneural.scoring import metrics


def test_ssim_identical_is_one(rng):
    a = rng.random((40, 50, 3))
    assert metrics.ssim(a, a) == pytest.approx(1.0, abs=1e-12)


def test_ssim_constant_images_match_the_closed_form():
    # constant images: zero variances and covariance, so SSIM = (2ab + C1) / (a^2 + b^2 + C1)
    a, b = 0.3, 0.7
    c1 = (metrics.SSIM_K1 * 1.0) ** 2
    want = (2 * a * b + c1) / (a * a + b * b + c1)
    got = metrics.ssim(np.full((32, 32), a), np.full((32, 32), b))
    assert got == pytest.approx(want, rel=1e-9)


def test_ssim_symmetric_bounded_and_decreasing_with_noise(rng):
    a = rng.random((48, 48))
    b1 = np.clip(a + rng.normal(0, 0.05, a.shape), 0, 1)
    b2 = np.clip(a + rng.normal(0, 0.2, a.shape), 0, 1)
    s1, s2 = metrics.ssim(a, b1), metrics.ssim(a, b2)
    assert metrics.ssim(b1, a) == pytest.approx(s1, abs=1e-12)
    assert -1 <= s2 < s1 < 1


def test_ssim_shape_mismatch_raises():
    with pytest.raises(ValueError):
        metrics.ssim(np.zeros((8, 8)), np.zeros((8, 9)))


def test_psnr_known_value_and_identity():
    a = np.zeros((4, 4, 3))
    assert metrics.psnr(a, a + 0.1) == pytest.approx(20.0, abs=1e-9)  # MSE 0.01, peak 1
    assert metrics.psnr(a, a) == 100.0


def test_display_matches_runtime_tonemap(rng):
    from vrneural.runtime.output import tonemap

    hdr = rng.random((8, 8, 4)).astype(np.float32) * 5
    d = metrics.display(hdr)
    assert d.shape == (8, 8, 3) and d.min() >= 0 and d.max() <= 1
    # tonemap is display() rounded to 8 bits
    assert np.abs(d * 255 - tonemap(hdr)).max() <= 0.5 + 1e-6


def test_flip_hdr_zero_for_identical_and_in_unit_range(rng):
    a = (rng.random((32, 32, 3)) * 2).astype(np.float32)
    assert metrics.flip_hdr(a, a, 23.0) == pytest.approx(0.0, abs=1e-6)
    f = metrics.flip_hdr(a, a * 0.3, 23.0)
    assert 0.0 < f <= 1.0


def test_pixels_per_degree_quest3():
    from vrneural.runtime.profiles import get_profile

    p = get_profile("quest3")
    assert metrics.pixels_per_degree(p.eye_res[1], p.fov_y) == pytest.approx(23.0)


def test_pareto_front():
    pts = [(1.0, 0.5), (2.0, 0.3), (3.0, 0.4), (0.5, 0.9), (2.0, 0.3)]
    # (3, 0.4) is dominated by (2, 0.3); the duplicate (2, 0.3) points do not dominate each other
    assert pareto(pts, lower_better=True) == [0, 1, 3, 4]
    assert pareto([(1, 10.0), (2, 5.0)], lower_better=False) == [0]


def test_frames_for_covers_whole_cycles():
    assert frames_for(0, 1, 3) == 3
    assert frames_for(4, 1, 3) == 5
    assert frames_for(6, 2, 3) == 14
    assert frames_for(2, 1, 4) == 6


def test_int_list_errors_are_one_line():
    assert int_items("--reuse", "0, 2,4", 0, 9) == (0, 2, 4) == int_items("--reuse", [0, 2, 4])
    with pytest.raises(VrnError, match="lists 2 twice; each value once"):
        int_items("--lights", "2,2", 1, 8)  # measured twice, reported as two rows before
    with pytest.raises(VrnError, match="has an empty item"):
        int_items("--texture-res", "128,,256", 8, 8192)
    for bad, word in (("a,b", "integers"), ("3,99", "out of range"), ("", "empty"), ((), "empty")):
        with pytest.raises(VrnError, match=word):
            int_items("--reuse", bad, 0, 9)
    with pytest.raises(VrnError, match="even"):
        int_items("--texture-res", "801", 2, 8192, even=True)


def test_list_fields_hold_tuples_parsed_when_the_config_is_built():
    """A list option is a tuple in the config, from the command line's comma-separated text
    or from any sequence in Python, checked once when the config is built."""
    from vrneural.bench.configs import FramesConfig, LightsConfig
    from vrneural.bench.train_configs import TradeoffConfig
    from vrneural.cli import build_parser
    from vrneural.config import config_from_args

    args = build_parser().parse_args(["bench", "frames", "--reuse", "0, 4", "--schedules", "burst"])
    c = config_from_args(FramesConfig, args)
    assert (c.reuse, c.schedules, c.texture_res) == ((0, 4), ("burst",), None)
    assert FramesConfig(texture_res=[800, 1200]).texture_res == (800, 1200)
    assert FramesConfig().resolved().texture_res == (800, 1200, 1600, 2000)
    with pytest.raises(VrnError, match=r"^--lights = '0,9': 0 is out of range; allowed \[1, "):
        LightsConfig(lights=(0, 9))
    with pytest.raises(VrnError, match=r"--schedules = 'Burst' is not allowed"):
        FramesConfig(schedules=("Burst",))
    t = TradeoffConfig(speeds="0,250.5", poses="", distances=[1])
    assert (t.speeds, t.poses, t.distances) == ((0.0, 250.5), (), (1.0,))
    with pytest.raises(VrnError, match=r"--presets = 'leather,' has an empty item"):
        TradeoffConfig(presets="leather,")


def test_stats_percentiles():
    s = stats([1.0, 2.0, 3.0, 4.0])
    assert s["median"] == 2.5 and s["max"] == 4.0 and s["p99"] <= 4.0


def test_quick_keeps_explicit_flags():
    from vrneural.bench.configs import FramesConfig
    from vrneural.bench.train_configs import QualityConfig

    c = FramesConfig(quick=True, texture_res="64").resolved()
    assert c.texture_res == (64,) and c.reuse == FramesConfig.QUICK.reuse == (0, 2, 4)  # given
    q = QualityConfig(quick=True, epochs=3).resolved()
    assert (q.epochs, q.res, q.teacher_epochs) == (3, 16, 2)
    assert FramesConfig(texture_res="64").resolved().reuse == FramesConfig().resolved().reuse


def test_quick_keeps_explicit_flags_even_at_their_default_value():
    from vrneural.bench.train_configs import QualityConfig
    from vrneural.cli import build_parser
    from vrneural.config import config_from_args

    default = QualityConfig().resolved().epochs
    argv = ["bench", "quality", "--quick", "--epochs", str(default)]
    q = config_from_args(QualityConfig, build_parser().parse_args(argv)).resolved()
    assert q.epochs == default and q.teacher_epochs == 2  # typed: kept; not typed: --quick
    args = build_parser().parse_args(argv[:3])  # --epochs not typed
    assert config_from_args(QualityConfig, args).resolved().epochs == 2


def test_flip_of_both_eyes_leaves_the_gap_out():
    """One FLIP evaluation for both eyes side by side: the blank gap between them is not
    counted, so an error in one eye is halved by the other's exact pixels, no more."""
    from vrneural.scoring.metrics import flip_hdr_eyes

    rng = np.random.default_rng(0)
    a = rng.uniform(0.05, 0.5, (2, 32, 40, 3)).astype(np.float32)
    assert flip_hdr_eyes(a, a, 23.0) == 0.0
    b = a.copy()
    b[1] *= 1.5  # only the right eye differs
    both = flip_hdr_eyes(a, b, 23.0)
    left_only = flip_hdr_eyes(a[:1], b[:1], 23.0)
    assert left_only == 0.0 and 0 < both < 1
    c = b.copy()
    c[0] *= 1.5  # now both differ: about twice the error
    assert 1.5 < flip_hdr_eyes(a, c, 23.0) / both < 2.5


def test_a_bench_sets_its_own_defaults_for_a_shared_part(capsys):
    """bench distance trains its packs 24 epochs (DistanceConfig.DEFAULTS) where bench tradeoff,
    sharing the PackBudget part, keeps 4; --quick and flags given still win, and --help and
    the CLI reference show the bench's own default."""
    from vrneural.bench.train_configs import DistanceConfig, TradeoffConfig
    from vrneural.cli import build_parser, main
    from vrneural.config import config_from_args

    d = DistanceConfig().resolved().budget
    assert (d.teacher_epochs, d.epochs, d.btf_res) == (24, 24, 32)
    assert TradeoffConfig().resolved().budget.epochs == 4
    # the distance bench's reference has 64 samples per pixel (minified material), tradeoff 16
    assert DistanceConfig().resolved().score.spp == 64
    assert TradeoffConfig().resolved().score.spp == 16
    q = DistanceConfig(quick=True).resolved().budget
    assert (q.teacher_epochs, q.epochs) == (1, 1)
    args = build_parser().parse_args(["bench", "distance", "--epochs", "7"])
    given = config_from_args(DistanceConfig, args).resolved().budget
    assert (given.epochs, given.teacher_epochs) == (7, 24)
    with pytest.raises(SystemExit):
        main(["bench", "distance", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--epochs EPOCHS epochs of each small network (default: 24)" in text
    with pytest.raises(SystemExit):
        main(["bench", "tradeoff", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--epochs EPOCHS epochs of each small network (default: 4)" in text


def test_distance_texel_size_is_the_materials_on_the_sphere():
    """--texel-mm is the size of a material texel on the scaled sphere at tiling 1: measured on
    the built-in sphere mesh near its equator (UV unit one radian), and the texels under a
    pixel grow with distance and tiling as the pixel's footprint does."""
    from vrneural.bench.distance import base_tiling, conditions, texels_per_pixel
    from vrneural.bench.train_configs import DistanceConfig
    from vrneural.runtime.assets import get_mesh

    c = DistanceConfig(texel_mm=1.0).resolved()
    m = get_mesh("sphere")
    p = m.positions * (c.size / float(np.ptp(m.positions, axis=0).max()))
    f = m.faces
    e3 = p[f[:, 1]] - p[f[:, 0]]
    duv = (m.uv[f[:, 1]] - m.uv[f[:, 0]]) * base_tiling(c) * c.budget.btf_res  # in texels
    eq = (np.abs(p[f[:, 0], 1]) < 0.05 * c.size) & (np.abs(duv[:, 1]) > 1e-3)
    eq &= np.abs(duv[:, 0]) < 1e-3 * np.abs(duv[:, 1])  # edges along a meridian
    mm = np.linalg.norm(e3[eq], axis=1) / np.abs(duv[eq, 1]) * 1e3
    assert eq.sum() > 10 and np.allclose(mm, 1.0, rtol=0.02), (eq.sum(), mm)
    ppd = 23.0
    base = base_tiling(c)
    near, far = (texels_per_pixel(c, d, base, ppd) for d in (1.0, 10.0))
    assert 0.4 < near < 0.8 and abs(far / near - 9.75 / 0.75) < 1e-6
    assert abs(texels_per_pixel(c, 1.0, 8 * base, ppd) / near - 8) < 1e-9
    conds = {x.name: x for x in conditions(c)}
    assert conds["tiling 8"].tiling == 8 * conds["1 m"].tiling == 8 * base_tiling(c)
    old = DistanceConfig(texel_mm=0.25 / 32 * 1e3).resolved()  # the scale before --texel-mm
    assert abs(base_tiling(old) - 1.0) < 1e-12


def test_distance_variants_are_chosen_by_key(capsys):
    """--variants names variants by the keys its help lists (every variant's, in the table's
    order); a key that names none is a one-line error listing them."""
    from vrneural.bench.distance import VARIANTS, check, selected, variant_key
    from vrneural.bench.train_configs import DistanceConfig
    from vrneural.cli import main
    from vrneural.errors import VrnError

    keys = [variant_key(n) for n in VARIANTS]
    assert len(set(keys)) == len(keys) and keys[0] == "all-off" and "all-on+4x-msaa" in keys
    with pytest.raises(SystemExit):
        main(["bench", "distance", "--help"])
    text = "".join(capsys.readouterr().out.split())  # the help's list, unwrapped
    assert ",".join(keys) in text
    assert selected(DistanceConfig().resolved()) == list(VARIANTS)
    c = DistanceConfig(variants=("taps", "all-off")).resolved()
    assert selected(c) == ["all off", "taps"]
    with pytest.raises(VrnError, match=r"^--variants: 'tap' is not a variant; choose from all-off"):
        selected(DistanceConfig(variants=("tap",)).resolved())
    with pytest.raises(VrnError, match=r"^--taps = 1 is out of range; allowed \[2, 8\]$"):
        check(DistanceConfig(taps=1).resolved())
