"""One progress bar over the stages of an atlas build (tqdm, on stderr).

The bar counts stages; each names itself and its size in the bar's postfix ("charts by normal
direction", "cut 462 charts", "rasterize 1200^2 + gutter, 9216 triangles"), so a long stage is
visible as it runs rather than as a bar that sits still.
"""

from __future__ import annotations

from tqdm import tqdm


class Stages:
    """``Stages(name, total, enabled)``; :meth:`stage` starts the next stage. Usable as a
    context manager (closes the bar)."""

    def __init__(self, name: str, total: int, enabled: bool):
        self.bar = tqdm(total=total, desc=f"atlas {name}", disable=not enabled, leave=False)
        self.started = False

    def stage(self, text: str, steps: int = 1) -> None:
        if self.started:
            self.bar.update(steps)
        self.started = True
        self.bar.set_postfix_str(text)

    def __enter__(self) -> Stages:
        return self

    def __exit__(self, *exc) -> None:
        self.bar.update(max(self.bar.total - self.bar.n, 0))
        self.bar.close()
