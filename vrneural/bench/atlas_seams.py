"""Seam error of an atlas: a Lambertian render in texture space against screen space.

One object (the mesh, scaled to 0.7 m, at the built-in head path's target), the procedural
Lambertian material (albedo (0.8, 0.5, 0.2): no network error), one point light, one eye at
frame 0 of the built-in head path. Rendered twice with :class:`vrneural.runtime.renderer.
Renderer`: ``--mode texture`` (radiance texture on the atlas, sampled bilinearly) and ``--mode
screen`` (shaded per pixel, no atlas): their difference is what the atlas costs. Chart borders
are located in the image by projecting the 3D edges that are seams of the atlas (an edge of two
triangles in different charts) into the eye, with a 1-pixel margin; ``seam_error`` is the
largest difference on those pixels, ``interior_error`` the largest elsewhere on the object
(pixels within 2 of its silhouette are left out of both: grazing angles differ between the
modes whatever the atlas), both relative to the 99th percentile of the screen-space image
(so 0.05 = 5 % of a bright pixel). Border pixels include borders hidden behind the surface
(no depth test), so the seam error is an upper bound that contains interior pixels too.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vrneural.material import lambertian_material
from vrneural.runtime.camera import OrbitPath
from vrneural.runtime.lights import PointLight
from vrneural.runtime.scene import MaterialDesc, ObjectDesc, Scene, model_matrix

ALBEDO = (0.8, 0.5, 0.2)


def _scene(mesh_file: str, size: float):
    from vrneural.runtime.assets import get_mesh

    p = get_mesh(mesh_file).positions
    centre = (p.max(0) + p.min(0)) / 2
    scale = size / float((p.max(0) - p.min(0)).max())
    model = model_matrix(np.asarray(OrbitPath.target) - centre * scale, (20, 30, 0), scale)
    mat = MaterialDesc("neural", lambertian_material(ALBEDO), "lambertian", 1.0)
    obj = ObjectDesc("mesh", mesh_file, model, mat)
    light = PointLight(position=(0.6, 1.8, 1.2), colour=(1.0, 1.0, 1.0), intensity=1.5)
    return Scene("seams", [obj], [light], None, None, "orbit", Path.cwd(), src="seam scene")


def border_mask(atlas, model: np.ndarray, view_proj: np.ndarray, W: int, H: int) -> np.ndarray:
    """[H, W] bool: pixels within one pixel of a projected seam of ``atlas``: an edge shared
    by two triangles (positions welded) whose atlas UVs differ at its ends."""
    from vrneural.atlas.charts import face_adjacency

    m = atlas.mesh
    pos = m.positions.astype(np.float64)
    faces = m.faces.astype(np.int64)
    fa, fb = face_adjacency(pos, faces)
    a, b = faces[fa], faces[fb]
    _, weld = np.unique(pos, axis=0, return_inverse=True)
    weld = weld.reshape(-1)
    # for each corner of a: the corner of b at the same position (or -1)
    match = weld[a][:, :, None] == weld[b][:, None, :]  # [P, 3, 3]
    has = match.any(2)
    other = np.take_along_axis(b, np.argmax(match, 2), 1)  # b's vertex at a's corner
    uv = atlas.uv_atlas
    differs = has & (uv[a] != uv[other]).any(-1)
    seam = differs.any(1)
    ends = a[seam][has[seam]].reshape(-1, 2)  # the two shared corners of each seam edge
    edges = np.stack([pos[ends[:, 0]], pos[ends[:, 1]]], 1)  # [E, 2, 3]
    mask = np.zeros((H, W), bool)
    if not len(edges):
        return mask
    t = np.linspace(0.0, 1.0, 9)[None, :, None]
    pts = edges[:, :1] * (1 - t) + edges[:, 1:] * t  # [E, 9, 3]
    pts = pts.reshape(-1, 3)
    world = np.c_[pts, np.ones(len(pts))] @ (view_proj @ model).T
    ok = world[:, 3] > 1e-9
    ndc = world[ok, :2] / world[ok, 3:4]
    x = np.floor((ndc[:, 0] + 1) / 2 * W).astype(np.int64)
    y = np.floor((1 - ndc[:, 1]) / 2 * H).astype(np.int64)
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            xx, yy = x + dx, y + dy
            inb = (xx >= 0) & (xx < W) & (yy >= 0) & (yy < H)
            mask[yy[inb], xx[inb]] = True
    return mask


def seam_error(mesh_file: str, texture_res: int, eye: int) -> dict:
    """``{seam_error, interior_error, border_pixels, object_pixels}`` of ``mesh_file`` (module
    doc) at ``texture_res``^2 texels, an ``eye`` x ``eye`` image."""
    from vrneural.runtime.renderer import Renderer, Settings

    scene = _scene(mesh_file, 0.7)
    imgs, r = {}, None
    kw = dict(eyes=1, reuse=0, texture_res=texture_res, eye_res=(eye, eye), fov_y=50.0, n_lights=1)
    for mode in ("screen", "texture"):
        r = Renderer(scene, Settings(mode=mode, **kw))
        r.frame(0)
        imgs[mode] = r.read_eyes()[0][..., :3].astype(np.float64)
    atlas = r.neural[0].atlas
    view_proj = r.eyes_at(0)[0].view_proj
    model = np.asarray(scene.objects[0].model, np.float64)  # world, as the eye's view_proj
    border = border_mask(atlas, model, view_proj, eye, eye)
    from scipy.ndimage import binary_erosion

    # object pixels away from its silhouette (where the two modes differ for other reasons)
    obj = binary_erosion(imgs["screen"].max(-1) > 0, iterations=2)
    diff = np.abs(imgs["texture"] - imgs["screen"]).max(-1)
    ref = float(np.percentile(imgs["screen"].max(-1)[obj], 99)) if obj.any() else 1.0
    on = border & obj
    off = obj & ~border
    return {
        "seam_error": float(diff[on].max() / ref) if on.any() else 0.0,
        "interior_error": float(diff[off].max() / ref) if off.any() else 0.0,
        "border_pixels": int(on.sum()),
        "object_pixels": int(obj.sum()),
        "texture_res": texture_res,
        "eye_res": eye,
    }
