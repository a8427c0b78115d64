"""vrneural: neural materials at VR frame rates.

Pipeline: BTF -> teacher -> distilled 8-wide student -> runtime pack (.vrnm) -> generated WGSL
that shades per-eye radiance textures in texture space, reused for N frames.
"""

import importlib

__version__ = "0.1.0"


def lazy_exports(package: str, names: dict[str, str]):
    """A package's module ``__getattr__`` exporting ``names`` (name -> its submodule), each
    imported on first use: importing the package stays light (CLI start-up,
    tests/test_cli_startup.py)."""

    def getattr_(name: str):
        if name in names:
            return getattr(importlib.import_module(f"{package}.{names[name]}"), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return getattr_
