"""Directions beyond the measured ones (docs/conventions.md section 2b): numpy only.

A BTF holds light and view directions up to some polar angle (75 degrees for UBO2014 and
``btf synth``); a network trained on it has seen nothing beyond. Every evaluator (this numpy
spec, the torch models, the WGSL passes) extends it the same way:

- a **light** beyond ``theta_i_max`` is evaluated at ``theta_i_max`` with the same azimuth, and
  the value is scaled by ``wi.z / cos(theta_i_max)``: the BTF carries ``cos(theta_i)``, so the
  extension is the boundary's reflectance times the true foreshortening, continuous at the
  boundary and tapering to exactly 0 at the horizon (exact for a Lambertian patch);
- a **view** beyond ``theta_o_max`` is evaluated at ``theta_o_max`` with the same azimuth, scale 1
  (radiance does not vanish at grazing view).

Both directions are taken in the shading frame (the interpolated normal), which is continuous
across triangles, so neither rule draws a seam along triangle edges.
"""

from __future__ import annotations

import math

import numpy as np

#: The direction range assumed for packs that do not record one (UBO2014's and btf synth's).
DEFAULT_THETA_MAX_DEG = 75.0


def check_dir_range(dir_range, what: str = "dir_range") -> tuple[float, float]:
    """``(theta_i_max, theta_o_max)`` in degrees, each in (0, 90); ValueError otherwise."""
    try:
        ti, to = (float(x) for x in dir_range)
    except (TypeError, ValueError):
        raise ValueError(f"{what} = {dir_range!r}; expected two angles in degrees") from None
    for name, v in (("theta_i_max", ti), ("theta_o_max", to)):
        if not (0.0 < v < 90.0):
            raise ValueError(f"{what} {name} = {v!r} degrees is out of range; allowed (0, 90)")
    return ti, to


def directions_range(light_dirs: np.ndarray, view_dirs: np.ndarray) -> tuple[float, float]:
    """The largest polar angle (degrees, to 1e-4) of a BTF's light and view directions
    ``[L, 3]``, ``[V, 3]`` (unit vectors, local frame), rounded so that every one of them lies
    inside the range in float32 (:func:`to_range` leaves them bit for bit)."""

    def top(d):
        z = np.min(np.asarray(d, np.float32)[:, 2])
        t = round(math.degrees(math.acos(min(max(float(z), -1.0), 1.0))), 4)
        while boundary_consts(t)[0] > z:  # rounded below the last direction: widen
            t = round(t + 1e-4, 4)
        return t

    return top(light_dirs), top(view_dirs)


def boundary_consts(theta_deg: float) -> tuple[np.float32, np.float32]:
    """``(cos, sin)`` of a range boundary as float32 (the constants every evaluator uses)."""
    t = np.radians(float(theta_deg))
    return np.float32(np.cos(t)), np.float32(np.sin(t))


def to_range(w: np.ndarray, cos_max: np.float32, sin_max: np.float32) -> np.ndarray:
    """Directions ``w: [N, 3]`` with ``w.z < cos_max`` moved to polar angle ``acos(cos_max)`` at
    the same azimuth (``+x`` where the azimuth is undefined); the others unchanged (f32).
    Twin of ``to_range`` in neural_material.wgsl."""
    w = np.asarray(w, np.float32)
    r2 = (w[:, :2] * w[:, :2]).sum(-1, keepdims=True)
    ok = r2 >= np.float32(1e-20)
    xy = np.where(ok, w[:, :2] * (sin_max / np.sqrt(np.where(ok, r2, 1))), [[sin_max, 0]])
    edge = np.concatenate([xy, np.full_like(r2, cos_max)], -1).astype(np.float32)
    return np.where(w[:, 2:] >= cos_max, w, edge).astype(np.float32)


def light_weight(wi_z: np.ndarray, cos_max: np.float32) -> np.ndarray:
    """Scale of a light's value: 1 inside the range, ``wi.z / cos_max`` beyond it, 0 at and
    below the horizon (f32). Twin of ``light_weight`` in neural_material.wgsl."""
    z = np.asarray(wi_z, np.float32)
    return np.clip(z / cos_max, np.float32(0), np.float32(1)).astype(np.float32)


def extend(wi: np.ndarray, wo: np.ndarray, dir_range) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The directions every evaluator feeds the networks, and the light's scale:
    ``(wi_eval [N, 3], wo_eval [N, 3], weight [N])`` for ``wi, wo: [N, 3]``."""
    ti, to = dir_range
    ci, si = boundary_consts(ti)
    co, so = boundary_consts(to)
    return to_range(wi, ci, si), to_range(wo, co, so), light_weight(np.asarray(wi)[:, 2], ci)
