"""The viewer's heads-up display: lines of text drawn on the CPU (Pillow, DejaVu Sans Mono as
shipped with matplotlib) into a small RGBA panel the present pass blends over the image."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

FONT_PX = 13
LINE_PX = 16
PAD = 6
BACKGROUND = (0, 0, 0, 170)
TEXT = (235, 235, 235, 255)
ALERT = (255, 190, 60, 255)


@functools.cache
def _font(size: int = FONT_PX):
    from PIL import ImageFont

    try:
        import matplotlib

        ttf = Path(matplotlib.__file__).parent / "mpl-data" / "fonts" / "ttf" / "DejaVuSansMono.ttf"
        return ImageFont.truetype(str(ttf), size)
    except (ImportError, OSError):  # any font will do
        return ImageFont.load_default(size=size)


def panel(
    lines: list[str],
    alert: set[int] | None = None,
    max_width: int = 4096,
    max_height: int = 4096,
) -> np.ndarray:
    """``[H, W, 4]`` uint8 (straight alpha): ``lines`` on a translucent dark panel, the ones
    whose index is in ``alert`` in amber; at most ``max_width`` pixels wide (longer lines are
    cut) and ``max_height`` high: the lines that do not fit become a last line that counts
    them (a small window keeps most of its image, and the HUD's first lines)."""
    from PIL import Image, ImageDraw

    fit = max(1, (max_height - 2 * PAD) // LINE_PX)
    if len(lines) > fit:
        keep = max(fit - 1, 1)
        lines = [*lines[:keep], f"+{len(lines) - keep} lines (F2 hides)"]
        alert = {i for i in alert or () if i < keep}
    font = _font()
    width = int(max((font.getlength(s) for s in lines), default=0)) + 2 * PAD
    width = max(16, min(width, max_width))
    height = LINE_PX * len(lines) + 2 * PAD
    img = Image.new("RGBA", (width, height), BACKGROUND)
    draw = ImageDraw.Draw(img)
    for i, s in enumerate(lines):
        colour = ALERT if alert and i in alert else TEXT
        draw.text((PAD, PAD + LINE_PX * i), s, font=font, fill=colour)
    return np.asarray(img, np.uint8).copy()


def thousands(n: float) -> str:
    """``1234567 -> '1.23 M'``, ``12345 -> '12.3 k'``: counts in the HUD."""
    n = float(n)
    for div, unit in ((1e9, " G"), (1e6, " M"), (1e3, " k")):
        if abs(n) >= div:
            return f"{n / div:.3g}{unit}"
    return f"{n:.0f}"
