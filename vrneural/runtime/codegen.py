"""Code generation: a :class:`~vrneural.material.NeuralMaterial` -> WGSL kernels.

The templates live in ``vrneural/shaders/`` (``texture_space.wgsl``, ``screen_space.wgsl``, both
importing ``neural_material.wgsl``); they hold the structure, and the networks come in as WGSL
text generated in Python (:func:`vrneural.runtime.codegen_mlp.network_wgsl`). The network
weights become WGSL constants in fully unrolled code (zero weights skipped:
``weights="constants"``), or they are read in loops from buffers:

- ``"storage"``: one storage buffer, layer by layer over local arrays (the comparison baseline;
  narrow networks only: lavapipe gets large dynamically indexed local arrays wrong);
- ``"uniform"`` / ``"streamed"``: single-level networks of any width (the reference teacher),
  layers streamed in pairs with every activation a named value, weights from one uniform buffer
  per layer plus one of the biases (dynamically uniform loads: 8x cheaper than storage loads on
  lavapipe), or, where the layers do not fit uniform bindings, from the storage buffer.

Specialisation: precision (``T`` = f32 | f16), the light count, the material's own layer sizes
and texture channel counts are template parameters; the radiance texture side ``R`` is a WGSL
``override`` constant.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import accumulate

import numpy as np

from vrneural.errors import VrnError, check_int
from vrneural.gpu.shaders import render_wgsl
from vrneural.grazing import boundary_consts
from vrneural.material import ARCHS, NeuralMaterial
from vrneural.mlp import pack_weights, wgsl_type
from vrneural.parallax import AUTO_BLOCK_FOOT_TEXELS, height_bounds
from vrneural.runtime.codegen_mlp import network_wgsl
from vrneural.runtime.codegen_sample import FILTERS, samplers_wgsl
from vrneural.runtime.interface import (
    LIGHT,
    SCREEN_PARAMS,
    TEXTURE_PARAMS,
    screen_bindings,
    structs_wgsl,
    texture_bindings,
)
from vrneural.runtime.reference import STRETCH_MAX
from vrneural.runtime.settings import LOD_TAPS_MAX

PRECISIONS = ("auto", "f16", "f32")
WEIGHTS = ("constants", "storage", "uniform", "streamed")
#: WebGPU's guaranteed uniform limits: bytes per binding, uniform buffers per shader stage; the
#: passes bind two of their own (params, lights).
UNIFORM_BINDING_BYTES = 65536
UNIFORM_BUFFERS_PER_STAGE = 12
PASS_UNIFORMS = 2
#: widest layer the "storage" variant takes: lavapipe computed wrong results for a 64-wide
#: single-level net in the texture pass (dynamically indexed local arrays of 4 x 64 floats)
STORAGE_MAX_WIDTH = 32
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
    weights: str  # one of WEIGHTS
    net_order: list
    n_layers: list
    max_width: int
    buf_dims_in: list
    buf_dims_out: list
    buf_offsets: list
    buf_acts: list  # activation names (vrneural.mlp.ACTIVATIONS)
    buf_bias_offsets: list  # per layer, into the uniform bias buffer (uniform weights)
    #: WGSL literals of (cos, sin) of theta_i_max, then of theta_o_max (the data's direction
    #: range, vrneural.grazing); exact float32 values, as the numpy twin uses
    dir_consts: tuple = ()
    #: pyramid levels of the neural textures (1: level 0 alone; more: LOD lookups in the
    #: texture-space pass)
    lod_levels: int = 1
    #: height-field parallax march steps (0: off) and the WGSL literals (hmin, hmax, W / H)
    parallax_steps: int = 0
    parallax_march: str = "texel"
    height_consts: tuple = ()
    #: NeuMIP's neural offset (parallax kind "neural"): the offset MLP's layers (None: off),
    #: the offset texture's channels and the WGSL literals (W, H) of its texel grid
    offset_net: list | None = None
    offset_ch: int = 0
    offset_consts: tuple = ()
    #: how the kernels filter the neural textures (and the height field): "exact" or
    #: "hardware" (runtime/codegen_sample.py:FILTERS)
    filtering: str = "exact"


def reference_weights(mat: NeuralMaterial) -> str:
    """The buffer-weight variant for a per-pixel reference network: streamed from uniform
    buffers where they hold it, else streamed from the storage buffer; a coarse-to-fine pack
    (narrow by design) layer by layer from the storage buffer."""
    if mat.arch != "single":
        width = _max_width(mat)
        if width > STORAGE_MAX_WIDTH:
            raise VrnError(
                f"--mode reference takes coarse-to-fine packs whose layers have at most "
                f"{STORAGE_MAX_WIDTH} inputs and outputs; this one has {width} (wide references "
                "must be single-level networks, e.g. a teacher); render it with --mode screen"
            )
        return "storage"
    return "uniform" if uniform_weights_fit(mat) else "streamed"


def uniform_weights_fit(mat: NeuralMaterial) -> bool:
    """Whether ``weights="uniform"`` can hold ``mat``: every layer's matrix within one uniform
    binding, and a binding per layer plus one for the biases within the per-stage limit."""
    layers = _layers(mat)
    biases = sum(lay.n_out for lay in layers)
    return (
        all(lay.n_in * lay.n_out * 4 <= UNIFORM_BINDING_BYTES for lay in layers)
        and biases * 4 <= UNIFORM_BINDING_BYTES
        and len(layers) + 1 + PASS_UNIFORMS <= UNIFORM_BUFFERS_PER_STAGE
    )


def _check_weights(mat: NeuralMaterial, weights: str) -> None:
    if weights not in WEIGHTS:
        raise VrnError(f"weights = {weights!r} is not allowed; choose one of {', '.join(WEIGHTS)}")
    if weights == "storage" and _max_width(mat) > STORAGE_MAX_WIDTH:
        raise VrnError(
            f"material {mat.meta.get('name', '?')!r}: storage weights take layers up to "
            f"{STORAGE_MAX_WIDTH} wide (wider ones: streamed or uniform weights)"
        )
    if weights in ("uniform", "streamed") and mat.arch != "single":
        raise VrnError(f"weights = {weights!r} needs a single-level network, not {mat.arch!r}")
    if weights == "uniform" and not uniform_weights_fit(mat):
        raise VrnError(
            f"material {mat.meta.get('name', '?')!r} does not fit uniform-buffer weights (a layer "
            f"over {UNIFORM_BINDING_BYTES} bytes, or over "
            f"{UNIFORM_BUFFERS_PER_STAGE - PASS_UNIFORMS - 1} layers); use streamed weights"
        )
    if weights == "constants" and mat.macs_per_texel > MAX_UNROLLED_MACS:
        if mat.meta.get("method") == "teacher":  # the usual way here: a teacher as --pack
            raise VrnError(
                f"material {mat.meta.get('name', '?')!r} is a teacher pack "
                f"({mat.macs_per_texel:.0f} MACs/texel, above the {MAX_UNROLLED_MACS} that "
                "texture and screen modes unroll into shaders): render it with --mode "
                "reference, or distill a student from its checkpoint (`vrneural distill`)"
            )
        raise VrnError(
            f"material {mat.meta.get('name', '?')!r} has {mat.macs_per_texel:.0f} MACs/texel; "
            f"unrolling is limited to {MAX_UNROLLED_MACS} (use buffer weights, e.g. --mode "
            "reference)"
        )


def _layers(mat: NeuralMaterial) -> list:
    """Every layer of ``mat``'s networks, in arch order (the buffer layouts' order)."""
    return [lay for n in ARCHS[mat.arch][0] for lay in mat.networks[n]]


def _max_width(mat: NeuralMaterial) -> int:
    """The most inputs or outputs of any layer (the local arrays' size in "storage")."""
    return max(max(lay.n_in, lay.n_out) for lay in _layers(mat))


def material_spec(
    mat: NeuralMaterial, weights: str = "constants", filtering: str = "exact"
) -> MaterialSpec:
    """Shapes and (for the buffer variant) layer tables of ``mat``; ``filtering``: one of
    :data:`~vrneural.runtime.codegen_sample.FILTERS`."""
    if filtering not in FILTERS:
        raise VrnError(f"neural filter = {filtering!r} is not allowed; choose one of {FILTERS}")
    nets, texs = ARCHS[mat.arch]
    layers = _layers(mat)
    dims_in = [lay.n_in for lay in layers]
    dims_out = [lay.n_out for lay in layers]
    offs = list(accumulate((lay.n_in * lay.n_out + lay.n_out for lay in layers[:-1]), initial=0))
    ca = mat.textures[texs[0]].shape[2]
    cb = mat.textures["fine"].shape[2] if mat.arch == "coarse_fine" else 0
    z = mat.networks["coarse"][-1].n_out if mat.arch == "coarse_fine" else 0
    return MaterialSpec(
        arch=mat.arch,
        networks=dict(mat.networks),
        output=mat.output,
        ca=ca,
        cb=cb,
        z=z,
        weights=weights,
        net_order=list(nets),
        n_layers=[len(mat.networks[n]) for n in nets],
        max_width=_max_width(mat),
        buf_dims_in=dims_in,
        buf_dims_out=dims_out,
        buf_offsets=offs,
        buf_acts=[lay.act for lay in layers],
        buf_bias_offsets=list(accumulate(dims_out[:-1], initial=0)),
        dir_consts=tuple(repr(float(c)) for t in mat.dir_range for c in boundary_consts(t)),
        lod_levels=mat.lod_levels,
        parallax_steps=mat.parallax_steps,
        parallax_march=mat.parallax_march,
        height_consts=_height_consts(mat),
        **_offset_fields(mat),
        filtering=filtering,
    )


def _offset_fields(mat: NeuralMaterial) -> dict:
    """The spec's neural-offset fields of ``mat`` (none without a neural offset)."""
    if mat.parallax_kind != "neural":
        return {}
    H, W = mat.offset_tex.shape[:2]
    return {
        "offset_net": list(mat.offset_net),
        "offset_ch": int(mat.offset_tex.shape[2]),
        "offset_consts": (repr(float(np.float32(W))), repr(float(np.float32(H)))),
    }


def _height_consts(mat: NeuralMaterial) -> tuple:
    """WGSL literals ``(hmin, hmax, W / H, slope max)`` of a parallax material's height field
    (exact float32 values, as the numpy twin uses); ``()`` without parallax."""
    if not mat.parallax_steps:
        return ()

    lo, hi = height_bounds(mat.height)
    H, W = mat.height.shape
    vals = (lo, hi, np.float32(W / H), mat.parallax_slope_max)
    return tuple(repr(float(v)) for v in vals)


def packed_weights(mat: NeuralMaterial) -> np.ndarray:
    """All networks' weights in the storage-buffer layout, in arch order. ``[n]`` float32."""
    return np.concatenate([pack_weights(mat.networks[n]) for n in ARCHS[mat.arch][0]])


def uniform_weights(mat: NeuralMaterial) -> list[np.ndarray]:
    """The uniform-buffer layout: one float32 array per layer (``W [out, in]`` row-major), then
    one of all biases in layer order; each zero-padded to whole ``vec4``s."""
    layers = _layers(mat)
    parts = [np.asarray(lay.weight, np.float32).ravel() for lay in layers]
    parts.append(np.concatenate([np.asarray(lay.bias, np.float32) for lay in layers]))
    return [np.concatenate([p, np.zeros(-len(p) % 4, np.float32)]) for p in parts]


def resolve_precision(precision: str, is_cpu: bool, has_f16: bool) -> str:
    """``auto`` -> f32 on CPU adapters (f16 is emulated) or without shader-f16, else f16."""
    if precision not in PRECISIONS:
        raise VrnError(f"--precision = {precision!r} is not allowed; choose one of auto, f16, f32")
    if precision == "auto":
        return "f16" if has_f16 and not is_cpu else "f32"
    if precision == "f16" and not has_f16:
        raise VrnError("--precision = 'f16' needs the shader-f16 feature, which the adapter lacks")
    return precision


RADIANCE_FORMATS = ("rgba16float", "rgba32float")


def check_taps(taps) -> int:
    """``taps`` (footprint taps per axis, ``Settings.lod_taps``) as an int, or a one-line error
    naming the allowed range."""
    check_int("--lod-taps", taps, 1, LOD_TAPS_MAX)
    return int(taps)


def texture_space_wgsl(
    mat: NeuralMaterial,
    precision: str = "f32",
    n_lights: int = 1,
    weights: str = "constants",
    radiance_format: str = "rgba16float",
    subgroups: bool = False,
    filtering: str = "exact",
    taps: int = 1,
) -> str:
    """WGSL of the texture-space pass for ``mat`` (see shaders/texture_space.wgsl);
    ``subgroups``: compaction with subgroup operations (device feature "subgroup");
    ``filtering``: how neural textures are filtered (codegen_sample.FILTERS); ``taps``: the
    most footprint taps per axis (``Settings.lod_taps``; 1: none, the code of before)."""
    _check_weights(mat, weights)
    if radiance_format not in RADIANCE_FORMATS:
        raise VrnError(f"radiance format {radiance_format!r} not in {RADIANCE_FORMATS}")
    T, spec = wgsl_type(precision), material_spec(mat, weights, filtering)
    return render_wgsl(
        "texture_space",
        T=T,
        mat=spec,
        nets=network_wgsl(spec, T),
        samplers=samplers_wgsl(spec),
        structs=structs_wgsl(TEXTURE_PARAMS, LIGHT),
        bindings=texture_bindings(spec, n_lights, radiance_format).wgsl(),
        n_active=max(0, int(n_lights)),  # lights looped over: 0 lights -> black, no MLP work
        fmt=radiance_format,
        subgroups=subgroups,
        auto_foot=repr(float(AUTO_BLOCK_FOOT_TEXELS)),
        march_side=repr(float(max(mat.march_grid[:2], default=0))),  # the grid's larger side
        taps=check_taps(taps),
        stretch_max=STRETCH_MAX,
    )


def screen_space_wgsl(
    mat: NeuralMaterial,
    precision: str = "f32",
    n_lights: int = 1,
    weights: str = "constants",
    subgroups: bool = False,
    filtering: str = "exact",
) -> str:
    """WGSL of the per-pixel screen-space pass for ``mat`` (see shaders/screen_space.wgsl)."""
    _check_weights(mat, weights)
    T, spec = wgsl_type(precision), material_spec(mat, weights, filtering)
    return render_wgsl(
        "screen_space",
        T=T,
        mat=spec,
        nets=network_wgsl(spec, T),
        samplers=samplers_wgsl(spec),
        structs=structs_wgsl(SCREEN_PARAMS, LIGHT),
        bindings=screen_bindings(spec, n_lights).wgsl(),
        n_active=max(0, int(n_lights)),  # lights looped over: 0 lights -> black, no MLP work
        subgroups=subgroups,
    )
