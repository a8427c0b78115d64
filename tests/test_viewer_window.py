"""`vrneural view` in a real window: Xvfb (started here), glfw, lavapipe presenting to the X11
surface. Key and mouse events go in through the canvas's event API; what the window shows is
read back from its surface texture and compared with an offscreen renderer's frame.

Outside CI these tests skip when Xvfb or glfw is missing (saying which); under CI=true they
fail instead (.ci/run installs both through scripts/setup.sh).
"""

import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
from conftest import CI

pytestmark = pytest.mark.gpu


@pytest.fixture(scope="module")
def display():
    from vrneural.viewer.xvfb import virtual_display

    missing = []
    if shutil.which("Xvfb") is None:
        missing.append("Xvfb (apt-get install xvfb)")
    try:
        import glfw  # noqa: F401
        import rendercanvas  # noqa: F401
    except ImportError as e:
        missing.append(f"glfw / rendercanvas ({e}; pip install 'vrneural[view]')")
    if missing:
        msg = "the window tests need " + " and ".join(missing)
        if CI:
            pytest.fail(f"CI=true: {msg}")
        pytest.skip(msg)
    with virtual_display() as name:  # (it closes glfw's connection before the server goes)
        yield name


def key(k, kind="key_down"):
    return {"event_type": kind, "key": k, "modifiers": ()}


def pointer(kind, x, y, buttons, button=0):
    return {
        "event_type": kind,
        "x": float(x),
        "y": float(y),
        "button": button,
        "buttons": tuple(buttons),
        "modifiers": (),
        "ntouches": 0,
        "touches": {},
    }


def drag(button, x0, y0, x1, y1):
    return [
        pointer("pointer_down", x0, y0, (button,), button),
        pointer("pointer_move", x1, y1, (button,)),
        pointer("pointer_up", x1, y1, (), button),
    ]


def run_script(view, script):
    """Run ``view`` in its window; after frame k, submit ``script[k]`` (events) to its canvas."""
    seen = []

    def hook(v, rec):
        seen.append(rec)
        for ev in script.get(rec.frame, []):
            v.canvas.submit_event(ev)

    view.after_frame(hook)
    view.keep_shown = True
    view.run()
    return seen


def test_window_shows_the_offscreen_frame_bit_for_bit_after_keys_and_mouse(display, tmp_path):
    from vrneural.runtime.output import tonemap
    from vrneural.viewer import View
    from vrneural.viewer.present import compose

    v = View(
        profile="tiny",
        eyes=2,
        eye_res="96x80",
        frames=12,
        shots=str(tmp_path / "shots"),
        record=str(tmp_path / "view.mp4"),
    )
    pose0 = v.pose()
    light0 = v.lights[1].at(0.0)
    script = {
        1: [key("F2"), key("]"), key("b")],  # HUD off, N 4 -> 5, staggered -> burst
        3: drag(1, 40, 40, 70, 52),  # orbit
        5: [key("l"), *drag(2, 60, 30, 40, 50)],  # select light 2, drag it
        7: [key("2")],  # light 2 off
        9: [key("p")],  # screenshot of frame 10
    }
    recs = run_script(v, script)
    assert [r.frame for r in recs] == list(range(12))  # --frames: closed after 12
    # each key changes the very next frame: nothing queued behind it
    assert [a for a, *_ in recs[2].inputs] == ["hud", "reuse_up", "schedule"]
    assert recs[1].settings["hud"] and not recs[2].settings["hud"]
    assert (recs[1].settings["reuse"], recs[2].settings["reuse"]) == (4, 5)
    assert (recs[1].settings["schedule"], recs[2].settings["schedule"]) == ("staggered", "burst")
    assert recs[7].settings["lights_on"] == [True, True]
    assert recs[8].settings["lights_on"] == [True, False]
    # the mouse moved the camera (left drag) and light 2 (right drag)
    assert not np.allclose(v.pose()[1], pose0[1])
    assert np.linalg.norm(v.lights[1].at(0.0) - light0) > 0.01
    assert v.lights[1].motion == "none"
    # the window's surface, read back, is the offscreen renderer's frame, bit for bit
    shown = v.shown
    assert shown.shape == (80, 192, 3) and shown.std() > 5
    np.testing.assert_array_equal(shown, compose(v.replay_offscreen()))
    # P: PNG = what the window showed at frame 10, EXR = its HDR, JSON = the settings
    import imageio.v3 as iio
    from OpenImageIO import ImageInput

    names = sorted(p.name for p in (tmp_path / "shots").iterdir())
    assert names == ["shot-0001.exr", "shot-0001.json", "shot-0001.png"]
    png = iio.imread(tmp_path / "shots" / "shot-0001.png")
    inp = ImageInput.open(str(tmp_path / "shots" / "shot-0001.exr"))
    exr = inp.read_image("float")
    inp.close()
    np.testing.assert_array_equal(png, tonemap(exr))
    meta = json.loads((tmp_path / "shots" / "shot-0001.json").read_text())
    assert meta["frame"] == 10 and meta["knobs"]["reuse"] == 5
    assert meta["lights"][1]["intensity"] == 0.0  # switched off
    # --record: every frame shown, at the window's size
    import imageio.v2 as iio2

    with iio2.get_reader(str(tmp_path / "view.mp4")) as rd:
        n = sum(1 for _ in rd)
        assert n == 12 and rd.get_meta_data()["size"] == (192, 80)


def test_shared_radiance_and_adaptive_reuse_keys(display):
    """G shares one radiance texture between the eyes (about half the blocks shaded), U turns
    adaptive reuse on (nothing shaded while nothing moves); the window still shows the
    offscreen renderer's frames bit for bit."""
    from vrneural.viewer import View
    from vrneural.viewer.present import compose

    v = View(profile="tiny", eyes=2, eye_res="96x80", frames=8)
    recs = run_script(v, {1: [key("F2"), key("g")], 4: [key("u"), key(" ")]})  # HUD off; pause
    assert (recs[1].settings["radiance"], recs[2].settings["radiance"]) == ("per-eye", "shared")
    assert not recs[4].settings["adaptive"] and recs[5].settings["adaptive"]
    full = [r.stats.blocks_shaded for r in recs[:3]]  # frame 0 and the shared one: full updates
    assert 0.45 < full[2] / full[0] < 0.6, full
    # adaptive: one full refresh when switched on, then nothing while the scene stands still
    assert recs[5].stats.blocks_shaded > 0
    assert [r.stats.blocks_shaded for r in recs[6:]] == [0, 0]
    np.testing.assert_array_equal(v.shown, compose(v.replay_offscreen()))


def test_mode_keys_head_path_and_fly(display, tmp_path):
    """M cycles texture -> screen -> reference; a pack without a teacher has no reference
    mode: the key is refused with `run`'s message on the HUD, and the mode goes back. H
    follows the scene's pose log; W flies forward while held."""
    from vrneural.runtime.camera import PoseLogPath
    from vrneural.runtime.scene import bundled_path
    from vrneural.viewer import View
    from vrneural.viewer.present import compose

    (tmp_path / "poses.csv").write_text(
        "t,x,y,z,qx,qy,qz,qw\n0,0,1.0,1.2,0,0,0,1\n1,0.3,1.1,1.0,0,0.0998,0,0.995\n"
    )
    (tmp_path / "s.toml").write_text(
        f"""
[head]
path = "poses.csv"
[[objects]]
mesh = "sphere"
position = [0.0, 1.0, -0.3]
[objects.material]
pack = "{bundled_path("leather.vrnm")}"
[[lights]]
position = [1, 2, 1]
intensity = 3.0
"""
    )
    v = View(str(tmp_path / "s.toml"), profile="tiny", eye_res="64x64", frames=12, hud=False)
    poses = {}

    def pose_of(view, rec):
        poses[rec.frame] = (view.pose(), view.t)

    v.after_frame(pose_of)
    script = {0: [key("m")], 2: [key("m")], 5: [key("h")], 7: [key("w")], 9: [key("w", "key_up")]}
    recs = run_script(v, script)
    modes = [r.settings["mode"] for r in recs]
    assert modes == ["texture"] + ["screen"] * 11
    assert "--mode reference needs a teacher" in v.status[0] and v.status[2]
    cams = [r.settings["camera"] for r in recs]
    assert cams[5] == "orbit" and cams[6] == "head path" and cams[8] == "orbit"
    (pos6, rot6), t6 = poses[6]
    want_pos, want_rot = PoseLogPath(tmp_path / "poses.csv").pose(t6)
    np.testing.assert_allclose(pos6, want_pos)
    np.testing.assert_allclose(rot6, want_rot)
    (p8, r8), _ = poses[8]
    (p10, _), _ = poses[10]
    step = p10 - p8  # W held for frames 9 and 10: straight ahead
    assert np.linalg.norm(step) > 1e-4 and np.dot(step, -r8[:, 2]) > 0.999 * np.linalg.norm(step)
    np.testing.assert_array_equal(v.shown, compose(v.replay_offscreen()))


def test_split_flip_shows_the_bench_flip_map(display):
    """Split view, FLIP: the right half shows HDR-FLIP of texture space against the reference
    (flip-evaluator in a worker process, as the bench computes it), left half texture space."""
    pytest.importorskip("flip_evaluator")
    from vrneural.gpu.readback import read_texture
    from vrneural.scoring.metrics import flip_hdr, pixels_per_degree
    from vrneural.viewer import View
    from vrneural.viewer.present import compose

    v = View(profile="tiny", eye_res="64x64", split="flip", split_every=1000, hud=False)
    got = {}

    def hook(view, rec):
        if view.flip_mean is not None and "map" not in got:
            got["map"] = read_texture(view.flip_tex)
            got["frame"] = rec.frame
        if ("map" in got and rec.frame > got["frame"]) or rec.frame > 400:
            view.close()

    v.after_frame(hook)
    v.keep_shown = True
    v.run()
    assert "map" in got, "no FLIP map within 400 frames"
    ref = v.renderers.get(v.live, "reference")[0].read_eyes()[0]
    test = v.replay_offscreen()[0]
    want = flip_hdr(ref, test, pixels_per_degree(64, v.r.s.fov_y))
    # tiny shades the built-in scene's two still lights and the camera stands still: once the
    # staggered updates went round, every frame is this one (and split_every keeps the reference)
    assert abs(v.flip_mean - want) < 1e-6
    np.testing.assert_array_equal(v.shown, compose([test], got["map"] / 255.0, 32, True))


def _cli(args, env=None, timeout=300):
    e = {**os.environ, **(env or {})}
    return subprocess.run(
        [sys.executable, "-m", "vrneural", "view", *args],
        capture_output=True,
        text=True,
        env=e,
        timeout=timeout,
    )


def test_cli_runs_and_its_errors_are_one_line(display, tmp_path):
    r = _cli(["--profile", "tiny", "--frames", "3", "--no-hud"])
    assert r.returncode == 0, r.stderr
    assert "view      3 frames" in r.stdout
    # no display at all
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    r = subprocess.run(
        [sys.executable, "-m", "vrneural", "view", "--frames", "1"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert "no display to open a window on" in r.stderr and "xvfb-run" in r.stderr
    # glfw's shared library missing
    r = _cli(["--frames", "1"], {"PYGLFW_LIBRARY": str(tmp_path / "libglfw.so")})
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert "glfw's shared library not found" in r.stderr
    # a display that is not there
    r = _cli(["--frames", "1"], {"DISPLAY": ":987"})
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert "cannot open the display ':987' (X11: Failed to open display :987)" in r.stderr
    # an unknown key binding
    (tmp_path / "k.toml").write_text('[keys]\nteleport = "t"\n')
    r = _cli(["--keys", str(tmp_path / "k.toml"), "--frames", "1"])
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert "k.toml: keys.teleport is not a known action" in r.stderr
    # a scene that fails to load: run's message, word for word
    (tmp_path / "bad.toml").write_text('[[objects]]\nmesh = "plane"\nscale = -1\n')
    r = _cli([str(tmp_path / "bad.toml"), "--frames", "1"])
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "vrneural",
            "run",
            str(tmp_path / "bad.toml"),
            "--out",
            str(tmp_path / "o"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == run.returncode == 2
    assert r.stderr.replace("vrneural view:", "vrneural run:") == run.stderr
    assert "bad.toml: objects[0].scale = -1 is out of range" in r.stderr


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_ctrl_c_and_sigterm_close_between_frames_and_keep_the_video(display, tmp_path, sig):
    import signal
    import time

    out = tmp_path / "v.mp4"
    p = subprocess.Popen(
        [sys.executable, "-m", "vrneural", "view", "--profile", "tiny", "--record", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    tmp = tmp_path / ".v.tmp.mp4"  # the video being written: there once the window is
    end = time.monotonic() + 120
    while time.monotonic() < end and not tmp.exists():
        time.sleep(0.1)
    time.sleep(1.5)  # some frames
    p.send_signal(getattr(signal, sig))
    _, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert err.strip().splitlines() == [f"vrneural view: interrupted (kept {out})"]
    import imageio.v2 as iio2

    with iio2.get_reader(str(out)) as rd:
        assert sum(1 for _ in rd) >= 2


def test_hud_leaves_a_small_window_most_of_its_image(display):
    """A 192 x 80 window: the HUD keeps to its top half (two lines at least: its first line and
    a count of the rest), and every pixel below is the offscreen renderer's frame."""
    from vrneural.viewer import View
    from vrneural.viewer.present import compose

    v = View(profile="tiny", eyes=2, eye_res="96x80", frames=3)
    run_script(v, {})
    changed = (v.shown != compose(v.replay_offscreen())).any(-1)
    rows = np.nonzero(changed.any(1))[0]
    from vrneural.viewer.hud import LINE_PX, PAD

    assert rows.size and rows.max() < 8 + max(80 // 2, 2 * LINE_PX + 2 * PAD), rows


def test_a_multisampled_view_shows_its_offscreen_frame(display):
    """`vrneural view --msaa 4 --depth-clear slices` (the run options pass through): the
    window shows the resolved, multisampled frame (HUD off), bit for bit the offscreen
    renderer's with the same settings, past a depth-slice cycle."""
    from vrneural.viewer import View
    from vrneural.viewer.present import compose

    v = View(profile="tiny", eyes=2, eye_res="96x80", frames=6, msaa=4, depth_clear="slices")
    recs = run_script(v, {0: [key("F2")]})
    assert [r.frame for r in recs] == list(range(6)) and not recs[-1].settings["hud"]
    assert v.r.eye_t[0].samples == 4 and v.r.depth_clear == "slices"
    shown = v.shown
    assert shown.shape == (80, 192, 3) and shown.std() > 5
    np.testing.assert_array_equal(shown, compose(v.replay_offscreen()))
