"""Tabulated BTFs: the file format, direction sets, a synthetic generator, UBO2014 import."""

from vrneural.btf.dirs import direction_set, ubo2014_directions
from vrneural.btf.format import BTF_MAGIC, BTF_VERSION, Btf, BtfWriter, read_btf, write_btf

__all__ = [
    "BTF_MAGIC",
    "BTF_VERSION",
    "Btf",
    "BtfWriter",
    "direction_set",
    "read_btf",
    "ubo2014_directions",
    "write_btf",
]
