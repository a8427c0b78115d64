"""The runtime pack (``.vrnm``): one neural material, readable with numpy alone. No pickle.

Container (:mod:`vrneural.formats.container`), magic ``b"VRNM"``, version 5. Header::

    {"arch": "coarse_fine" | "single", "output": "linear" | "log1p",
     "networks": {name: [{"n_in": int, "n_out": int, "act": str}, ...]},
     "textures": {name: [H, W, C]},
     "dir_range": [theta_i_max, theta_o_max],   # degrees, each in (0, 90); since version 2
     "levels": {name: n},   # pyramid levels 1..n-1 of each neural texture; since version 3
     "parallax": {"kind": "height", "steps": n, "march": m} | {"kind": "off"},   # since 4
                 | {"kind": "neural", "march": m},   # since version 5
     "offset": [{"n_in", "n_out", "act"}, ...],   # the neural offset's MLP (kind neural)
     "meta": {"name": ..., "provenance": {...}, "metrics": {...}, "ranges": {...}}}

Version 1 packs (no ``dir_range``) load with the default 75 degrees, said once per file;
packs before version 4 (no height field) load with parallax off, said once per file.

Arrays: ``net.<name>.<i>.weight`` ``[out, in]`` float32, ``net.<name>.<i>.bias`` ``[out]``
float32, ``tex.<name>`` ``[H, W, C]`` float16 and its levels ``tex.<name>.<k>`` ``[H >> k,
W >> k, C]``, ``height`` ``[H, W]`` float16 (UV units, the fine / features texels; present
when the material has one, :mod:`vrneural.parallax`), ``offset.<i>.weight`` / ``.bias`` and
``tex.offset`` ``[H, W, C]`` float16 (NeuMIP's neural offset, :mod:`vrneural.neural_offset`;
kind ``neural`` only), each with a CRC32. Writing refuses NaN/Inf.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from vrneural.errors import VrnError
from vrneural.formats.container import read_container, write_container
from vrneural.grazing import DEFAULT_THETA_MAX_DEG
from vrneural.material import NeuralMaterial
from vrneural.mlp import Layer
from vrneural.parallax import MARCHES

VRNM_MAGIC = b"VRNM"
VRNM_VERSION = 5
#: versions this reader takes (1: before the recorded direction range; 2: before pyramids;
#: 3: before height fields; 4: before the neural offset)
VRNM_READS = (1, 2, 3, 4, 5)
_said: set[tuple[str, str]] = set()  # (file, message) said by _said_once


def write_vrnm(path, mat: NeuralMaterial) -> Path:
    """Write ``mat`` atomically. Raises :class:`VrnError` on non-finite weights or textures."""
    arrays: dict[str, np.ndarray] = {}

    def put_layers(prefix: str, layers) -> list[dict]:
        for i, lay in enumerate(layers):
            arrays[f"{prefix}.{i}.weight"] = np.asarray(lay.weight, np.float32)
            arrays[f"{prefix}.{i}.bias"] = np.asarray(lay.bias, np.float32)
        return [{"n_in": lay.n_in, "n_out": lay.n_out, "act": lay.act} for lay in layers]

    nets = {name: put_layers(f"net.{name}", layers) for name, layers in mat.networks.items()}
    for name, t in mat.textures.items():
        if not np.isfinite(np.asarray(t, np.float32)).all():
            raise VrnError(f"{path}: neural texture '{name}' contains NaN/Inf (f16 overflow?)")
        arrays[f"tex.{name}"] = np.asarray(t, np.float16)
        for k, lv in enumerate(mat.levels.get(name, []), 1):
            arrays[f"tex.{name}.{k}"] = np.asarray(lv, np.float16)
    if mat.height is not None:
        arrays["height"] = np.asarray(mat.height, np.float16)
    offset = None
    if mat.offset_net is not None:
        offset = put_layers("offset", mat.offset_net)
        arrays["tex.offset"] = np.asarray(mat.offset_tex, np.float16)
    for k, a in arrays.items():
        if not np.isfinite(a).all():
            raise VrnError(f"{path}: refusing to write non-finite values in '{k}'")
    header = {
        "arch": mat.arch,
        "output": mat.output,
        "networks": nets,
        "textures": {k: list(t.shape) for k, t in mat.textures.items()},
        "dir_range": [float(x) for x in mat.dir_range],
        "levels": {k: 1 + len(mat.levels.get(k, [])) for k in mat.textures},
        "parallax": dict(mat.parallax),
        "meta": mat.meta,
    }
    if offset is not None:
        header["offset"] = offset
    return write_container(path, VRNM_MAGIC, VRNM_VERSION, header, arrays)


def read_vrnm(path) -> NeuralMaterial:
    """Read and validate a ``.vrnm`` pack into a :class:`NeuralMaterial`."""
    header, arrays, version = read_container(path, VRNM_MAGIC, VRNM_READS, what="runtime pack")
    try:
        nets = {
            name: _layers(path, arrays, f"net.{name}", specs)
            for name, specs in header["networks"].items()
        }
        offset_net = offset_tex = None
        if version >= 5 and "offset" in header:
            offset_net = _layers(path, arrays, "offset", header["offset"])
            offset_tex = np.array(arrays["tex.offset"], np.float16)
        texs = {name: np.array(arrays[f"tex.{name}"], np.float16) for name in header["textures"]}
        if version >= 2:
            dir_range = header["dir_range"]
        else:  # none recorded: the default, said once
            dir_range = (DEFAULT_THETA_MAX_DEG, DEFAULT_THETA_MAX_DEG)
            _said_once(
                path,
                "pack from before recorded direction ranges; assuming the BTF's directions reach "
                f"{DEFAULT_THETA_MAX_DEG:g} degrees (re-export it to record its own)",
            )
        counts = header["levels"] if version >= 3 else {}
        levels = {
            name: [np.array(arrays[f"tex.{name}.{k}"], np.float16) for k in range(1, int(n))]
            for name, n in counts.items()
            if int(n) > 1
        }
        if version >= 4:
            parallax = header["parallax"]
            if parallax.get("march", "texel") not in MARCHES:  # "auto" is the renderer's
                raise ValueError(f"parallax march {parallax['march']!r} not in {MARCHES}")
            height = np.array(arrays["height"], np.float16) if "height" in arrays else None
        else:
            parallax, height = {"kind": "off"}, None
            _said_once(
                path,
                "pack from before height fields (format < 4); parallax off (re-distill with "
                "--parallax to give it one)",
            )
        for k, a in arrays.items():  # before the material checks its height field
            if not np.isfinite(np.asarray(a, np.float32)).all():
                raise VrnError(f"{path}: '{k}' contains NaN/Inf")
        mat = NeuralMaterial(
            header["arch"], nets, texs, header["output"], header.get("meta", {}), dir_range,
            levels, parallax, height, offset_net, offset_tex,
        )  # fmt: skip
    except KeyError as e:
        raise VrnError(f"{path}: runtime pack lacks {e}") from None
    except (ValueError, TypeError, AttributeError) as e:
        raise VrnError(f"{path}: invalid runtime pack: {e}") from None
    return mat


def _layers(path, arrays: dict, prefix: str, specs: list) -> list[Layer]:
    """The layers ``<prefix>.<i>.weight`` / ``.bias`` of a pack, checked against the header."""
    layers = []
    for i, s in enumerate(specs):
        w = np.array(arrays[f"{prefix}.{i}.weight"], np.float32)
        b = np.array(arrays[f"{prefix}.{i}.bias"], np.float32)
        if w.shape != (s["n_out"], s["n_in"]):
            raise VrnError(
                f"{path}: {prefix}.{i}.weight has shape {list(w.shape)}, "
                f"header says [{s['n_out']}, {s['n_in']}]"
            )
        layers.append(Layer(w, b, s["act"]))
    return layers


def _said_once(path, message: str) -> None:
    """Print ``path: message`` on stderr, once per file and message (an old pack's default)."""
    key = (str(Path(path).resolve()), message)
    if key not in _said:
        _said.add(key)
        print(f"{path}: {message}", file=sys.stderr)
