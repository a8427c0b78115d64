"""Contact sheets (`vrneural btf show`) and summaries (`vrneural btf info`) of a ``.btf``.

The sheet shows BTF slices at several characteristic ``(wi, wo)`` pairs (each tiled 2 x 2 so
that seams would show), each tonemapped with its own exposure (printed in its title), plus the
unfolded apparent BRDF of one texel: an image over light index (rows) x view index (columns),
like the papers' figures (log-tonemapped because it spans orders of magnitude).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vrneural.btf.dirs import spherical
from vrneural.btf.format import Btf
from vrneural.warn import VrnWarning


class BtfWarning(VrnWarning):
    """A BTF that reads but holds values training refuses (``vrneural btf info``)."""


#: (label, light theta/phi, view theta/phi) in degrees.
PAIRS = (
    ("head-on  wi=0 wo=0", (0, 0), (0, 0)),
    ("side light  wi=60@0 wo=0", (60, 0), (0, 0)),
    ("raking light  wi=75@90 wo=0", (75, 90), (0, 0)),
    ("mirror along u  wi=45@0 wo=45@180", (45, 0), (45, 180)),
    ("mirror along v  wi=45@90 wo=45@270", (45, 90), (45, 270)),
    ("back-scatter  wi=wo=60@45", (60, 45), (60, 45)),
    ("grazing view  wi=30@0 wo=75@180", (30, 0), (75, 180)),
    ("grazing both  wi=75@0 wo=75@180", (75, 0), (75, 180)),
)


def nearest(dirs: np.ndarray, theta_deg: float, phi_deg: float) -> int:
    """Index of the direction in ``dirs`` ``[N, 3]`` closest to (theta, phi) in degrees."""
    d = spherical(np.radians([theta_deg]), np.radians([phi_deg]))[0]
    return int(np.argmax(dirs @ d))


def tonemap(x: np.ndarray, exposure: float) -> np.ndarray:
    """Linear RGB -> display sRGB in [0, 1] after scaling by ``exposure`` (Reinhard on max)."""
    y = np.maximum(x * exposure, 0.0)
    y = y / (1.0 + y.max(-1, keepdims=True) * 0.25)
    y = np.clip(y, 0.0, 1.0)
    return np.where(y <= 0.0031308, 12.92 * y, 1.055 * np.power(y, 1 / 2.4) - 0.055)


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
    return {
        "path": str(btf.path),
        "shape": {"lights": L, "views": V, "height": H, "width": W, "channels": 3},
        "dtype": "float16",
        "size_bytes": btf.path.stat().st_size if btf.path else None,
        "light_theta_deg": [float(theta.min()), float(theta.max())],
        "same_light_and_view_dirs": bool(
            L == V and np.allclose(btf.light_dirs, btf.view_dirs, atol=1e-6)
        ),
        "value_min": lo,
        "value_max": hi,
        "value_mean": total / max(count, 1),
        "value_range_sampled": bool(n > max_slices),
        "nonfinite_values": bad,
        "meta": btf.meta,
    }


def contact_sheet(btf: Btf, out, texel: tuple[int, int] | None = None) -> Path:
    """Write the contact sheet PNG to ``out``. ``texel = (x, y)`` picks the unfolded texel."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from vrneural.formats.atomic import atomic_path

    L, V, H, W = btf.shape
    slices, labels = [], []
    for label, (tl, pl), (tv, pv) in PAIRS:
        li, vi = nearest(btf.light_dirs, tl, pl), nearest(btf.view_dirs, tv, pv)
        slices.append(np.tile(btf.slice(li, vi), (2, 2, 1)))
        labels.append(f"{label}\n(l{li}, v{vi})")
    # one exposure per panel (its 99th percentile -> 0.8), printed in its title: glossy
    # materials span orders of magnitude between mirror and off-mirror pairs, so one global
    # exposure would show either the highlights or everything else
    exposures = [0.8 / max(float(np.percentile(s.max(-1), 99.0)), 1e-6) for s in slices]
    x, y = texel if texel is not None else (W // 2, H // 2)
    unf = np.asarray(btf.values[:, :, y, x, :], np.float32)  # [L, V, 3]
    lum = np.log1p(unf / max(float(np.percentile(unf, 50)), 1e-6))
    unf_img = lum / max(float(lum.max()), 1e-6)

    cols = 4
    rows = (len(slices) + cols - 1) // cols
    fig = plt.figure(figsize=(4 * cols, 4 * rows + 6.5), dpi=100)
    name = btf.meta.get("name", btf.path.name if btf.path else "?")
    fig.suptitle(
        f"{name}: {L} lights x {V} views x {H}x{W} texels (slices tiled 2x2, each panel "
        "with its own exposure x)",
        fontsize=13,
    )
    for k, (img, lab, ex) in enumerate(zip(slices, labels, exposures, strict=True)):
        ax = fig.add_subplot(rows + 2, cols, k + 1)
        ax.imshow(tonemap(img, ex), interpolation="nearest")
        ax.set_title(f"{lab} x{ex:.3g}", fontsize=9)
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
    fig.tight_layout()
    out = Path(out)
    with atomic_path(out) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    return out
