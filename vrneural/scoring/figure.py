"""``slices.png`` of `vrneural eval`: at each characteristic slice of the contact sheet
(:func:`vrneural.btf.sheet.sheet_panels`) a row of the BTF, then each pack's slice and its
absolute error (mean over RGB). Slices share the row's exposure (the BTF's, see
:func:`vrneural.scoring.score.slice_exposure`); error maps share the row's colour scale, so packs
compare at a glance (Fig. 8/12 of the paper, from packs rather than checkpoints)."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from vrneural.btf.sheet import sheet_panels
from vrneural.presentation import pyplot
from vrneural.scoring.metrics import display
from vrneural.scoring.score import predict_slice, slice_exposure, texel_blocks


def slices_png(mats: list, names: list[str], btf, precision: str) -> bytes:
    """The figure as PNG bytes. ``precision``: ``f32``, ``f16`` or ``both`` (shown in f32)."""
    plt = pyplot()
    prec = "f16" if precision == "f16" else "f32"
    L, V, H, W = btf.shape
    uv = texel_blocks(H, W)
    panels = sheet_panels(btf)
    cols = 1 + 2 * len(mats)
    fig, axes = plt.subplots(
        len(panels), cols, figsize=(2.3 * cols, 2.5 * len(panels)), squeeze=False, dpi=100
    )
    for r, pan in enumerate(panels):
        gt = np.asarray(btf.slice(pan.light, pan.view), np.float32)
        ex = slice_exposure(gt)
        ys = [
            predict_slice(m, btf.light_dirs[pan.light], btf.view_dirs[pan.view], uv, H, W, prec)
            for m in mats
        ]
        errs = [np.abs(y - gt).mean(-1) for y in ys]
        top = max(max(float(np.percentile(e, 99.5)) for e in errs), 1e-8)
        axes[r][0].imshow(display(gt * ex), interpolation="nearest")
        axes[r][0].set_title(f"BTF {pan.names[0]}\n{pan.shown}", fontsize=7)
        for k, (name, y, e) in enumerate(zip(names, ys, errs, strict=True)):
            axes[r][1 + 2 * k].imshow(display(y * ex), interpolation="nearest")
            axes[r][1 + 2 * k].set_title(f"{name}", fontsize=7)
            axes[r][2 + 2 * k].imshow(e, cmap="magma", vmin=0, vmax=top, interpolation="nearest")
            axes[r][2 + 2 * k].set_title(
                f"|error| L1 {e.mean():.3g}\n(scale 0-{top:.2g})", fontsize=7
            )
        for ax in axes[r]:
            ax.axis("off")
    name = btf.meta.get("name", Path(btf.path).stem)
    head = f"vrneural eval: {name} ({L}x{V} slices of {H}x{W}), {prec}"
    note = "each row at the BTF slice's exposure, error maps on one scale per row"
    # one line where the figure is wide enough (about 11 px per character at 9 pt), else two
    one = len(head) + 2 + len(note) <= fig.get_figwidth() * 100 / 6.5
    fig.suptitle(f"{head}; {note}" if one else f"{head}\n{note}", fontsize=9)
    room = (0.35 if one else 0.55) / fig.get_figheight()
    fig.tight_layout(rect=(0, 0, 1, 1 - room))  # room for the title
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    return buf.getvalue()
