"""The viewer's GPU parts on lavapipe without a display: the present pass against its numpy
twin (bit for bit), the renderer hooks it uses, and the Jupyter backend rendering a frame."""

import numpy as np
import pytest
from test_runtime_render import _scene


def _target(w, h, fmt="rgba8unorm"):
    import wgpu

    from vrneural.gpu.device import get_device

    tu = wgpu.TextureUsage
    return get_device().create_texture(
        size=(w, h, 1), format=fmt, usage=tu.RENDER_ATTACHMENT | tu.COPY_SRC
    )


def _present(presenter, lay, window, fmt="rgba8unorm"):
    from vrneural.gpu.device import get_device
    from vrneural.gpu.readback import read_texture

    dev = get_device()
    tgt = _target(*window, fmt)
    enc = dev.create_command_encoder()
    presenter.encode(enc, tgt, window, lay)
    dev.queue.submit([enc.finish()])
    return read_texture(tgt)[..., :3]


@pytest.fixture(scope="module")
def stereo():
    """A tiny stereo renderer after 3 frames of the built-in scene (its eyes and HDR)."""
    from vrneural.gpu.device import adapter_summary
    from vrneural.runtime.config import RunConfig, resolve
    from vrneural.runtime.renderer import Renderer
    from vrneural.runtime.scene import builtin_scene

    sc = builtin_scene()
    s = resolve(RunConfig(eyes=2, profile="tiny", eye_res="64x48"), sc, adapter_summary())
    r = Renderer(sc, s)
    for f in range(3):
        r.frame(f)
    return r, r.read_eyes()


@pytest.mark.gpu
def test_present_pass_matches_its_numpy_twin_bit_for_bit(stereo):
    from vrneural.viewer.present import Layout, Presenter, compose

    r, hdr = stereo
    p = Presenter("rgba8unorm")
    eyes = r.colour_textures()
    want = compose(hdr)  # what `run` writes: tonemap of each eye, side by side
    assert want.std() > 5  # a picture, not a flat colour
    np.testing.assert_array_equal(_present(p, Layout(eyes, (128, 48)), (128, 48)), want)
    # a window twice the size: each image pixel becomes 2 x 2 window pixels
    big = _present(p, Layout(eyes, (128, 48)), (256, 96))
    np.testing.assert_array_equal(big, want.repeat(2, 0).repeat(2, 1))
    import wgpu

    from vrneural.gpu.readback import upload_texture

    # the renderer's eyes side by side in one texture (mode texture): eye 0 its left columns
    assert len(eyes) == 1 and tuple(eyes[0].size[:2]) == (128, 48)
    # split: eye 0 left of column 20, the other eye's HDR (a texture of its own) from there on
    other = upload_texture(
        hdr[1].astype(np.float16), "rgba16float", wgpu.TextureUsage.TEXTURE_BINDING
    )
    got = _present(p, Layout(eyes[:1], (64, 48), 20, other), (64, 48))
    np.testing.assert_array_equal(got, compose(hdr[:1], hdr[1], 20))
    # split with display colours on the right (the FLIP map)
    heat = np.random.default_rng(0).integers(0, 256, (48, 64, 4)).astype(np.uint8)
    tex = upload_texture(heat, "rgba8unorm", wgpu.TextureUsage.TEXTURE_BINDING)
    got = _present(p, Layout(eyes[:1], (64, 48), 33, tex, True), (64, 48))
    np.testing.assert_array_equal(got, compose(hdr[:1], heat / 255.0, 33, True))


@pytest.mark.gpu
def test_hud_and_markers_change_only_their_pixels_and_srgb_targets_stay_within_one_step(stereo):
    from vrneural.viewer.hud import panel
    from vrneural.viewer.present import RING, Layout, Presenter, compose

    r, hdr = stereo
    want = compose(hdr)
    p = Presenter("rgba8unorm")
    hud = panel(["FPS 12.3", "mode texture"])
    p.set_hud(hud)
    lay = Layout(r.colour_textures(), (128, 48), markers=[(100.0, 30.0, True)], selected=0)
    got = _present(p, lay, (128, 48))
    changed = (got != want).any(-1)
    inside = np.zeros_like(changed)
    inside[8 : 8 + hud.shape[0], 8 : 8 + hud.shape[1]] = True
    c = RING // 2
    inside[30 - c : 30 - c + RING, 100 - c : 100 - c + RING] = True
    assert changed[inside].sum() > 100 and not changed[~inside].any()
    # an sRGB target: the shader decodes, the hardware encodes again
    s = Presenter("rgba8unorm-srgb")
    got = _present(s, Layout(r.colour_textures(), (128, 48)), (128, 48), "rgba8unorm-srgb")
    assert np.abs(got.astype(int) - want).max() <= 1


@pytest.mark.gpu
def test_renderer_hooks_time_pose_and_invalidate(tmp_path):
    """frame(f, t, head) renders what frame(f) renders when given the path's own time and pose;
    invalidate() makes the next frame a full update again."""
    from vrneural.runtime.renderer import Renderer, Settings

    scene = _scene(tmp_path)  # a static head over a lit plane
    s = Settings(eyes=1, reuse=4, texture_res=64, eye_res=(48, 48), fov_y=90.0, n_lights=1)
    a, b = Renderer(scene, s), Renderer(scene, s)
    full = a.frame(0)
    pose = a.head.pose(0.0)
    assert b.frame(0, 0.0, pose).blocks_shaded == full.blocks_shaded
    np.testing.assert_array_equal(a.read_eyes()[0], b.read_eyes()[0])
    part = a.frame(1)
    assert 0 < part.blocks_shaded < full.blocks_shaded  # staggered: a fifth of the rows
    a.invalidate()
    again = a.frame(2)
    assert again.blocks_shaded == full.blocks_shaded and again.updated_objects == 1
    tex = a.colour_textures()
    assert len(tex) == 1 and tuple(tex[0].size[:2]) == (48, 48)
    from vrneural.errors import VrnError

    with pytest.raises(VrnError, match="expected a finite position"):
        a.frame(3, 0.0, (np.zeros(2), np.eye(3)))


@pytest.mark.gpu
def test_jupyter_backend_renders_a_frame_through_the_widget():
    """rendercanvas's Jupyter backend (a jupyter_rfb widget): one frame drawn through the
    widget's own API equals the offscreen renderer's frame (tonemapped) bit for bit."""
    pytest.importorskip("jupyter_rfb")
    from vrneural.viewer import View
    from vrneural.viewer.present import compose

    v = View(profile="tiny", eye_res="80x64", hud=False)
    w = v.show()
    assert type(w).__name__ == "JupyterRenderCanvas"
    w.force_draw()  # what the widget's frame request does, synchronously
    w.force_draw()
    img = np.asarray(w.snapshot().data)[..., :3]
    assert img.shape == (64, 80, 3) and len(v.records) == 2
    np.testing.assert_array_equal(img, compose(v.replay_offscreen()))
    w.close()
