"""Tabulated BTFs: the file format, direction sets, a synthetic generator, UBO2014 import."""

from vrneural import lazy_exports

_FORMAT = ["BTF_MAGIC", "BTF_VERSION", "Btf", "BtfWriter", "read_btf", "write_btf"]
_FROM = {**dict.fromkeys(_FORMAT, "format"), "direction_set": "dirs", "ubo2014_directions": "dirs"}
__all__ = list(_FROM)
__getattr__ = lazy_exports(__name__, _FROM)  # numpy and tqdm on first use
