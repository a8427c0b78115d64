"""Tabulated BTFs: the file format, direction sets, a synthetic generator, UBO2014 import."""

import importlib

_FROM = {"direction_set": "dirs", "ubo2014_directions": "dirs"}
__all__ = ["BTF_MAGIC", "BTF_VERSION", "Btf", "BtfWriter", "read_btf", "write_btf", *_FROM]


def __getattr__(name: str):  # numpy and tqdm: on first use, not with the package (CLI start-up)
    if name in __all__:
        return getattr(importlib.import_module(f"vrneural.btf.{_FROM.get(name, 'format')}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
