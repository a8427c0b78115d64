"""`bench quality --btf A.btf[,B.btf]`: the quality table on any BTF, not only the presets.

A given BTF is benched as it is (no synthesis; ``--res`` and ``--dirs`` apply to the presets
only), in a folder named after its file name inside ``--out``, and its rows in the report are
labelled by that file name (``pebbles.btf``), so they cannot be taken for a synthetic preset.
"""

from __future__ import annotations

from pathlib import Path

from vrneural.btf.format import read_btf
from vrneural.errors import VrnError


def given_btfs(cfg) -> dict[str, Path]:
    """``{file name: path}`` of ``cfg.btf`` (a tuple of paths; empty: none), in order."""
    out: dict[str, Path] = {}
    for item in cfg.btf or ():
        p = Path(item)
        if out.get(p.name) == p:
            raise VrnError(f"--btf gives {p} twice; give each file once")
        if p.name in out:
            raise VrnError(
                f"--btf names two files called {p.name} ({out[p.name]} and {p}); the table "
                "labels each by its file name: rename one"
            )
        out[p.name] = p
    return out


def check_given(cfg) -> dict[str, Path]:
    """Every ``--btf`` file opens as a BTF that training takes (even size, at least two
    (light, view) pairs); one-line errors before any work."""
    btfs = given_btfs(cfg)
    for p in btfs.values():
        if p.suffix.lower() != ".btf":
            raise VrnError(f"--btf {p}: expected a .btf file (convert images with btf import)")
        b = read_btf(p)
        L, V, H, W = b.shape
        if H % 2 or W % 2:
            raise VrnError(
                f"--btf {p}: {H}x{W} texels, odd; training uses 2x2 texel blocks: crop it to "
                "an even size"
            )
        if L * V < 2:
            raise VrnError(
                f"--btf {p}: only {L * V} (light, view) pair; one is held out for the test L1, "
                "so at least 2 are needed"
            )
    return btfs


def btf_path(name: str, cfg, root: Path) -> Path:
    """Where the BTF of material ``name`` is: the given file, or the preset's synthesised one
    in ``root/btf``."""
    given = given_btfs(cfg)
    return given[name] if name in given else root / "btf" / f"{name}.btf"
