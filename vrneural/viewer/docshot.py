"""The docs' picture of the viewer (docs/viewer.md): a real window under Xvfb (the window
tests' machinery), read back from its surface after a few frames and key presses.

    python -m vrneural.viewer.docshot docs/viewer.png [--force]

The built-in scene at the preview profile, one eye, HUD on, the split view (texture space
left, the per-pixel reference right; on lavapipe the reference frame takes seconds).
"""

from __future__ import annotations

import argparse
import sys

from vrneural.errors import VrnError
from vrneural.outputs import check_output
from vrneural.runtime.output import write_png
from vrneural.viewer.view import View
from vrneural.viewer.xvfb import on_a_display


def shoot(frames: int = 8, split: str = "reference", **options):
    """``[H, W, 3]`` uint8: the window's surface after ``frames`` frames."""
    v = View(frames=frames, split=split, **options)
    v.keep_shown = True
    v.run()
    return v.shown


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m vrneural.viewer.docshot",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("out", help="PNG to write")
    p.add_argument("--force", action="store_true", help="overwrite it")
    a = p.parse_args(argv)
    try:
        out = check_output(a.out, a.force)
        img = on_a_display(shoot)
        write_png(out, img)
    except VrnError as e:
        print(f"vrneural.viewer.docshot: error: {e}", file=sys.stderr)
        return 2
    print(f"wrote {out} ({img.shape[1]}x{img.shape[0]})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
