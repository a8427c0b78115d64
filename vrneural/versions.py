"""Versions of the packages that shape results, recorded in `vrneural info` and every result."""

from __future__ import annotations

import platform
from importlib import metadata

PACKAGES = (
    "vrneural",
    "wgpu",
    "numpy",
    "trimesh",
    "xatlas",
    "imageio",
    "OpenImageIO",
    "torch",
    "matplotlib",
    "flip-evaluator",
)


def package_versions() -> dict[str, str | None]:
    """``{"python": ..., "machine": ..., <package>: version or None}``."""
    out: dict[str, str | None] = {
        "python": platform.python_version(),
        "machine": platform.machine(),
    }
    for name in PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out
