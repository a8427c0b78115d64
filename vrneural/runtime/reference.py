"""numpy twins of the runtime's shading kernels: the readable specification of
``shaders/texture_space.wgsl`` (:func:`shade_texture_space`) and of the per-pixel evaluation
shared with ``shaders/screen_space.wgsl`` (:func:`shade_points`), and of the forward pass's
plain (non-neural) objects (:func:`shade_plain`).

Units: positions metres (world), light radiance ``colour * intensity`` in W/sr; a point light
contributes ``L = BTF(u, wi, wo) * I / d^2`` (docs/conventions.md section 2). Output radiance is
clamped to ``[0, 65504]`` (the f16 range) and is never NaN. This module never imports wgpu.
"""

from __future__ import annotations

import numpy as np

from vrneural.atlas.types import EMPTY, Atlas
from vrneural.formats.f16 import F16_MAX
from vrneural.material import NeuralMaterial, material_forward


def barycentric_2d(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Barycentrics ``[N, 3]`` of points ``p: [N, 2]`` in triangles ``a, b, c: [N, 2]`` (f32);
    extrapolated outside; ``1/3`` each for degenerate triangles (``|det| < 1e-20``)."""
    f = np.float32
    v0, v1, v2 = (b - a).astype(f), (c - a).astype(f), (p - a).astype(f)
    den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
    ok = np.abs(den) >= 1e-20
    d = np.where(ok, den, f(1))
    l1 = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / d
    l2 = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / d
    out = np.stack([1 - l1 - l2, l1, l2], -1).astype(f)
    out[~ok] = f(1 / 3)
    return out


def safe_normalize(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    n2 = (v * v).sum(-1, keepdims=True)
    ok = n2 >= 1e-20
    return np.where(ok, v / np.sqrt(np.where(ok, n2, 1)), fallback).astype(np.float32)


def ortho(n: np.ndarray) -> np.ndarray:
    """A unit vector orthogonal to each unit ``n: [N, 3]`` (same rule as the shader)."""
    ax = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]).astype(np.float32)
    c = np.cross(n, ax)
    return (c / np.linalg.norm(c, axis=-1, keepdims=True)).astype(np.float32)


def normal_matrix(model: np.ndarray) -> np.ndarray:
    """Inverse transpose of the upper-left 3x3 of ``model: [4, 4]``, as ``[4, 4]``."""
    out = np.eye(4, dtype=np.float32)
    out[:3, :3] = np.linalg.inv(model[:3, :3].astype(np.float64)).T
    return out


def _interpolate(atlas: Atlas, tri: np.ndarray, p: np.ndarray, *arrays: np.ndarray) -> list:
    """Per-vertex ``arrays`` of ``atlas.mesh`` interpolated (f32) in triangles ``tri: [N]`` at
    atlas points ``p: [N, 2]`` with :func:`barycentric_2d`."""
    f = atlas.mesh.faces[tri].astype(np.int64)  # [N, 3]
    uva = atlas.uv_atlas.astype(np.float32)
    lam = barycentric_2d(p, uva[f[:, 0]], uva[f[:, 1]], uva[f[:, 2]])[..., None]  # [N, 3, 1]
    return [(lam * a[f].astype(np.float32)).sum(1) for a in arrays]


def world_frames(pos: np.ndarray, nrm: np.ndarray, tan: np.ndarray, model: np.ndarray):
    """World position, unit normal, tangent and bitangent ``[N, 3]`` each from object-space
    position, normal ``[N, 3]`` (not normalised) and tangent ``[N, 4]`` (w: handedness):
    normal matrix, Gram-Schmidt tangent, handedness.
    Twin of ``frame_of`` in neural_material.wgsl."""
    model = model.astype(np.float32)
    pos = pos @ model[:3, :3].T + model[:3, 3]
    n = safe_normalize(nrm @ normal_matrix(model)[:3, :3].T, np.float32([0, 0, 1]))
    tw = tan[:, :3] @ model[:3, :3].T
    t = safe_normalize(tw - n * (n * tw).sum(-1, keepdims=True), ortho(n))
    b = np.where(tan[:, 3:] >= 0, 1.0, -1.0).astype(np.float32) * np.cross(n, t)
    return pos, n, t, b


def camera_relative(model, eye, light_pos):
    """``(model [4, 4], eye [3], light_pos [L, 3])`` re-expressed with the eye at the origin,
    subtracted in float64 before anything is rounded to f32. Shading is translation invariant,
    so this changes nothing but precision: an object 1e5 m from the world origin (f32 spacing
    7.8 mm there) shades like one at the origin (docs/extremes.md)."""
    o = np.asarray(eye, np.float64).reshape(-1)[:3]
    m = np.array(model, np.float64)
    m[:3, 3] -= o
    lp = np.asarray(light_pos, np.float64).reshape(-1, 3) - o
    return m, np.zeros(3), lp


def non_empty_blocks(tri_ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row-major ``(by, bx)`` of the 2x2 blocks of ``tri_ids: [R, R]`` with a triangle (the
    blocks the texture-space pass considers; the GPU's candidate lists come from here too)."""
    r = tri_ids.shape[0]
    b = (tri_ids != np.uint32(EMPTY)).reshape(r // 2, 2, r // 2, 2).any(axis=(1, 3))
    return np.nonzero(b)


def footprint_side(mat: NeuralMaterial) -> np.float32:
    """The larger side of the neural texture a footprint is measured in (the fine texture of a
    coarse-to-fine material, else its features): the kernel's ``max(dims.x, dims.y)``."""
    name = "fine" if mat.arch == "coarse_fine" else "features"
    return np.float32(max(mat.textures[name].shape[:2]))


def block_lod(mat: NeuralMaterial, foot: np.ndarray) -> np.ndarray | None:
    """Each block's level of detail in ``mat``'s prefiltered neural textures (None without
    pyramids): ``log2`` of its footprint in the full-resolution texture's texels (at least 1):
    ``foot: [N]``, one atlas texel's tiled material-UV length (:func:`texel_foot` x tiling),
    times the texture's larger side. Twin of the texture-space kernel's ``lod``."""
    if mat.lod_levels <= 1:
        return None
    texels = np.asarray(foot, np.float32) * footprint_side(mat)
    return np.log2(np.maximum(texels, np.float32(1))).astype(np.float32)


#: the most a footprint is stretched along the view (1 / cos theta_o at most: 8, as a GPU's
#: anisotropic filtering at most 8x), in the texture-space pass's footprint taps
STRETCH_MAX = 8.0


def footprint_taps(mat: NeuralMaterial, foot, taps: int, wo=None, pixel: bool = False) -> dict:
    """The texture-space pass's footprint taps (``Settings.lod_taps``) of blocks whose
    footprint is ``foot: [N]`` in tiled material UV (one atlas texel's, times the pass's
    ``lod_scale``). With ``pixel`` (the pass's ``lod_scale`` above 1: the footprint is a
    pixel's) it is stretched along the view's direction in the tangent plane by ``1 / cos``
    of its angle to the normal (at most :data:`STRETCH_MAX`), as a pixel's is on a surface
    seen obliquely: ``wo: [N, 3]`` the view in each block's tangent frame. Returns ``na, nb:
    [N]`` taps along the view and across it (each the footprint's width there in the
    full-resolution neural texture's texels, rounded, 1 to ``taps``), ``a, b: [N, 2]`` the
    steps between them in material UV and ``lod`` (``[N]``; None without pyramids), the
    level of each tap's share. Twin of the kernel's ``na, nb, step_a * ma, step_b * mb, lod_t``."""
    side = footprint_side(mat)
    foot = np.asarray(foot, np.float32)
    f32 = np.float32
    if pixel:
        wo = np.asarray(wo, np.float32)
        stretch = f32(1) / np.maximum(wo[:, 2], f32(1 / STRETCH_MAX))
        xy = wo[:, :2]
        ln = np.sqrt((xy * xy).sum(-1, keepdims=True))
        ma = np.where((xy * xy).sum(-1, keepdims=True) > 1e-12, xy / np.maximum(ln, 1e-30),
                      f32([1, 0]))  # fmt: skip
    else:
        stretch = np.ones_like(foot)
        ma = np.tile(f32([1, 0]), (len(foot), 1))
    mb = np.stack([-ma[:, 1], ma[:, 0]], -1)
    tb = foot * side
    ta = tb * stretch
    na = np.clip(np.floor(ta + f32(0.5)), 1, taps).astype(f32)
    nb = np.clip(np.floor(tb + f32(0.5)), 1, taps).astype(f32)
    lod = None
    if mat.lod_levels > 1:
        lod = np.log2(np.maximum(np.maximum(ta / na, tb / nb), f32(1))).astype(f32)
    a = ((foot * stretch) / na)[:, None] * ma
    b = (foot / nb)[:, None] * mb
    return {"na": na.astype(np.int64), "nb": nb.astype(np.int64), "a": a.astype(f32),
            "b": b.astype(f32), "lod": lod}  # fmt: skip


def tapped_forward(mat, wi, wo, uvs, precision, lod, foot, taps: dict | None):
    """:func:`~vrneural.material.material_forward` averaged over each block's footprint taps
    (:func:`footprint_taps`; None: one point per texel, at ``lod``): the mean over ``na x nb``
    evaluations at ``uvs`` shifted by ``(i + 0.5 - na / 2) a + (j + 0.5 - nb / 2) b`` (``i``
    fastest, the kernel's order), each at the taps' ``lod``."""
    if taps is None:
        return material_forward(mat, wi, wo, uvs, precision, lod, foot)
    f32 = np.float32
    na, nb, a, b, tlod = (taps[k] for k in ("na", "nb", "a", "b", "lod"))
    out = np.zeros((len(wi), 4, 3), np.float32)
    for ka, kb in {(int(x), int(y)) for x, y in zip(na, nb, strict=True)}:
        m = (na == ka) & (nb == kb)
        for j in range(ka * kb):
            ca = f32(j % ka) + f32(0.5) - f32(0.5) * f32(ka)
            cb = f32(j // ka) + f32(0.5) - f32(0.5) * f32(kb)
            o = ca * a[m] + cb * b[m]  # [M, 2]
            out[m] += material_forward(
                mat, wi[m], wo[m], uvs[m] + o[:, None, :], precision,
                None if tlod is None else tlod[m], None if foot is None else foot[m],
            )  # fmt: skip
        out[m] *= f32(1) / (f32(ka) * f32(kb))
    return out


def shade_points(
    mat, pos, n, t, b, uvs, eye, light_pos, light_rgb, precision="f32", margin=0.0, lod=None,
    foot=None, taps=None,
):  # fmt: skip
    """Radiance ``[N, 4, 3]`` of ``N`` points (frames ``[N, 3]``) whose 4 texels have material
    UVs ``uvs: [N, 4, 2]``, lit by point lights ``light_pos, light_rgb: [L, 3]`` (W/sr), seen
    from ``eye: [3]``. Returns (radiance, front ``[N]`` bool, coarse evals, fine evals).
    ``margin`` (m): a point also counts as front when it faces any point within ``margin`` of
    the eye (the shared radiance texture of both eyes); its view beyond the horizon is then
    evaluated at the range's edge (:mod:`vrneural.grazing`). ``lod: [N]``: the blocks'
    levels of detail in the prefiltered neural textures (None: level 0); ``foot: [N]`` their
    atlas texels' tiled material-UV length (march ``"auto"``); ``taps``: footprint taps
    ``(footprint [N], taps per axis at most, pixel)`` (:func:`footprint_taps`; None: one point
    per texel), the evaluations then counted per tap."""
    f32 = np.float32
    v = np.asarray(eye, f32) - pos
    wo_w = safe_normalize(v, n)
    wo = np.stack([(wo_w * t).sum(-1), (wo_w * b).sum(-1), (wo_w * n).sum(-1)], -1)
    front = (wo[:, 2] > 0) | ((v * n).sum(-1) > -f32(margin))
    tp = None if taps is None else footprint_taps(mat, taps[0], taps[1], wo, taps[2])
    acc = np.zeros((pos.shape[0], 4, 3), f32)
    n_coarse = 0
    for lp, lc in zip(np.asarray(light_pos, f32), np.asarray(light_rgb, f32), strict=True):
        lv = lp - pos
        d2 = np.maximum((lv * lv).sum(-1, keepdims=True), f32(1e-12))
        wiw = lv / np.sqrt(d2)
        wi = np.stack([(wiw * t).sum(-1), (wiw * b).sum(-1), (wiw * n).sum(-1)], -1)
        lit = front & (wi[:, 2] > 0)
        if lit.any():
            tl = None if tp is None else {k: None if v is None else v[lit] for k, v in tp.items()}
            y = tapped_forward(
                mat, wi[lit], wo[lit], uvs[lit], precision, None if lod is None else lod[lit],
                None if foot is None else foot[lit], tl,
            )  # fmt: skip
            acc[lit] += y * (lc / d2[lit])[:, None, :]
        n_coarse += int(lit.sum()) if tp is None else int((tp["na"] * tp["nb"])[lit].sum())
    acc = np.nan_to_num(np.clip(acc, 0, F16_MAX), nan=0.0)
    return acc, front, n_coarse, 4 * n_coarse


def block_geometry(atlas: Atlas) -> dict:
    """What the texture-space pass needs of the atlas, once per atlas (the GPU's "geometry
    atlas", ``GpuAtlas.geometry``): for each non-empty 2x2 block in :func:`non_empty_blocks`
    order, ``by, bx: [N]``, its texels' coordinates ``tx, ty: [N, 4]``, the object-space
    attributes at the block centre ``pos, nrm: [N, 3]``, ``tan: [N, 4]`` through the first
    non-empty texel's triangle, and the untiled material UVs of its 4 texels ``uv: [N, 4, 2]``
    (texel order (0,0), (1,0), (0,1), (1,1); each texel through its own triangle, empty texels
    through the centre's, extrapolated) and ``foot: [N]``, the untiled material-UV length of
    one atlas texel on the centre's triangle (:func:`texel_foot`).
    """
    R = atlas.resolution
    nb = R // 2
    ids = atlas.tri_ids.reshape(nb, 2, nb, 2).transpose(0, 2, 1, 3).reshape(nb, nb, 4)
    by, bx = non_empty_blocks(atlas.tri_ids)
    blk = ids[by, bx]  # [N, 4]
    first = np.argmax(blk != EMPTY, axis=1)
    tc = blk[np.arange(len(blk)), first].astype(np.int64)
    centre = np.stack([2 * bx + 1, 2 * by + 1], -1).astype(np.float32) / np.float32(R)
    m = atlas.mesh
    pos, nrm, tan = _interpolate(atlas, tc, centre, m.positions, m.normals, m.tangents)
    tri = np.where(blk != EMPTY, blk, tc[:, None]).astype(np.int64)  # [N, 4]
    tx = 2 * bx[:, None] + np.array([0, 1, 0, 1])  # [N, 4]
    ty = 2 * by[:, None] + np.array([0, 0, 1, 1])
    p = (np.stack([tx, ty], -1).astype(np.float32) + np.float32(0.5)) / np.float32(R)
    (uv,) = _interpolate(atlas, tri.ravel(), p.reshape(-1, 2), atlas.mesh.uv)
    foot = texel_foot(atlas, tc)
    return {
        "by": by, "bx": bx, "tx": tx, "ty": ty, "pos": pos, "nrm": nrm, "tan": tan,
        "uv": uv.reshape(-1, 4, 2), "foot": foot,
    }  # fmt: skip


def texel_foot(atlas: Atlas, tri: np.ndarray) -> np.ndarray:
    """``[N]`` float32: how long one atlas texel is in (untiled) material UV on triangles
    ``tri``: the longer column of the triangle's Jacobian d(material uv) / d(atlas uv), over the
    atlas side. Taken from the triangle (not from the texels' uv differences, which jump across
    UV seams and chart borders); 0 for a triangle degenerate in the atlas."""
    f = atlas.mesh.faces[tri].astype(np.int64)
    a = atlas.uv_atlas.astype(np.float64)
    m = atlas.mesh.uv.astype(np.float64)
    P = np.stack([a[f[:, 1]] - a[f[:, 0]], a[f[:, 2]] - a[f[:, 0]]], -1)  # [N, 2, 2]
    T = np.stack([m[f[:, 1]] - m[f[:, 0]], m[f[:, 2]] - m[f[:, 0]]], -1)
    det = P[:, 0, 0] * P[:, 1, 1] - P[:, 0, 1] * P[:, 1, 0]
    ok = np.abs(det) > 1e-20
    inv = np.stack([[P[:, 1, 1], -P[:, 0, 1]], [-P[:, 1, 0], P[:, 0, 0]]], 0).transpose(2, 0, 1)
    J = T @ (inv / np.where(ok, det, 1.0)[:, None, None])  # d(material uv) / d(atlas uv)
    cols = np.linalg.norm(J, axis=1)  # [N, 2]: per atlas axis
    return np.where(ok, cols.max(1) / atlas.resolution, 0.0).astype(np.float32)


def texture_blocks(atlas: Atlas, model: np.ndarray, tiling=(1.0, 1.0, 0.0, 0.0), phase=0, period=1):
    """Geometry of the non-empty 2x2 blocks in rows ``phase::period``: texel coordinates
    ``tx, ty: [N, 4]``, the block-centre frame ``pos, n, t, b: [N, 3]`` (world) and the texels'
    tiled material UVs ``uvs: [N, 4, 2]`` (from :func:`block_geometry`)."""
    g = block_geometry(atlas)
    sel = g["by"] % period == phase
    pos, n, t, b = world_frames(g["pos"][sel], g["nrm"][sel], g["tan"][sel], model)
    tl = np.asarray(tiling, np.float32)
    uvs = g["uv"][sel] * tl[:2] + tl[2:]
    foot = g["foot"][sel] * np.float32(max(tl[0], tl[1]))  # tiled
    tx, ty = g["tx"][sel], g["ty"][sel]
    return {"tx": tx, "ty": ty, "pos": pos, "n": n, "t": t, "b": b, "uvs": uvs, "foot": foot}


def shade_texture_space(
    atlas: Atlas,
    mat: NeuralMaterial,
    model: np.ndarray,
    eye: np.ndarray,
    light_pos: np.ndarray,
    light_rgb: np.ndarray,
    tiling=(1.0, 1.0, 0.0, 0.0),
    precision: str = "f32",
    phase: int = 0,
    period: int = 1,
    previous: np.ndarray | None = None,
    margin: float = 0.0,
    lod_scale: float = 1.0,
    taps: int = 1,
):
    """Twin of the texture-space pass. Returns ``(radiance [R, R, 4] float32, counters [4])``.

    Only block rows ``by % period == phase`` are processed; texels not written keep
    ``previous`` (zeros by default). ``margin``: see :func:`shade_points`; ``lod_scale``: the
    prefiltered neural textures' footprint in atlas texels (the pass's ``P.lod.x``: above 1
    where a pixel is larger than the texel, ``Settings.lod_footprint``); ``taps``: footprint
    taps per axis at most (``Settings.lod_taps``, :func:`footprint_taps`). Counters: blocks
    shaded, back-facing blocks skipped, coarse MLP evaluations, fine MLP evaluations
    (``single``: 0 and per-texel evaluations).
    """
    R = atlas.resolution
    out = np.zeros((R, R, 4), np.float32) if previous is None else previous.copy()
    model, eye, light_pos = camera_relative(model, eye, light_pos)
    g = texture_blocks(atlas, model, tiling, phase, period)
    tx, ty, pos, n, t, b, uvs = (g[k] for k in ("tx", "ty", "pos", "n", "t", "b", "uvs"))
    fs = g["foot"] * np.float32(lod_scale)
    tp = (fs, taps, lod_scale > 1) if taps > 1 else None
    rad, front, nc, nf = shade_points(
        mat, pos, n, t, b, uvs, eye, light_pos, light_rgb, precision, margin,
        block_lod(mat, fs), g["foot"], tp,
    )  # fmt: skip
    w = front
    out[ty[w], tx[w], :3] = rad[w]
    out[ty[w], tx[w], 3] = 1.0
    nc = 0 if mat.arch == "single" else nc
    counters = np.array([int(w.sum()), int((~front).sum()), nc, nf], np.int64)
    return out, counters


def shade_plain(world, normal, eye, albedo, specular, shininess, light_pos, light_rgb):
    """Twin of forward.wgsl's ``plain_colour``: Lambert ``albedo / pi`` + normalised Blinn-Phong
    ``specular (s + 8) / (8 pi) (n.h)^s`` (``s``: shininess), two-sided, under point lights with
    inverse-square falloff, in float32 in the shader's order (its ``x * inverseSqrt(d)`` as
    ``x / sqrt(d)``). ``world, normal: [..., 3]`` (metres, world; the normal need not be unit),
    ``eye [3]`` (metres), ``albedo [3]`` or ``[..., 3]``, ``specular, shininess`` scalars,
    ``light_pos, light_rgb: [L, 3]`` (metres; colour * intensity, W/sr); returns radiance
    ``[..., 3]`` float32, clamped to the f16 maximum. A point at the eye gives NaN, as on the
    GPU."""
    f32 = np.float32
    world, normal = np.asarray(world, f32), np.asarray(normal, f32)
    n0 = normal / np.sqrt(np.sum(normal * normal, -1, keepdims=True))
    v = np.asarray(eye, f32) - world
    wo = v / np.sqrt(np.sum(v * v, -1, keepdims=True))
    n = np.where(np.sum(n0 * wo, -1, keepdims=True) < 0, -n0, n0)
    kd = np.asarray(albedo, f32) * f32(1 / np.pi)
    ks = f32(specular) * (f32(shininess) + f32(8)) * f32(1 / (8 * np.pi))
    c = np.zeros_like(world)
    for lp, lc in zip(np.asarray(light_pos, f32), np.asarray(light_rgb, f32), strict=True):
        lv = lp - world
        r = f32(1) / np.sqrt(np.maximum(np.sum(lv * lv, -1, keepdims=True), f32(1e-12)))
        wi = lv * r
        cos_i = np.sum(n * wi, -1, keepdims=True)
        hv = wi + wo
        nh = np.sum(n * hv, -1, keepdims=True) / np.sqrt(np.sum(hv * hv, -1, keepdims=True))
        s = ks * np.maximum(nh, f32(0)) ** f32(shininess)
        c += np.where(cos_i > 0, (kd + s) * (cos_i * r * r) * lc, f32(0))
    return np.minimum(c, f32(F16_MAX))
