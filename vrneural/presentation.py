"""How results are shown, for every command that writes them (the benchmarks, `eval`): Markdown
tables and matplotlib figures on the Agg backend, saved as PNG atomically.
"""

from __future__ import annotations

from pathlib import Path

from vrneural.outputs import atomic_path


def table(headers: list[str], rows: list[list]) -> list[str]:
    """Markdown table lines; floats printed with 3 significant digits."""

    def cell(v):
        if isinstance(v, float):
            return f"{v:.3g}" if abs(v) < 1e3 else f"{v:.0f}"
        return str(v)

    out = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    out += ["| " + " | ".join(cell(v) for v in r) + " |" for r in rows]
    return out


def pyplot():
    """``matplotlib.pyplot`` on the Agg backend (files only, no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_png(fig, path: Path, dpi: int = 100, bbox: str | None = "tight") -> Path:
    """Save a matplotlib figure as PNG atomically (dpi 100 keeps plots well under 300 KB) and
    close it; ``bbox``: matplotlib's ``bbox_inches``."""
    import matplotlib.pyplot as plt

    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi, bbox_inches=bbox)
    plt.close(fig)
    return path
