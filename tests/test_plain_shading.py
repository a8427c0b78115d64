"""The forward pass's plain objects (forward.wgsl: plain_colour, fs_plain) against their numpy
twin runtime/reference.py:shade_plain, pixel for pixel on the GPU."""

from types import SimpleNamespace

import numpy as np
import pytest

from vrneural.runtime.reference import shade_plain

W, H = 64, 48
LIGHT_POS = np.array([[0.4, 0.3, 1.2], [-0.9, 0.6, 0.62], [0.1, -0.2, -2.0]], np.float32)
LIGHT_RGB = np.array([[2.0, 1.5, 1.0], [0.3, 0.6, 0.9], [5.0, 5.0, 5.0]], np.float32)


def _render(normal, eye, albedo, spec, shin) -> np.ndarray:
    """A quad filling the eye target, with view_proj and model the identity: the pixel at
    (x, y) shows world point (ndc x, ndc y, 0.5); every vertex has the normal ``normal``."""
    from vrneural.gpu.device import get_device
    from vrneural.gpu.readback import read_texture
    from vrneural.runtime import forward as fw

    mesh = SimpleNamespace(
        positions=np.array([[-1, -1, 0.5], [1, -1, 0.5], [1, 1, 0.5], [-1, 1, 0.5]], np.float32),
        normals=np.tile(np.asarray(normal, np.float32), (4, 1)),
        faces=np.array([[0, 1, 2], [0, 2, 3]], np.uint32),
    )
    et = fw.EyeTargets(W, H, len(LIGHT_POS))
    et.update(np.eye(4), eye, LIGHT_POS, LIGHT_RGB)
    d = fw.DrawObject(mesh, None, np.eye(4), 0, plain=(albedo, spec, shin))
    pipe = fw.render_pipeline(len(LIGHT_POS), "fs_plain", False)
    bundle = fw.record_bundle(et, [(pipe, d.bind_group(), d)])
    enc = get_device().create_command_encoder()
    rp = fw.begin_pass(enc, et)
    rp.execute_bundles([bundle])
    rp.end()
    get_device().queue.submit([enc.finish()])
    return read_texture(et.colour).astype(np.float32)[..., :3]


@pytest.mark.gpu
@pytest.mark.parametrize(
    "normal, albedo, spec, shin",
    [
        ((0.1, -0.2, 1.5), (0.6, 0.4, 0.2), 0.3, 24.0),  # facing the eye, unnormalised
        ((-0.3, 0.2, -2.0), (0.35, 0.35, 0.38), 0.02, 16.0),  # facing away: two-sided flip
        ((0.0, 0.0, 1.0), (0.8, 0.8, 0.8), 1.0, 400.0),  # a sharp highlight
    ],
    ids=["front", "back", "sharp"],
)
def test_plain_objects_render_their_twin(normal, albedo, spec, shin):
    """Every pixel within float16 rounding of the twin at the pixel centre's world point:
    three lights (one behind the surface: no contribution), a light close to the surface (strong
    falloff), unnormalised normals, the two-sided flip, a sharp Blinn-Phong lobe."""
    eye = np.array([0.2, 0.1, 3.0], np.float32)
    got = _render(normal, eye, albedo, spec, shin)
    x = (np.arange(W) + 0.5) / W * 2 - 1
    y = 1 - (np.arange(H) + 0.5) / H * 2
    world = np.stack([*np.meshgrid(x, y), np.full((H, W), 0.5)], -1).astype(np.float32)
    want = shade_plain(world, np.broadcast_to(normal, world.shape), eye, albedo, spec, shin,
                       LIGHT_POS, LIGHT_RGB)  # fmt: skip
    assert want.max() > 0.1 and np.ptp(want) > 0.05  # a lit, varying image
    np.testing.assert_allclose(got, want, rtol=2e-3, atol=1e-5)
