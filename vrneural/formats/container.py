"""A small versioned container for named numpy arrays plus a JSON header. No pickle.

Layout (little endian)::

    0   magic         8 bytes, names the format (e.g. b"VRNBTF\\0\\0", b"VRNM\\0\\0\\0\\0")
    8   version       uint32, the format's version
    12  header_crc    uint32, CRC32 of the header bytes
    16  header_len    uint64
    24  header        UTF-8 JSON; header["arrays"][name] = {dtype, shape, offset, nbytes[, crc32]}
    ..  arrays        raw C-order data, each starting on a 64-byte boundary

Arrays are memory-mapped on read, so a 22 GB BTF can be read one slice at a time. The reader
validates magic, version, header checksum, declared shapes against sizes, and the file length
(truncation), and raises :class:`~vrneural.errors.VrnError` with the file name on any mismatch.

While a file is being written its header carries ``"partial": true`` (its arrays are still
being filled); :meth:`ContainerWriter.finalize` rewrites the header without it. The reader
refuses a file so marked (an interrupted write copied or renamed), unless asked to continue it.
Files written before the marker existed have no such key and read as before.
"""

from __future__ import annotations

import json
import os
import struct
import zlib
from pathlib import Path

import numpy as np

from vrneural.errors import VrnError, input_file
from vrneural.outputs.files import partial_path

#: the magic of every vrneural container format -> what to call it in an error
_KNOWN_MAGIC = {
    b"VRNBTF": "a BTF file",
    b"VRNM": "a runtime pack",
    b"VRNATLAS": "an atlas cache entry",
}

_PREFIX = struct.Struct("<8sIIQ")
_ALIGN = 64
_DTYPES = {"float16", "float32", "float64", "uint8", "uint16", "uint32", "int32", "int64"}


def _layout(header: dict, specs: dict[str, tuple[tuple[int, ...], str]]) -> tuple[int, dict, int]:
    """Reserve the header and assign array offsets. Returns (header length, table, file size).

    The header is padded with spaces (valid JSON whitespace) to a reserved length that leaves
    room for the offsets, so offsets can be computed before the final header text is known.
    """
    for dtype in (d for _, d in specs.values()):
        if dtype not in _DTYPES:
            raise ValueError(f"unsupported dtype {dtype}")
    draft = json.dumps(dict(header, arrays={k: {} for k in specs}), sort_keys=True)
    hlen = _align(len(draft) + 160 * (len(specs) + 1))
    off = _align(_PREFIX.size + hlen)
    table: dict[str, dict] = {}
    for name, (shape, dtype) in specs.items():
        nbytes = int(np.prod(shape, dtype=np.int64)) * np.dtype(dtype).itemsize
        table[name] = {
            "dtype": dtype,
            "shape": [int(s) for s in shape],
            "offset": off,
            "nbytes": nbytes,
        }
        off = _align(off + nbytes)
    return hlen, table, off


def _header_bytes(header: dict, table: dict, file_size: int, hlen: int) -> bytes:
    """The header text padded to its reserved length ``hlen``."""
    raw = json.dumps(dict(header, arrays=table, file_size=file_size), sort_keys=True).encode()
    assert len(raw) <= hlen, "header reservation too small"
    return raw + b" " * (hlen - len(raw))


def _align(n: int) -> int:
    return (n + _ALIGN - 1) // _ALIGN * _ALIGN


class ContainerWriter:
    """Create a container whose arrays are filled later (streaming), then :meth:`finalize`.

    Data goes to ``<path>.partial``; only :meth:`finalize` renames it to ``path``. With
    ``resume=True`` an existing partial file with an identical header is reopened, so an
    interrupted long write (a 22 GB BTF) can continue where it stopped.
    """

    def __init__(
        self,
        path,
        magic: bytes,
        version: int,
        header: dict,
        specs: dict[str, tuple[tuple[int, ...], str]],
        resume: bool = False,
    ):
        self.path = Path(path)
        self.partial = partial_path(self.path)
        self.magic = magic.ljust(8, b"\0")
        self.version = version
        marked = dict(header, partial=True)  # until finalize (see the module docstring)
        hlen, self.table, self.file_size = _layout(marked, specs)
        self._final = _header_bytes(header, self.table, self.file_size, hlen)
        start = self._prefixed(_header_bytes(marked, self.table, self.file_size, hlen))
        self.resumed = False
        if resume and self.partial.exists():
            with open(self.partial, "rb") as f:
                old = f.read(len(start))
            # an unmarked header: a partial file of a release before the marker
            same = old in (start, self._prefixed(self._final))
            if same and self.partial.stat().st_size == self.file_size:
                self.resumed = True
            else:  # never overwrite an interrupted write that resume was asked to continue
                raise VrnError(
                    f"{self.partial}: an interrupted write with a different header or size; "
                    "it cannot be continued with these settings"
                )
        if not self.resumed:
            from vrneural.outputs import check_free_space, make_parent

            old_size = self.partial.stat().st_size if self.partial.is_file() else 0
            check_free_space(self.path, self.file_size, reclaimed=old_size)
            make_parent(self.partial)
            try:
                with open(self.partial, "wb") as f:
                    f.write(start)
                    f.truncate(self.file_size)
            except OSError as e:
                raise VrnError(f"{self.partial}: cannot write ({e.strerror or e})") from None

    def _prefixed(self, hbytes: bytes) -> bytes:
        return _PREFIX.pack(self.magic, self.version, zlib.crc32(hbytes), len(hbytes)) + hbytes

    def array(self, name: str) -> np.memmap:
        """A writable memory map of array ``name``."""
        a = self.table[name]
        return np.memmap(
            self.partial, dtype=a["dtype"], mode="r+", offset=a["offset"], shape=tuple(a["shape"])
        )

    def finalize(self) -> Path:
        """Clear the partial mark, flush and move the finished file into place (atomic rename)."""
        try:
            with open(self.partial, "rb+") as f:
                f.write(self._prefixed(self._final))
                f.flush()
                os.fsync(f.fileno())
            os.replace(self.partial, self.path)
        except OSError as e:
            raise VrnError(f"{self.path}: cannot write ({e.strerror or e})") from None
        return self.path


def write_container(
    path, magic: bytes, version: int, header: dict, arrays: dict[str, np.ndarray]
) -> Path:
    """Write whole arrays at once (atomically), with a CRC32 per array."""
    arrays = {k: np.ascontiguousarray(v) for k, v in arrays.items()}
    crcs = {k: zlib.crc32(v.tobytes()) for k, v in arrays.items()}
    header = dict(header, array_crc32=crcs)
    w = ContainerWriter(
        path, magic, version, header, {k: (v.shape, str(v.dtype)) for k, v in arrays.items()}
    )
    try:
        with open(w.partial, "rb+") as f:
            for k, v in arrays.items():
                f.seek(w.table[k]["offset"])
                f.write(v.tobytes())
        return w.finalize()
    except OSError as e:  # a full disk
        raise VrnError(f"{path}: cannot write ({e.strerror or e})") from None
    finally:
        if w.partial.exists():
            w.partial.unlink()


def read_container(
    path,
    magic: bytes,
    versions: tuple[int, ...],
    what: str = "file",
    verify_crc: bool = True,
    partial: bool = False,
) -> tuple[dict, dict[str, np.ndarray], int]:
    """Open and validate a container. Returns ``(header, arrays, version)``.

    Arrays are read-only memory maps. ``what`` names the format in error messages. A file
    still being written (or left by an interrupted write) is refused unless ``partial``.
    """
    p = input_file(path, f"a {what}")
    size = p.stat().st_size
    magic = magic.ljust(8, b"\0")
    with open(p, "rb") as f:
        pre = f.read(_PREFIX.size)
        if pre.lstrip()[:1] in (b"{", b"["):  # the .config.json beside an output, say
            raise VrnError(f"{p}: is a JSON file (text), not a {what}")
        if len(pre) < _PREFIX.size:
            raise VrnError(f"{p}: truncated ({size} bytes), not a {what}")
        got_magic, version, crc, hlen = _PREFIX.unpack(pre)
        if got_magic != magic:
            if got_magic.startswith(b"PK\x03\x04"):  # a zip: what torch.save writes
                hint = "; `vrneural export CHECKPOINT -o PACK.vrnm` makes one"
                raise VrnError(
                    f"{p}: wrong magic (a zip, probably a PyTorch checkpoint), not a {what}"
                    + (hint if what == "runtime pack" else "")
                )
            other = _KNOWN_MAGIC.get(got_magic.rstrip(b"\0"))
            if other is not None:  # one of our other formats: say which
                hint = (
                    "; `vrneural teach` trains a teacher on it, `vrneural distill` a student"
                    if other == "a BTF file" and what == "runtime pack"
                    else ""
                )
                raise VrnError(f"{p}: is {other}, expected a {what}{hint}")
            if got_magic.startswith(b"!DFMF"):  # a measured UBO2014 BTF, not converted yet
                raise VrnError(
                    f"{p}: is a UBO2014 BTF (magic {got_magic!r}), not a {what}; convert it "
                    "with `vrneural btf import UBO.btf -o OUT.btf`"
                )
            raise VrnError(f"{p}: wrong magic {got_magic!r}, not a {what} (expected {magic!r})")
        if version not in versions:
            raise VrnError(
                f"{p}: {what} version {version} is not supported "
                f"(this vrneural reads {', '.join(map(str, versions))})"
            )
        if hlen > size:
            raise VrnError(f"{p}: truncated header ({size} bytes, header claims {hlen})")
        hbytes = f.read(hlen)
    if len(hbytes) != hlen or zlib.crc32(hbytes) != crc:
        raise VrnError(f"{p}: corrupt header (checksum mismatch)")
    try:
        header = json.loads(hbytes)
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise VrnError(f"{p}: corrupt header (not JSON)") from None
    if not partial and (header.get("partial") or p.name.endswith(".partial")):
        raise VrnError(
            f"{p}: an unfinished {what} (an interrupted write, not all of its data is there); "
            "finish it with the --resume of the command that wrote it"
        )
    need = int(header.get("file_size", -1))
    if size < need:
        raise VrnError(f"{p}: truncated: {size} bytes, expected {need}")
    arrays: dict[str, np.ndarray] = {}
    crcs = header.get("array_crc32", {}) if verify_crc else {}
    for name, a in header.get("arrays", {}).items():
        shape = tuple(a["shape"])
        if (
            a["dtype"] not in _DTYPES
            or a["nbytes"] != int(np.prod(shape, dtype=np.int64)) * np.dtype(a["dtype"]).itemsize
        ):
            raise VrnError(
                f"{p}: array '{name}' has shape {list(shape)} / dtype {a['dtype']} "
                f"inconsistent with its size {a['nbytes']}"
            )
        if a["offset"] + a["nbytes"] > size:
            raise VrnError(f"{p}: truncated inside array '{name}'")
        arr = (
            np.memmap(p, dtype=a["dtype"], mode="r", offset=a["offset"], shape=shape)
            if a["nbytes"]
            else np.zeros(shape, a["dtype"])
        )
        if name in crcs and zlib.crc32(np.ascontiguousarray(arr).tobytes()) != crcs[name]:
            raise VrnError(f"{p}: array '{name}' is corrupt (checksum mismatch)")
        arrays[name] = arr
    return header, arrays, version
