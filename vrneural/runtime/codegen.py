"""Code generation: a :class:`~vrneural.material.NeuralMaterial` -> WGSL kernels.

The templates live in ``vrneural/shaders/`` (``texture_space.wgsl``, ``screen_space.wgsl``, both
importing ``neural_material.wgsl``, which reuses the ``mlp_body`` macro of ``mlp.wgsl``). The
network weights become WGSL constants in fully unrolled code (zero weights skipped), or, with
``buffer_weights=True``, they are read from a storage buffer in loops (the comparison baseline,
and the only sane choice for wide teachers such as a 128-wide reference network).

Specialisation: precision (``T`` = f32 | f16), the light count, the material's own layer sizes
and texture channel counts are template parameters; the radiance texture side ``R`` is a WGSL
``override`` constant.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vrneural.errors import VrnError
from vrneural.gpu.shaders import render_wgsl
from vrneural.material import ARCHS, NeuralMaterial
from vrneural.mlp import pack_weights

_ACT_CODE = {"relu": 0, "leaky_relu": 1, "none": 2}
PRECISIONS = ("auto", "f16", "f32")
#: Unrolled code above this many multiply-adds per texel is refused (compile time explodes).
MAX_UNROLLED_MACS = 20000


@dataclass
class MaterialSpec:
    """What the templates need to know about a material (shapes, weights, the variant)."""

    arch: str
    networks: dict
    output: str
    ca: int  # channels of texture a (coarse / features)
    cb: int  # channels of texture b (fine), 0 for "single"
    z: int  # latent size (coarse_fine), 0 otherwise
    buffer_weights: bool
    net_order: list
    n_layers: list
    max_width: int
    buf_dims_in: list
    buf_dims_out: list
    buf_offsets: list
    buf_acts: list


def material_spec(mat: NeuralMaterial, buffer_weights: bool = False) -> MaterialSpec:
    """Shapes and (for the buffer variant) layer tables of ``mat``."""
    nets, texs = ARCHS[mat.arch]
    layers = [lay for n in nets for lay in mat.networks[n]]
    dims_in = [lay.n_in for lay in layers]
    dims_out = [lay.n_out for lay in layers]
    offs, off = [], 0
    for lay in layers:
        offs.append(off)
        off += lay.n_in * lay.n_out + lay.n_out
    ca = mat.textures[texs[0]].shape[2]
    cb = mat.textures["fine"].shape[2] if mat.arch == "coarse_fine" else 0
    z = mat.networks["coarse"][-1].n_out if mat.arch == "coarse_fine" else 0
    return MaterialSpec(
        arch=mat.arch,
        networks={k: [_plain(lay) for lay in v] for k, v in mat.networks.items()},
        output=mat.output,
        ca=ca,
        cb=cb,
        z=z,
        buffer_weights=buffer_weights,
        net_order=list(nets),
        n_layers=[len(mat.networks[n]) for n in nets],
        max_width=max([*dims_in, *dims_out]),
        buf_dims_in=dims_in,
        buf_dims_out=dims_out,
        buf_offsets=offs,
        buf_acts=[_ACT_CODE[lay.act] for lay in layers],
    )


class _PlainLayer:
    """A layer with list weights (fast Jinja indexing)."""

    def __init__(self, lay):
        self.weight = lay.weight.astype(np.float32).tolist()
        self.bias = lay.bias.astype(np.float32).tolist()
        self.act = lay.act
        self.n_in = lay.n_in
        self.n_out = lay.n_out


def _plain(lay) -> _PlainLayer:
    return _PlainLayer(lay)


def packed_weights(mat: NeuralMaterial) -> np.ndarray:
    """All networks' weights in the storage-buffer layout, in arch order. ``[n]`` float32."""
    return np.concatenate([pack_weights(mat.networks[n]) for n in ARCHS[mat.arch][0]])


def resolve_precision(precision: str, is_cpu: bool, has_f16: bool) -> str:
    """``auto`` -> f32 on CPU adapters (f16 is emulated) or without shader-f16, else f16."""
    if precision not in PRECISIONS:
        raise VrnError(f"--precision = {precision!r} is not allowed; choose one of auto, f16, f32")
    if precision == "auto":
        return "f16" if has_f16 and not is_cpu else "f32"
    if precision == "f16" and not has_f16:
        raise VrnError("--precision = 'f16' needs the shader-f16 feature, which the adapter lacks")
    return precision


def _check_unroll(mat: NeuralMaterial, buffer_weights: bool) -> None:
    if not buffer_weights and mat.macs_per_texel > MAX_UNROLLED_MACS:
        raise VrnError(
            f"material {mat.meta.get('name', '?')!r} has {mat.macs_per_texel:.0f} MACs/texel; "
            f"unrolling is limited to {MAX_UNROLLED_MACS} (use buffer weights, e.g. --mode "
            "reference)"
        )


RADIANCE_FORMATS = ("rgba16float", "rgba32float")


def texture_space_wgsl(
    mat: NeuralMaterial,
    precision: str = "f32",
    n_lights: int = 1,
    buffer_weights: bool = False,
    radiance_format: str = "rgba16float",
    subgroups: bool = False,
) -> str:
    """WGSL of the texture-space pass for ``mat`` (see shaders/texture_space.wgsl);
    ``subgroups``: compaction with subgroup operations (device feature "subgroup")."""
    _check_unroll(mat, buffer_weights)
    if radiance_format not in RADIANCE_FORMATS:
        raise VrnError(f"radiance format {radiance_format!r} not in {RADIANCE_FORMATS}")
    return render_wgsl(
        "texture_space",
        T="f16" if precision == "f16" else "f32",
        mat=material_spec(mat, buffer_weights),
        n_lights=max(1, int(n_lights)),  # uniform array size (WGSL arrays are never empty)
        n_active=max(0, int(n_lights)),  # lights looped over: 0 lights -> black, no MLP work
        fmt=radiance_format,
        subgroups=subgroups,
    )


def screen_space_wgsl(
    mat: NeuralMaterial,
    precision: str = "f32",
    n_lights: int = 1,
    buffer_weights: bool = False,
    subgroups: bool = False,
) -> str:
    """WGSL of the per-pixel screen-space pass for ``mat`` (see shaders/screen_space.wgsl)."""
    _check_unroll(mat, buffer_weights)
    return render_wgsl(
        "screen_space",
        T="f16" if precision == "f16" else "f32",
        mat=material_spec(mat, buffer_weights),
        n_lights=max(1, int(n_lights)),  # uniform array size (WGSL arrays are never empty)
        n_active=max(0, int(n_lights)),  # lights looped over: 0 lights -> black, no MLP work
        subgroups=subgroups,
    )
