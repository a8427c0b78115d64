"""Small hand-made inputs of the extremes cases and of the tests that use the same shapes:
a quad whose local frame is the world frame and its atlas, directions, translations, and the
continuity bound of a sweep of directions."""

from __future__ import annotations

import numpy as np

from vrneural.atlas.types import EMPTY, Atlas, Mesh


def quad_mesh(size: float = 1.0, normal_scale: float = 1.0, tangent_scale: float = 1.0) -> Mesh:
    """A ``size`` m square in the xy plane centred at the origin: normal +z, tangent +x, so the
    local frame equals the world frame (bitangent +y). material uv = (x, y) / size + 0.5.
    ``normal_scale`` / ``tangent_scale`` store deliberately unnormalized frames."""
    s = size / 2
    p = np.array([[-s, -s, 0], [s, -s, 0], [-s, s, 0], [s, s, 0]], np.float32)
    n = np.tile(np.float32([0, 0, normal_scale]), (4, 1))
    t = np.tile(np.float32([tangent_scale, 0, 0, 1]), (4, 1))
    uv = (p[:, :2] / size + 0.5).astype(np.float32)
    return Mesh("quad", p, np.array([[0, 1, 2], [1, 3, 2]], np.uint32), n, t, uv)


def quad_atlas(res: int = 16, lo: float = 0.125, hi: float = 0.875, mesh: Mesh | None = None):
    """``mesh`` (default :func:`quad_mesh`) mapped to atlas square ``[lo, hi]^2`` at ``res``;
    texels outside are EMPTY, a 1-texel gutter keeps the nearest triangle."""
    m = mesh or quad_mesh()
    uva = (lo + (hi - lo) * m.uv).astype(np.float32)
    c = (np.arange(res) + 0.5) / res
    u, v = np.meshgrid(c, c)  # [y, x]
    a = (u - lo) / (hi - lo)
    b = (v - lo) / (hi - lo)
    ids = np.where(a + b < 1.0, 0, 1).astype(np.uint32)
    g = 1.0 / (res * (hi - lo))
    inside = (a > -g) & (a < 1 + g) & (b > -g) & (b < 1 + g)
    ids[~inside] = EMPTY
    return Atlas(m, uva, ids, res, 1)


def translate(x, y, z) -> np.ndarray:
    """``[4, 4]`` float64 translation."""
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def direction(theta_deg: float, phi_deg: float = 0.0) -> np.ndarray:
    """Unit vector ``[3]`` (float64) at polar angle ``theta`` from +z and azimuth ``phi``."""
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


def lipschitz_bound(mat) -> float:
    """An upper bound of ``|d y / d dirs|`` (2-norm) of a material with ``linear`` output and
    fixed features: the product of the layers' spectral norms (ReLU-type activations are
    1-Lipschitz), the first layer restricted to its 9 direction inputs."""
    if mat.output != "linear":
        raise ValueError("the bound needs a linear output")

    def chain(layers, first_cols):
        b = np.linalg.norm(layers[0].weight[:, first_cols].astype(np.float64), 2)
        for lay in layers[1:]:
            b *= np.linalg.norm(lay.weight.astype(np.float64), 2)
        return b

    if mat.arch == "coarse_fine":
        z = mat.networks["coarse"][-1].n_out
        return chain(mat.networks["coarse"], slice(0, 9)) * chain(mat.networks["fine"], slice(0, z))
    return chain(mat.networks["mlp"], slice(0, 9))


def dirs9(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """``[N, 9]`` network direction inputs ``[wi, wo, h]`` (material.half_vector rule)."""
    from vrneural.material import half_vector

    return np.concatenate([wi, wo, half_vector(wi, wo)], -1).astype(np.float64)


def step_bounds(mat, wi: np.ndarray, wo: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Upper bounds ``[N - 1]`` of ``|y[k+1] - y[k]|`` along a path of directions ``wi, wo:
    [N, 3]`` (texel uvs ``uv: [N, 4, 2]``, the same texels at every step), as
    :func:`vrneural.material.material_forward` extends them beyond the data's range
    (:func:`vrneural.grazing.extend`): the network sees the extended directions and its value
    is scaled by the light weight ``w``, so a step is at most
    ``lip |d_ext[k+1] - d_ext[k]| + max(|net[k]|, |net[k+1]|) |w[k+1] - w[k]|``."""
    from vrneural.grazing import extend
    from vrneural.material import material_forward

    wi_e, wo_e, w = extend(wi.astype(np.float32), wo.astype(np.float32), mat.dir_range)
    net = np.abs(material_forward(mat, wi_e, wo_e, uv).astype(np.float64)).max(axis=(1, 2))
    dd = np.linalg.norm(np.diff(dirs9(wi_e, wo_e), axis=0), axis=1)
    dw = np.abs(np.diff(w.astype(np.float64)))
    return lipschitz_bound(mat) * dd + np.maximum(net[1:], net[:-1]) * dw


def finite_nonneg(a: np.ndarray) -> bool:
    a = np.asarray(a)
    return bool(np.isfinite(a).all() and (a >= 0).all())
