"""Contact sheets (`vrneural btf show`) and summaries (`vrneural btf info`) of a ``.btf``.

The sheet shows BTF slices at several characteristic ``(wi, wo)`` pairs (each tiled 2 x 2 so
that seams would show), each tonemapped with its own exposure (printed in its title), plus the
unfolded apparent BRDF of one texel: an image over light index (rows) x view index (columns),
like the papers' figures (log-tonemapped because it spans orders of magnitude).

A BTF only has its own directions, so each panel shows the slice nearest to the pair asked for
and its title gives both: the pair's name and asked angles, and the angles and indices of the
slice shown. Pairs that resolve to the same slice (coarse direction sets) share one panel.

A gallery (``vrneural btf show A.btf B.btf ...``) sets several BTFs side by side: one row per
file, one column per pair, to compare materials at the same directions.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vrneural.btf.dirs import spherical
from vrneural.btf.format import Btf
from vrneural.errors import VrnError
from vrneural.presentation import pyplot, save_png
from vrneural.warn import VrnWarning


class BtfWarning(VrnWarning):
    """A BTF that reads but holds values training refuses (``vrneural btf info``)."""


#: (name, light theta/phi, view theta/phi) in degrees: the pairs the sheet asks for.
PAIRS = (
    ("head-on", (0, 0), (0, 0)),
    ("side light", (60, 0), (0, 0)),
    ("raking light", (75, 90), (0, 0)),
    ("mirror along u", (45, 0), (45, 180)),
    ("mirror along v", (45, 90), (45, 270)),
    ("back-scatter", (60, 45), (60, 45)),
    ("grazing view", (30, 0), (75, 180)),
    ("grazing both", (75, 0), (75, 180)),
)


def nearest(dirs: np.ndarray, theta_deg: float, phi_deg: float) -> int:
    """Index of the direction in ``dirs`` ``[N, 3]`` closest to (theta, phi) in degrees."""
    d = spherical(np.radians([theta_deg]), np.radians([phi_deg]))[0]
    return int(np.argmax(dirs @ d))


def fmt_angle(theta_deg: float, phi_deg: float) -> str:
    """``"theta@phi"`` in degrees (theta to 0.1, phi whole, in [0, 360)); ``"0"`` on the normal."""
    t = f"{theta_deg:.1f}".removesuffix(".0")
    if t == "0":
        return "0"
    return f"{t}@{round(phi_deg) % 360}"


def dir_angles(d: np.ndarray) -> tuple[float, float]:
    """(theta, phi) in degrees of the unit vector ``d``."""
    theta = float(np.degrees(np.arccos(np.clip(float(d[2]), -1.0, 1.0))))
    phi = float(np.degrees(np.arctan2(float(d[1]), float(d[0])))) % 360.0
    return theta, phi


@dataclass
class Panel:
    """One contact-sheet panel: the slice ``(light, view)`` and the pairs that resolved to it."""

    light: int
    view: int
    shown: str  #: the slice's own angles, ``"wi=17.5@0 wo=54.3@190"``
    names: list[str] = field(default_factory=list)  #: names of the pairs asked for
    asked: list[str] = field(default_factory=list)  #: their angles, ``"wi=45@0 wo=45@180"``

    def title(self) -> str:
        """Multi-line title: each pair asked for, then the slice shown (angles, indices)."""
        lines = [f"{n} (asked {a})" for n, a in zip(self.names, self.asked, strict=True)]
        lines[1:] = [f"+ {x}" for x in lines[1:]]
        n = len(self.names)
        to = "nearest" if n == 1 else "nearest to both" if n == 2 else f"nearest to all {n}"
        return "\n".join([*lines, f"{to}: {self.shown}, l{self.light} v{self.view}"])


def pair_slices(btf: Btf) -> list[tuple[int, int]]:
    """``(light, view)`` of the slice of ``btf`` nearest to each of :data:`PAIRS`, in their
    order (two pairs may give the same slice)."""
    return [
        (nearest(btf.light_dirs, tl, pl), nearest(btf.view_dirs, tv, pv))
        for _, (tl, pl), (tv, pv) in PAIRS
    ]


def asked_angles(light: tuple[float, float], view: tuple[float, float]) -> str:
    """A pair's angles as asked, ``"wi=45@0 wo=45@180"``."""
    return f"wi={fmt_angle(*light)} wo={fmt_angle(*view)}"


def slice_angles(btf: Btf, light: int, view: int) -> str:
    """The angles of slice ``(light, view)`` of ``btf``, ``"wi=17.5@0 wo=54.3@190"``."""
    wi = fmt_angle(*dir_angles(btf.light_dirs[light]))
    return f"wi={wi} wo={fmt_angle(*dir_angles(btf.view_dirs[view]))}"


def sheet_panels(btf: Btf) -> list[Panel]:
    """The panels of the contact sheet: for each of :data:`PAIRS` the nearest slice of ``btf``;
    pairs that resolve to the same slice share one panel (in the order of their first pair)."""
    panels: dict[tuple[int, int], Panel] = {}
    for (name, light, view), (li, vi) in zip(PAIRS, pair_slices(btf), strict=True):
        if (li, vi) not in panels:
            panels[li, vi] = Panel(li, vi, slice_angles(btf, li, vi))
        panels[li, vi].names.append(name)
        panels[li, vi].asked.append(asked_angles(light, view))
    return list(panels.values())


def tonemap(x: np.ndarray, exposure: float) -> np.ndarray:
    """Linear RGB -> display sRGB in [0, 1] after scaling by ``exposure`` (Reinhard on max)."""
    y = np.maximum(x * exposure, 0.0)
    y = y / (1.0 + y.max(-1, keepdims=True) * 0.25)
    y = np.clip(y, 0.0, 1.0)
    return np.where(y <= 0.0031308, 12.92 * y, 1.055 * np.power(y, 1 / 2.4) - 0.055)


def exposure(img: np.ndarray) -> float:
    """A panel's exposure: its 99th percentile (of the max over RGB) maps to 0.8."""
    return 0.8 / max(float(np.percentile(img.max(-1), 99.0)), 1e-6)


def summary(btf: Btf, max_slices: int = 256) -> dict:
    """Shape, directions, value range and metadata. The value range is exact for files up to
    ``max_slices`` slices, else taken over ``max_slices`` evenly spread slices (``sampled``);
    it covers the finite values, and ``nonfinite_values`` counts the NaN/Inf ones seen."""
    L, V, H, W = btf.shape
    n = L * V
    idx = np.arange(n) if n <= max_slices else np.linspace(0, n - 1, max_slices).astype(int)
    lo, hi, total, count, bad = np.inf, -np.inf, 0.0, 0, 0
    for k in idx:
        s = btf.slice(int(k) // V, int(k) % V)
        ok = np.isfinite(s)
        bad += int(s.size - ok.sum())
        s = s[ok]  # the range of the finite values; the others are counted
        if s.size:
            lo, hi = min(lo, float(s.min())), max(hi, float(s.max()))
        total += float(s.sum(dtype=np.float64))
        count += s.size
    theta = np.degrees(np.arccos(np.clip(btf.light_dirs[:, 2], -1, 1)))
    theta_v = np.degrees(np.arccos(np.clip(btf.view_dirs[:, 2], -1, 1)))
    return {
        "path": str(btf.path),
        "shape": {"lights": L, "views": V, "height": H, "width": W, "channels": 3},
        "dtype": "float16",
        "size_bytes": btf.path.stat().st_size if btf.path else None,
        "light_theta_deg": [float(theta.min()), float(theta.max())],
        "view_theta_deg": [float(theta_v.min()), float(theta_v.max())],
        "same_light_and_view_dirs": bool(
            L == V and np.allclose(btf.light_dirs, btf.view_dirs, atol=1e-6)
        ),
        "value_min": lo,
        "value_max": hi,
        "value_mean": total / max(count, 1),
        "value_range_sampled": bool(n > max_slices),
        "nonfinite_values": bad,
        "height_field": None if btf.height is None else _height_summary(btf),
        "meta": btf.meta,
    }


def sheet_figure(btf: Btf, texel: tuple[int, int] | None = None):
    """The contact sheet as a matplotlib figure (panels from :func:`sheet_panels`)."""
    plt = pyplot()
    L, V, H, W = btf.shape
    panels = sheet_panels(btf)
    slices = [np.tile(btf.slice(p.light, p.view), (2, 2, 1)) for p in panels]
    # one exposure per panel (its 99th percentile -> 0.8), printed in its title: glossy
    # materials span orders of magnitude between mirror and off-mirror pairs, so one global
    # exposure would show either the highlights or everything else
    exposures = [exposure(s) for s in slices]
    x, y = texel if texel is not None else (W // 2, H // 2)
    unf = np.asarray(btf.values[:, :, y, x, :], np.float32)  # [L, V, 3]
    lum = np.log1p(unf / max(float(np.percentile(unf, 50)), 1e-6))
    unf_img = lum / max(float(lum.max()), 1e-6)

    cols = 4
    rows = (len(slices) + cols - 1) // cols
    fig = plt.figure(figsize=(4 * cols, 4.3 * rows + 6.5), dpi=100)
    name = btf.meta.get("name", btf.path.name if btf.path else "?")
    fig.suptitle(
        f"{name}: {L} lights x {V} views x {H}x{W} texels (slices tiled 2x2, each panel "
        "with its own exposure x)\neach panel: the (wi, wo) pair asked for and the nearest slice "
        "this BTF has (light index l, view index v); angles theta@phi in degrees",
        fontsize=13,
    )
    for k, (img, p, ex) in enumerate(zip(slices, panels, exposures, strict=True)):
        ax = fig.add_subplot(rows + 2, cols, k + 1)
        ax.imshow(tonemap(img, ex), interpolation="nearest")
        ax.set_title(f"{p.title()}  x{ex:.3g}", fontsize=9)
        ax.axis("off")
    ax = fig.add_subplot(rows + 2, 1, (rows + 1, rows + 2))
    ax.imshow(np.clip(unf_img, 0, 1), interpolation="nearest", aspect="auto")
    ax.set_title(
        f"unfolded apparent BRDF of texel (x={x}, y={y}): rows = light index, "
        f"columns = view index, log(1 + v / median)",
        fontsize=10,
    )
    ax.set_xlabel("view index")
    ax.set_ylabel("light index")
    from matplotlib.ticker import MaxNLocator

    for axis in (ax.xaxis, ax.yaxis):  # indices: whole numbers only (few directions: 2.5, ...)
        axis.set_major_locator(MaxNLocator(integer=True))
    fig.tight_layout()
    return fig


def gallery_figure(btfs: list[Btf]):
    """Several BTFs side by side: one row per BTF, one column per pair of :data:`PAIRS` (pairs
    that share a slice keep their own columns), each panel the nearest slice (tiled 2 x 2, its
    own exposure, as on the contact sheet); the columns are titled with the pairs asked for,
    each panel labelled with its slice's own angles and exposure."""
    plt = pyplot()
    cols, rows = len(PAIRS), len(btfs)
    fig, axes = plt.subplots(
        rows, cols, figsize=(2.1 * cols, 2.35 * rows + 0.9), dpi=100, squeeze=False
    )
    fig.suptitle(
        "slices at characteristic (wi, wo) pairs (angles theta@phi in degrees; each panel the "
        "nearest slice the BTF has, tiled 2x2, with its own exposure x)",
        fontsize=10,
    )
    for r, btf in enumerate(btfs):
        label = btf.path.name if btf.path else btf.meta.get("name", "?")
        _, _, H, W = btf.shape
        for c, ((pair, light, view), (li, vi)) in enumerate(
            zip(PAIRS, pair_slices(btf), strict=True)
        ):
            img = np.tile(btf.slice(li, vi), (2, 2, 1))
            ex = exposure(img)
            ax = axes[r, c]
            ax.imshow(tonemap(img, ex), interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_xlabel(f"{slice_angles(btf, li, vi)}  x{ex:.3g}", fontsize=6.5)
            if r == 0:
                ax.set_title(f"{pair}\n(asked {asked_angles(light, view)})", fontsize=8)
            if c == 0:
                ax.set_ylabel(
                    f"{label}\n{W}x{H} texels, {len(btf.light_dirs)} x {len(btf.view_dirs)} dirs",
                    fontsize=8,
                )
    fig.tight_layout()
    return fig


def gallery(btfs: list[Btf], out) -> Path:
    """Write :func:`gallery_figure` of ``btfs`` as a PNG to ``out``."""
    return save_png(gallery_figure(btfs), Path(out), bbox=None)


def contact_sheet(btf: Btf, out, texel: tuple[int, int] | None = None) -> Path:
    """Write the contact sheet PNG to ``out``. ``texel = (x, y)`` picks the unfolded texel."""
    return save_png(sheet_figure(btf, texel), Path(out), bbox=None)


def _height_summary(btf) -> dict:
    """The height field's size and range, and its relief on the texel grid with the parallax
    ``distill --parallax auto`` gives it (vrneural.parallax; None where it does not fit)."""
    from vrneural.parallax import choose_kind, height_at_texels, relief_texels

    out = {
        "shape": list(btf.height.shape),
        "min": float(btf.height.min()),
        "max": float(btf.height.max()),
        "relief_texels": None,
        "parallax_auto": None,
    }
    try:
        h = height_at_texels(btf.height, btf.resolution)
    except VrnError:
        return out
    out["relief_texels"] = relief_texels(h)
    out["parallax_auto"] = choose_kind("auto", h, str(btf.path))[0]
    return out
