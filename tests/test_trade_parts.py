"""The parts `bench tradeoff` is built from: crops at the headset's density, the supersampled
reference, radiance shared by both eyes, adaptive reuse, the head-turn logs and their errors."""

import dataclasses

import numpy as np
import pytest

from vrneural.bench import poses
from vrneural.bench.supersample import stratified_offsets
from vrneural.runtime.adaptive import AdaptiveState, coverage_slack, object_directions, turned
from vrneural.runtime.camera import PoseLogPath, quat_to_matrix, window_matrix


def test_stratified_offsets_cover_every_cell_once_and_follow_the_seed():
    for spp in (1, 4, 16, 10):
        o = stratified_offsets(spp, 0)
        assert o.shape == (spp, 2) and (o >= -0.5).all() and (o < 0.5).all()
        k = int(np.ceil(np.sqrt(spp)))
        cells = {tuple(c) for c in np.floor((o + 0.5) * k).astype(int)}
        assert len(cells) == spp  # one sample per cell
    assert np.array_equal(stratified_offsets(16, 3), stratified_offsets(16, 3))
    assert not np.array_equal(stratified_offsets(16, 3), stratified_offsets(16, 4))


def test_window_matrix_maps_the_crop_onto_clip_space():
    m = window_matrix((64, 48), (100, 50, 200, 160))
    # the crop's corners in the full image's NDC go to (-1, 1) and (1, -1)
    left, top = 2 * 100 / 200 - 1, 1 - 2 * 50 / 160
    right, bottom = 2 * 164 / 200 - 1, 1 - 2 * 98 / 160
    for (x, y), want in (((left, top), (-1, 1)), ((right, bottom), (1, -1))):
        got = m @ np.array([x, y, 0.5, 1.0])
        np.testing.assert_allclose(got[:2], want, atol=1e-12)
    np.testing.assert_array_equal(window_matrix((8, 8)), np.eye(4))
    j = window_matrix((8, 8), jitter=(0.5, 0.25))  # samples half a pixel right, a quarter down
    np.testing.assert_allclose(j[:2, 3], [-2 * 0.5 / 8, 2 * 0.25 / 8])


def test_turn_logs_turn_at_their_speed_about_the_neck(tmp_path):
    rows = poses.turn_poses(300.0, 30.0, fps=90.0)
    assert (np.diff(rows[:, 0]) > 0).all()
    np.testing.assert_allclose(np.linalg.norm(rows[:, 4:], axis=1), 1, atol=1e-12)
    log = PoseLogPath(poses.write_pose_log(tmp_path / "t.csv", rows))
    assert abs(poses.peak_speed(log) - 300.0) < 1e-3
    # the eyes move sideways by about NECK_FORWARD x the yaw (the neck pivot), not 0
    move = np.linalg.norm(rows[-1, 1:4] - rows[0, 1:4])
    want = 2 * np.hypot(poses.NECK_FORWARD, 0) * np.sin(np.radians(15))
    assert abs(move - want) < 1e-3
    first, n = poses.turn_frames(300.0, 30.0, 0.1, 90.0)
    yaw = [np.degrees(np.arctan2(-quat_to_matrix(q)[0, 2], quat_to_matrix(q)[2, 2]))
           for q in rows[:, 4:]]  # fmt: skip
    assert abs(abs(yaw[first + n] - yaw[first]) - 30.0) < 1e-6 and yaw[0] == yaw[first]


def test_adaptive_reuse_waits_at_rest_and_sweeps_faster_when_things_turn():
    a = AdaptiveState()
    d0 = np.array([[0.0, 0, 1], [0, 1, 0]])
    a.restart(d0)
    one = np.ones(2)
    for _ in range(50):  # nothing moves: never updated again
        assert not a.step(d0, one, 2.0, 16, True).update

    def rot(deg):
        t = np.radians(deg)
        return np.array([[np.sin(t), 0, np.cos(t)], [0, 1, 0]])

    # turning 0.5 deg per frame: after 4 frames a refresh over floor(2 / 0.5) = 4 frames
    slices = [a.step(rot(0.5 * (k + 1)), one, 2.0, 16, True) for k in range(8)]
    upd = [s for s in slices if s.update]
    assert upd[0].period == 4 and [s.phase for s in upd[:4]] == [0, 1, 2, 3]
    # 5 deg per frame, over the budget every frame: full updates (period 1)
    b = AdaptiveState()
    b.restart(d0)
    s = [b.step(rot(5.0 * (k + 1)), one, 2.0, 16, True) for k in range(3)]
    assert all(x.update and x.period == 1 for x in s)
    c = AdaptiveState()  # burst: every refresh is one full update
    c.restart(d0)
    s = [c.step(rot(0.5 * (k + 1)), one, 2.0, 16, False) for k in range(10)]
    assert [x.period for x in s if x.update] == [1, 1]


def test_adaptive_directions_are_in_the_object_frame():
    model = np.eye(4)
    model[:3, 3] = (1.0, 2.0, 3.0)
    rot = np.eye(4)
    rot[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]  # 90 deg about z
    d = object_directions(model, np.zeros(3), (1.0, 2.0, 5.0), np.array([[3.0, 2.0, 3.0]]))
    np.testing.assert_allclose(d, [[0, 0, 1], [1, 0, 0]], atol=1e-12)
    dr = object_directions(model @ rot, np.zeros(3), (1.0, 2.0, 5.0), np.array([[3.0, 2.0, 3.0]]))
    np.testing.assert_allclose(dr, [[0, 0, 1], [0, -1, 0]], atol=1e-12)
    assert turned(d, dr, np.ones(2)) == pytest.approx(90.0)
    assert coverage_slack(0.5) == 1.0 and coverage_slack(1e-6) == 4.0


@pytest.mark.parametrize(
    "argv, want",
    [
        (["--reuse", "auto", "--reuse-budget", "0"], "--reuse-budget = 0.0 is out of range"),
        (["--reuse", "auto", "--reuse-budget", "-2"], "allowed (0, 180] degrees"),
        (["--reuse", "often"], "--reuse = 'often' must be a whole number of frames"),
        (["--eyes", "1", "--radiance", "shared"], "--radiance shared needs --eyes 2"),
    ],
)
def test_run_options_of_the_trade_are_one_line_errors(argv, want, tmp_path):
    from distill_helpers import expect_one_line_error

    expect_one_line_error(["run", "--profile", "tiny", "--out", tmp_path / "o", *argv], want)
    assert not (tmp_path / "o").exists()


@pytest.mark.gpu
def test_a_crop_is_the_window_of_the_whole_image():
    from vrneural.gpu.device import adapter_summary
    from vrneural.runtime.config import RunConfig, resolve
    from vrneural.runtime.renderer import Renderer
    from vrneural.runtime.scene import builtin_scene

    scene = builtin_scene()
    for mode in ("screen", "texture"):
        cfg = RunConfig(profile="tiny", frames=2, mode=mode, eye_res="192x160", reuse=0)
        s = resolve(cfg, scene, adapter_summary())
        r = Renderer(scene, s)
        r.frame(0)
        whole = r.read_eyes()
        c = Renderer(scene, dataclasses.replace(s, eye_res=(64, 48), crop=(80, 60, 192, 160)))
        c.frame(0)
        for w, p in zip(whole, c.read_eyes(), strict=True):
            # the same pixels, rasterised with another projection: equal but for a rounding
            # of the interpolated atlas uv at a few f16 texels (1.2e-4 of 1.0 measured)
            np.testing.assert_allclose(p, w[60:108, 80:144], atol=5e-4)


@pytest.mark.gpu
def test_shared_radiance_halves_the_blocks_and_follows_the_twin():
    """One texture per object, shaded from the eyes' centre with a facing margin of half the
    IPD: about half the blocks of per-eye textures, and the GPU pass equals its numpy twin."""
    from vrneural.gpu.device import adapter_summary
    from vrneural.material import random_material
    from vrneural.runtime import reference as ref
    from vrneural.runtime.config import RunConfig, resolve
    from vrneural.runtime.renderer import Renderer
    from vrneural.runtime.scene import builtin_scene
    from vrneural.runtime.texture_pass import shade_texture_space

    scene = builtin_scene()
    blocks = {}
    for rad in ("per-eye", "shared"):
        s = resolve(RunConfig(profile="tiny", frames=1, radiance=rad), scene, adapter_summary())
        blocks[rad] = Renderer(scene, s).frame(0).blocks_shaded
    assert 0.45 < blocks["shared"] / blocks["per-eye"] < 0.6, blocks
    from runtime_helpers import quad_atlas

    at = quad_atlas(16)
    mat = random_material(2)
    eye, lp, lc = np.float32([0.9, 0.0, 0.05]), np.float32([[0.3, 0.2, 0.9]]), np.ones((1, 3))
    for margin in (0.0, 0.2):  # the eye almost edge-on: the margin decides what is shaded
        want, wc = ref.shade_texture_space(at, mat, np.eye(4), eye, lp, lc, margin=margin)
        got, gc = shade_texture_space(at, mat, np.eye(4), eye, lp, lc, margin=margin)
        np.testing.assert_array_equal(gc, wc)
        w16 = want.astype(np.float16).astype(np.float32)
        assert (np.abs(got - w16) / (np.abs(w16) + 1e-2 * max(w16.max(), 1e-12))).max() <= 2e-3


@pytest.mark.gpu
def test_reference_noise_falls_with_the_sample_count():
    """Two references with different sample positions differ less at 16 samples per pixel
    than at 1: the floor the bench reads every difference against is the sampling noise."""
    from vrneural.bench import trade_scene as ts
    from vrneural.bench.parts import Scored
    from vrneural.bench.supersample import SupersampledReference
    from vrneural.bench.tradeoff import settings_for, variant
    from vrneural.bench.train_configs import TradeoffConfig
    from vrneural.material import random_material
    from vrneural.runtime.profiles import get_profile

    prof = get_profile("quest3")
    c = TradeoffConfig(score=Scored(crop=32)).resolved()
    cond = ts.Condition("rest", "rest", 0.0, 2, [1])
    teacher = random_material(7, "single", 16)
    scene = ts.scene_for(cond, random_material(3), teacher)
    s = settings_for(c, variant(mode="reference"), cond, prof, teacher)
    floors = []
    for spp in (1, 16):
        a, b = (SupersampledReference(scene, s, spp, seed) for seed in (0, 1))
        for r in (a, b):
            ts.track(r.r, cond, c.score.crop, prof.eye_res)
        floors.append(float(np.abs(a.frame(1) - b.frame(1)).mean()))
    assert floors[1] < 0.6 * floors[0], floors


def test_bench_pose_log_errors_are_one_line(tmp_path):
    from distill_helpers import expect_one_line_error

    bad = tmp_path / "bad.csv"
    bad.write_text("0,0,1.3,1,0,0,0,1\n0.1,0,1.3,1,0,0,0,1\n0.05,0,1.3,1,0,0,0,1\n")
    out = tmp_path / "o"
    argv = ["bench", "tradeoff", "--quick", "--poses", bad, "--out", out]
    expect_one_line_error(argv, "bad.csv:3", "time is not after the previous row's")
    bad.write_text("0,0,1.3,1,0,0,0,2\n")
    expect_one_line_error(argv, "bad.csv:1", "quaternion of length 2")
    bad.write_text("0,0,1.3,1,0,0,1\n")
    expect_one_line_error(argv, "bad.csv:1", "expected 8 columns, got 7")
    assert not out.exists()
