"""`vrneural view` without a GPU or a display: key bindings, the camera, the tonemap table,
configs and their one-line errors, screenshot naming, the FLIP worker's stream format."""

import io
import math

import numpy as np
import pytest

from vrneural.errors import VrnError

# ----- keys


def test_default_keys_cover_every_action_once():
    from vrneural.viewer.keys import ACTIONS, KeyMap

    km = KeyMap()
    assert set(km.keys) == set(ACTIONS)
    assert len(set(km.keys.values())) == len(ACTIONS)  # no key does two things
    assert km.action("M") == km.action("m") == "mode"  # letters with or without Shift
    assert km.action(" ") == "pause" and km.action("F1") == "help"
    assert km.action("x") is None
    assert len(km.help_lines()) == len(ACTIONS) + 2  # F1 lists every key, then the mouse


def test_key_file_remaps_and_its_errors_name_file_and_field(tmp_path):
    from vrneural.viewer.keys import load_keys

    p = tmp_path / "keys.toml"
    p.write_text('[keys]\nscreenshot = "F12"\nmode = "Space"\npause = "Tab"\n')
    km = load_keys(p)
    assert km.action("F12") == "screenshot" and km.action(" ") == "mode"
    assert km.action("p") is None  # the old key is free
    for text, needle in [
        ('[keys]\nzoom = "z"\n', "keys.toml: keys.zoom is not a known action (known: help"),
        ('[keys]\nmode = "Ctrl+M"\n', "keys.toml: keys.mode = 'Ctrl+M' is not a key"),
        ("[keys]\nmode = 3\n", "keys.toml: keys.mode = 3 must be a key name"),
        ('[keys]\nmode = "p"\n', "keys.toml: keys.mode = 'p' is already the key of screenshot"),
        ('[keyz]\nmode = "p"\n', "keys.toml: keyz is not a known table"),
        ("[keys\n", "keys.toml: invalid TOML"),
    ]:
        p.write_text(text)
        with pytest.raises(VrnError) as e:
            load_keys(p)
        assert needle in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(VrnError, match="key file not found"):
        load_keys(tmp_path / "nope.toml")


# ----- camera


def test_yaw_pitch_inverts_forward_and_orbit_keeps_the_target():
    from vrneural.viewer.camera import ViewCamera, forward_of, yaw_pitch

    for yaw, pitch in [(0.3, -0.2), (-2.0, 0.7), (3.0, 0.0)]:
        y, p = yaw_pitch(forward_of(yaw, pitch))
        assert math.isclose(math.cos(y), math.cos(yaw), abs_tol=1e-12)
        assert math.isclose(math.sin(y), math.sin(yaw), abs_tol=1e-12)
        assert math.isclose(p, pitch, abs_tol=1e-12)
    cam = ViewCamera((0, 1.2, 1.0), (0.1, -0.4, -1.0), 1.3)
    target = cam.target.copy()
    cam.drag(40, -25)
    np.testing.assert_allclose(cam.target, target, atol=1e-12)
    assert math.isclose(np.linalg.norm(cam.position - target), 1.3)
    cam.wheel(-100)  # one notch towards the scene
    assert math.isclose(cam.distance, 1.3 / 1.1) and np.allclose(cam.target, target)
    pos, rot = cam.pose()
    np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(-rot[:, 2], cam.forward, atol=1e-12)
    cam.mode = "fly"
    cam.move(0, 0, 1, 0.5)  # half a second forward at speed 0.6 m/s
    np.testing.assert_allclose(cam.position, pos + 0.3 * cam.forward, atol=1e-12)


def test_a_dragged_light_follows_the_pointer_in_the_image():
    from vrneural.runtime.camera import look_rotation
    from vrneural.viewer.camera import drag_point, project

    pose = (np.array([0.0, 1.0, 2.0]), look_rotation(np.array([0.2, -0.3, -1.0])))
    size, fov = (320, 240), 70.0
    light = np.array([0.3, 1.4, -0.5])
    x, y = project(light, pose, fov, 320 / 240, size)
    moved = drag_point(light, pose, fov, 25.0, -12.0, size[1])
    x2, y2 = project(moved, pose, fov, 320 / 240, size)
    assert math.isclose(x2 - x, 25.0, abs_tol=1e-9) and math.isclose(y2 - y, -12.0, abs_tol=1e-9)
    behind = pose[0] + pose[1][:, 2]  # behind the camera: not projected, not moved
    assert project(behind, pose, fov, 1.0, size) is None
    np.testing.assert_array_equal(drag_point(behind, pose, fov, 5, 5, 240), behind)


def test_quaternion_of_a_pose_matches_the_pose_log_convention():
    from vrneural.runtime.camera import look_rotation, quat_to_matrix
    from vrneural.viewer.shot import quaternion

    for f in ([0.3, -0.2, -1.0], [-1.0, 0.5, 0.2], [0.0, -0.9, 0.1]):
        rot = look_rotation(np.array(f))
        np.testing.assert_allclose(quat_to_matrix(np.array(quaternion(rot))), rot, atol=1e-12)


# ----- the tonemap table and the layout


def test_tonemap_table_is_output_tonemap_for_every_f16_value():
    from vrneural.runtime.output import tonemap
    from vrneural.viewer.present import tonemap_lut

    lut = tonemap_lut()
    assert lut.shape == (65536,) and lut.max() == 255
    rng = np.random.default_rng(3)
    bits = rng.integers(0, 65536, size=(40, 30, 3)).astype(np.uint16)
    hdr = bits.view(np.float16).astype(np.float32)
    with np.errstate(all="ignore"):  # NaN / infinity patterns among the bits
        want = tonemap(hdr)
    np.testing.assert_array_equal(lut[bits], want)
    assert lut[np.float16(np.nan).view(np.uint16)] == 0  # as nan_to_num maps it
    assert lut[np.float16(-2.0).view(np.uint16)] == 0


def test_fit_keeps_whole_scales_and_centres():
    from vrneural.viewer.present import fit

    assert fit((96, 96), (96, 96)) == (0.0, 0.0, 1.0)
    assert fit((400, 200), (96, 96)) == (104.0, 4.0, 2.0)  # 2x fits, 2.08 does not: whole
    x0, y0, s = fit((960, 540), (1920, 1024))
    assert (x0, y0, s) == (0.0, 14.0, 0.5)  # smaller than the image: any scale


# ----- configs


def test_view_defaults_and_run_only_options_are_refused():
    from vrneural.runtime.config import RunConfig
    from vrneural.viewer.startup import configs

    cfg, vc = configs(None, None, {"mode": "screen", "split": "flip", "frames": 5})
    assert (cfg.profile, cfg.eyes, cfg.mode) == ("preview", 1, "screen")
    assert (vc.split, vc.frames) == ("flip", 5)
    cfg, _ = configs(RunConfig(eyes=2, profile="tiny"))  # chosen in code: kept
    assert (cfg.profile, cfg.eyes) == ("tiny", 2)
    with pytest.raises(VrnError, match="video is an option of `vrneural run`"):
        configs(None, None, {"video": False})
    with pytest.raises(VrnError, match="unknown option 'zoom'"):
        configs(None, None, {"zoom": 2})


def test_view_config_errors(tmp_path):
    from vrneural.viewer.config import ViewConfig, check_view_config

    existing = tmp_path / "v.mp4"
    existing.write_bytes(b"x")
    for vc, needle in [
        (ViewConfig(frames=-1), "--frames = -1 is out of range"),
        (ViewConfig(record=str(tmp_path / "v.avi")), "must name an .mp4 file"),
        (ViewConfig(record=str(existing)), "output exists; pass --force"),
        (ViewConfig(window="12x12"), "--window = '12x12' is out of range"),
        (ViewConfig(keys=str(tmp_path / "k.toml")), "key file not found"),
        (ViewConfig(shots=str(existing)), "is a file; name a directory"),
    ]:
        with pytest.raises(VrnError) as e:
            check_view_config(vc)
        assert needle in str(e.value)
    check_view_config(ViewConfig(record=str(existing), force=True))


def test_no_display_is_one_line_with_the_fix():
    from vrneural.viewer.backends import check_display

    with pytest.raises(VrnError) as e:
        check_display({})
    msg = str(e.value)
    assert "neither DISPLAY nor WAYLAND_DISPLAY is set" in msg and "xvfb-run -a" in msg
    check_display({"DISPLAY": ":0"})
    check_display({"WAYLAND_DISPLAY": "wayland-0"})


# ----- outputs


def test_screenshots_never_replace_earlier_ones(tmp_path):
    from vrneural.viewer.outputs import claim_shot

    (tmp_path / "shot-0002.png").write_bytes(b"mine")
    a = claim_shot(tmp_path)
    b = claim_shot(tmp_path)
    assert (a.name, b.name) == ("shot-0001", "shot-0003")  # 0002's image is someone's
    assert (tmp_path / "shot-0002.png").read_bytes() == b"mine"
    (tmp_path / "shot-0009.json").write_text("{}")
    assert claim_shot(tmp_path).name == "shot-0010"


def test_flip_worker_stream_round_trip():
    from vrneural.viewer.outputs import read_array, write_array

    f = io.BytesIO()
    arrays = [np.float64(2.5), np.arange(24, dtype=np.float32).reshape(2, 3, 4)[:, ::2]]
    for a in arrays:
        write_array(f, a)
    f.seek(0)
    for a in arrays:
        b = read_array(f)
        assert b.dtype == np.asarray(a).dtype and b.shape == np.shape(a)
        np.testing.assert_array_equal(b, a)
    assert read_array(f) is None


def test_hud_panel_keeps_to_its_height_and_counts_the_lines_left_out():
    from vrneural.viewer.hud import LINE_PX, PAD, panel

    lines = [f"line {i}" for i in range(10)]
    full = panel(lines, {1, 8})
    assert full.shape[0] == LINE_PX * 10 + 2 * PAD
    cut = panel(lines, {1, 8}, max_height=4 * LINE_PX + 2 * PAD)
    assert cut.shape[0] == 4 * LINE_PX + 2 * PAD  # three lines and "+7 lines (F2 hides)"
    w, top = full.shape[1], 3 * LINE_PX + PAD  # (the last line is wider than the others)
    np.testing.assert_array_equal(cut[:top, :w], full[:top])
    assert not np.array_equal(cut[top:, :w], full[top : cut.shape[0]])
    amber = (cut[..., :3] == (255, 190, 60)).all(-1)  # line 1's alert kept, line 8's gone
    assert amber[PAD + LINE_PX : PAD + 2 * LINE_PX].any() and not amber[top:].any()
