"""Neural materials as plain data, and their numpy evaluation (the reference every other
implementation, torch or WGSL, must match).

A material maps ``(u, wi, wo)`` to a BTF value (RGB, docs/conventions.md section 2 convention).

Architectures (``arch``):

``"coarse_fine"`` (the paper's student, Eq. 3-4)
    ``z_c = M_c([wi, wo, h, U_c(u_c)])`` once per 2x2 texel block at the block's mean material
    UV ``u_c``; then ``y_k = out(M_f([z_c, U_f(u_k)]))`` for each of the block's 4 texels.
    networks ``"coarse"`` and ``"fine"``; textures ``"coarse"`` (U_c) and ``"fine"`` (U_f).
``"single"`` (the single-level baselines: 8-wide ablation, NeuMIP-sized)
    ``y_k = out(M([wi, wo, h, U(u_k)]))`` per texel. network ``"mlp"``; texture ``"features"``.

Shared definitions:

- directions are unit vectors in the local frame; ``h = normalize(wi + wo)``, or ``(0, 0, 1)``
  when ``|wi + wo|^2 < 1e-12`` (see :func:`half_vector`);
- neural textures ``[H, W, C]`` float16 are sampled bilinearly with wrap-around addressing,
  texel ``(x, y)`` centred at UV ``((x + 0.5) / W, (y + 0.5) / H)`` (:func:`sample_bilinear_wrap`);
- ``output`` transform of the last layer's raw value ``r``: ``"linear"``: ``max(r, 0)``;
  ``"log1p"``: ``expm1(max(r, 0))`` (the network predicts ``log(1 + y)``);
- neural textures may carry prefiltered pyramid levels (``levels[name]``: level 1, 2, ... each
  half the previous side): a lookup at a level of detail ``lod`` blends the bilinear lookups of
  levels ``floor(lod)`` and ``floor(lod) + 1`` (:func:`sample_lod`);
- directions beyond the training data's range ``dir_range`` (the largest light and view polar
  angles of its BTF) are extended as :mod:`vrneural.grazing` defines: the network is evaluated
  at the range's boundary, a light's value tapering to 0 at the horizon.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from vrneural.errors import VrnError
from vrneural.grazing import DEFAULT_THETA_MAX_DEG, boundary_consts, check_dir_range, extend
from vrneural.mlp import Layer, macs, mlp_forward, random_mlp
from vrneural.parallax import PACK_KINDS, check_pack_height, slope_max
from vrneural.sampling import sample_bilinear_wrap

ARCHS = {
    "coarse_fine": (("coarse", "fine"), ("coarse", "fine")),
    "single": (("mlp",), ("features",)),
}
OUTPUTS = ("linear", "log1p")
DIR_INPUTS = 9  # wi, wo, h
HALF_EPS2 = 1e-12


@dataclass
class NeuralMaterial:
    """Weights, neural textures and metadata of one material (what a ``.vrnm`` file holds)."""

    arch: str
    networks: dict[str, list[Layer]]
    textures: dict[str, np.ndarray]  # name -> [H, W, C] float16
    output: str = "linear"
    meta: dict = field(default_factory=dict)  # name, provenance, metrics, ranges
    #: (theta_i_max, theta_o_max) degrees: the largest light and view polar angles of the data
    dir_range: tuple[float, float] = (DEFAULT_THETA_MAX_DEG, DEFAULT_THETA_MAX_DEG)
    #: texture name -> its pyramid levels 1.. (``[H >> k, W >> k, C]`` float16 each)
    levels: dict = field(default_factory=dict)
    #: height-field parallax (vrneural.parallax): ``{"kind": "height", "steps": n}`` or
    #: ``{"kind": "off"}`` (also ``{}``)
    parallax: dict = field(default_factory=dict)
    #: ``[H, W]`` float16 height field, UV units, on the full-resolution texel grid (or None)
    height: np.ndarray | None = None
    #: NeuMIP's neural offset (vrneural.neural_offset; parallax kind ``"neural"``): the offset
    #: MLP's layers and the offset texture ``[H, W, C]`` float16 on the full-resolution grid
    offset_net: list | None = None
    offset_tex: np.ndarray | None = None

    def __post_init__(self):
        self.dir_range = check_dir_range(self.dir_range)
        self.levels = {k: [np.asarray(a, np.float16) for a in v] for k, v in self.levels.items()}
        for name, lv in self.levels.items():
            if name not in self.textures:
                raise ValueError(f"pyramid levels for texture {name!r}, which it does not have")
            prev = self.textures[name].shape
            for k, a in enumerate(lv, 1):
                want = (prev[0] // 2, prev[1] // 2, prev[2])
                if a.shape != want or min(want[:2]) < 1:
                    raise ValueError(
                        f"texture {name!r} level {k} has shape {list(a.shape)}; expected "
                        f"{list(want)} (half of level {k - 1}, same channels)"
                    )
                prev = a.shape
        if len({len(v) for v in self.levels.values()}) > 1:
            raise ValueError("every neural texture needs the same number of pyramid levels")
        if self.arch not in ARCHS:
            raise ValueError(f"arch {self.arch!r} not in {sorted(ARCHS)}")
        if self.output not in OUTPUTS:
            raise ValueError(f"output {self.output!r} not in {OUTPUTS}")
        nets, texs = ARCHS[self.arch]
        if set(self.networks) != set(nets) or set(self.textures) != set(texs):
            raise ValueError(f"{self.arch} needs networks {nets} and textures {texs}")
        self.textures = {k: np.asarray(v, np.float16) for k, v in self.textures.items()}
        for k, t in self.textures.items():
            if t.ndim != 3 or min(t.shape) < 1:
                raise ValueError(f"texture '{k}' has shape {list(t.shape)}; expected [H, W, C > 0]")
        first = self.networks[nets[0]][0].n_in
        if first != DIR_INPUTS + self.textures[texs[0]].shape[2]:
            raise ValueError(
                f"first layer takes {first} inputs, expected 9 + "
                f"{self.textures[texs[0]].shape[2]} texture channels"
            )
        if self.arch == "coarse_fine":
            z = self.networks["coarse"][-1].n_out
            if self.networks["fine"][0].n_in != z + self.textures["fine"].shape[2]:
                raise ValueError("fine network input != latent size + fine texture channels")
        if self.networks[nets[-1]][-1].n_out != 3:
            raise ValueError("the last network must output 3 values (RGB)")
        self._check_parallax()

    def _check_parallax(self) -> None:
        self.parallax = dict(self.parallax or {"kind": "off"})
        kind = self.parallax.get("kind")
        if kind not in PACK_KINDS:
            raise ValueError(f"parallax kind {kind!r} not in {PACK_KINDS}")
        if kind == "height" and self.height is None:
            raise ValueError("parallax kind 'height' needs a height field, and it has none")
        res = self.textures[ARCHS[self.arch][1][-1]].shape[:2]  # fine / features
        if (kind == "neural") != (self.offset_net is not None and self.offset_tex is not None):
            raise ValueError(
                "parallax kind 'neural' needs the offset MLP and the offset texture, and only it "
                f"carries them (kind {kind!r})"
            )
        if kind == "neural":
            from vrneural.neural_offset import check_offset
            from vrneural.parallax import MATERIAL_MARCHES

            if self.parallax_march not in MATERIAL_MARCHES:
                raise ValueError(
                    f"parallax march {self.parallax_march!r} not in {MATERIAL_MARCHES}"
                )
            self.offset_tex = check_offset(self.offset_net, self.offset_tex, res)
        if self.height is not None:
            steps = self.parallax.get("steps", 1) if kind == "height" else 1
            march = self.parallax.get("march", "texel")
            self.height = check_pack_height(self.height, res, steps, march)

    @property
    def parallax_kind(self) -> str:
        """``"height"``, ``"neural"`` or ``"off"``."""
        return self.parallax.get("kind", "off")

    @property
    def parallax_steps(self) -> int:
        """March steps of height-field parallax (0 when off)."""
        return int(self.parallax.get("steps", 0)) if self.parallax_kind == "height" else 0

    @property
    def parallax_march(self) -> str:
        """Where the parallax march runs: ``"texel"``, once per 2x2 ``"block"``, or ``"auto"``
        (render time only: per block where a block spans at most a texel of the march's grid,
        :func:`vrneural.parallax.auto_blocks`)."""
        return self.parallax.get("march", "texel")

    @property
    def march_grid(self) -> tuple[int, ...]:
        """Shape of the grid the parallax marches on: the height field, or the offset texture
        of a neural offset (``()`` without parallax)."""
        if self.parallax_steps:
            return self.height.shape
        return self.offset_tex.shape if self.parallax_kind == "neural" else ()

    @property
    def parallax_slope_max(self) -> np.float32:
        """The steepest view's ray slope (:func:`vrneural.parallax.slope_max`): the march's
        full step count is reached there."""
        return slope_max(*boundary_consts(self.dir_range[1]), self.height.shape)

    @property
    def lod_levels(self) -> int:
        """Pyramid levels of its neural textures (1: level 0 alone)."""
        return 1 + max((len(v) for v in self.levels.values()), default=0)

    @property
    def macs_per_texel(self) -> float:
        """Multiply-adds per shaded texel (the coarse net counts a quarter: once per block)."""
        extra = 0.0
        if self.parallax_kind == "neural":
            from vrneural.neural_offset import offset_macs

            extra = offset_macs(self.offset_net, self.parallax_march)
        if self.arch == "coarse_fine":
            return macs(self.networks["coarse"]) / 4 + macs(self.networks["fine"]) + extra
        return float(macs(self.networks["mlp"])) + extra

    @property
    def weight_bytes(self) -> int:
        nets = [*self.networks.values(), self.offset_net or []]
        return sum(4 * (lay.weight.size + lay.bias.size) for net in nets for lay in net)

    @property
    def texture_bytes(self) -> int:
        extra = 0 if self.offset_tex is None else self.offset_tex.nbytes
        return sum(t.nbytes for t in self.textures.values()) + extra


def half_vector(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """``normalize(wi + wo)`` ``[..., 3]``; ``(0, 0, 1)`` where ``|wi + wo|^2 < 1e-12``."""
    s = np.asarray(wi, np.float32) + np.asarray(wo, np.float32)
    n2 = (s * s).sum(-1, keepdims=True)
    ok = n2 >= HALF_EPS2
    h = np.where(ok, s / np.sqrt(np.where(ok, n2, 1.0)), np.array([0, 0, 1], np.float32))
    return h.astype(np.float32)


def pool_level(tex: np.ndarray, level: int) -> np.ndarray:
    """``tex: [H, W, C]`` averaged over ``2^level`` squares (float32 sum, float16 result): the
    ``"filter"`` pyramid of :class:`vrneural.distill.models.NeuralModel`."""
    s = 1 << level
    H, W, C = tex.shape
    t = np.asarray(tex, np.float32)[: H // s * s, : W // s * s]
    return t.reshape(H // s, s, W // s, s, C).mean((1, 3)).astype(np.float16)


def sample_lod(mat: NeuralMaterial, name: str, uv: np.ndarray, lod) -> np.ndarray:
    """Lookup of neural texture ``name`` at ``uv: [..., 2]`` and level of detail ``lod``
    (broadcast to ``uv.shape[:-1]``; None: level 0): the bilinear lookups of levels
    ``floor(lod)`` and the next blended by ``lod - floor(lod)``, ``lod`` clamped to the
    pyramid. Twin of ``sample_*_lod`` in neural_material.wgsl."""
    base = mat.textures[name]
    if lod is None:
        return sample_bilinear_wrap(base, uv)
    pyr = [base, *mat.levels.get(name, [])]
    top = np.float32(len(pyr) - 1)
    lod = np.broadcast_to(np.clip(np.asarray(lod, np.float32), 0, top), uv.shape[:-1])
    lo = np.floor(lod)
    t = (lod - lo).astype(np.float32)[..., None]
    lo = lo.astype(np.int64)
    out = np.zeros((*uv.shape[:-1], base.shape[2]), np.float32)
    for k in np.unique(lo):
        m = lo == k
        a = sample_bilinear_wrap(pyr[k], uv[m])
        b = sample_bilinear_wrap(pyr[min(k + 1, len(pyr) - 1)], uv[m])
        out[m] = a * (1 - t[m]) + b * t[m]
    return out


def apply_output(raw: np.ndarray, output: str) -> np.ndarray:
    r = np.maximum(raw, 0)
    return np.expm1(r) if output == "log1p" else r


def material_forward(
    mat: NeuralMaterial,
    wi: np.ndarray,
    wo: np.ndarray,
    uv: np.ndarray,
    precision: str = "f32",
    lod: np.ndarray | None = None,
    foot: np.ndarray | None = None,
) -> np.ndarray:
    """BTF values of a material, evaluated the way the shader does.

    ``wi, wo: [N, 3]`` unit vectors (one angular condition per block); ``uv: [N, 4, 2]`` the
    material UVs of the block's 4 texels. Returns ``[N, 4, 3]`` float32. For ``"single"`` each
    texel is independent (the 4 share only the directions). Directions beyond
    ``mat.dir_range`` are extended (:func:`vrneural.grazing.extend`): 0 for a light at or
    below the horizon. ``lod: [N]``: each block's level of detail in the neural textures'
    pyramids (None: level 0; see :func:`sample_lod`). A material with height-field parallax
    looks its textures up at :func:`vrneural.parallax.parallax_uv` of ``uv`` along the
    extended ``wo`` (the coarse texture at the corrected texels' mean); one with a neural
    offset at :func:`vrneural.neural_offset.offset_uv`'s. ``foot: [N]``: each block's atlas
    texel in tiled material UV (the texture-space pass's), which march ``"auto"`` needs.
    """
    wi = np.asarray(wi, np.float32)
    wo = np.asarray(wo, np.float32)
    uv = np.asarray(uv, np.float32)
    if wi.ndim != 2:
        raise VrnError(
            f"material_forward: wi has shape {list(wi.shape)}, expected [N, 3] (one direction "
            "per 2x2 block; a single one as wi[None])"
        )
    n = wi.shape[0]
    for name, a, want in (("wi", wi, (n, 3)), ("wo", wo, (n, 3)), ("uv", uv, (n, 4, 2))):
        if a.shape != want:
            shape = "[N, 4, 2] (4 texels of a 2x2 block)" if name == "uv" else "[N, 3]"
            raise VrnError(
                f"material_forward: {name} has shape {list(a.shape)}, expected {shape} with N = {n}"
            )
        if not np.isfinite(a).all():  # NaN in, NaN out, silently
            raise VrnError(f"material_forward: {name} holds NaN/Inf values")
    wi, wo, weight = extend(wi, wo, mat.dir_range)
    march = mat.parallax_march
    if march == "auto" and mat.parallax_kind != "off":
        from vrneural.parallax import auto_blocks

        if foot is None:
            raise VrnError("material_forward: parallax march 'auto' needs each block's foot")
        march = auto_blocks(foot, mat.march_grid)
    if mat.parallax_steps:  # lookups where the (extended) view ray meets the height field
        from vrneural.parallax import parallax_uv

        uv = parallax_uv(mat.height, wo, uv, mat.parallax_steps, mat.parallax_slope_max, march)
    elif mat.parallax_kind == "neural":  # NeuMIP's offset module moves the lookups
        from vrneural.neural_offset import offset_uv

        uv = offset_uv(mat.offset_net, mat.offset_tex, wo, uv, march, precision)
    dirs = np.concatenate([wi, wo, half_vector(wi, wo)], -1)  # [N, 9]
    lod4 = None if lod is None else np.repeat(np.asarray(lod, np.float32), 4)  # per texel
    if mat.arch == "coarse_fine":
        fc = sample_lod(mat, "coarse", uv.mean(axis=1), lod)
        z = mlp_forward(np.concatenate([dirs, fc], -1), mat.networks["coarse"], precision)
        ff = sample_lod(mat, "fine", uv.reshape(-1, 2), lod4)  # [N*4, Cf]
        zk = np.repeat(z, 4, axis=0)
        raw = mlp_forward(np.concatenate([zk, ff], -1), mat.networks["fine"], precision)
    else:
        f = sample_lod(mat, "features", uv.reshape(-1, 2), lod4)
        raw = mlp_forward(
            np.concatenate([np.repeat(dirs, 4, axis=0), f], -1), mat.networks["mlp"], precision
        )
    y = apply_output(raw, mat.output).reshape(n, 4, 3) * weight[:, None, None]
    return y.astype(np.float32)


def random_material(
    seed: int = 0,
    arch: str = "coarse_fine",
    width: int = 8,
    channels: int = 8,
    tex_res: int = 16,
    layers: int | None = None,
    output: str = "linear",
) -> NeuralMaterial:
    """A material with seeded random weights and textures (tests, and the frame benchmarks,
    whose timings depend on the networks' shapes, not their values).

    ``layers``: hidden layers of M_c (``coarse_fine``) or of the one MLP (``single``). The
    default is the trained shape of ``vrneural distill``: M_c 2 x W, M_f W -> 3 (the student);
    3 x W (the single-level net)."""
    if layers is None:
        layers = 2 if arch == "coarse_fine" else 3
    rng = np.random.default_rng(seed)
    if arch == "coarse_fine":
        nets = {
            "coarse": random_mlp([DIR_INPUTS + channels] + [width] * layers, seed, last_act="relu"),
            "fine": random_mlp([width + channels, width, 3], seed + 1),
        }
        texs = {
            k: rng.standard_normal((tex_res, tex_res, channels)).astype(np.float16) * 0.5
            for k in ("coarse", "fine")
        }
    else:
        nets = {"mlp": random_mlp([DIR_INPUTS + channels] + [width] * layers + [3], seed)}
        texs = {"features": rng.standard_normal((tex_res, tex_res, channels)).astype(np.float16)}
    return NeuralMaterial(arch, nets, texs, output, {"name": f"random-{seed}"})


def lambertian_material(albedo=(0.8, 0.5, 0.2), tex_res: int = 4) -> NeuralMaterial:
    """An exact coarse-to-fine encoding of a flat homogeneous Lambertian patch.

    BTF = albedo / pi * max(wi.z, 0): the coarse net passes ``relu(wi.z)`` through, the fine net
    scales it per channel. Textures are zero (the material is homogeneous).
    """
    c = 1
    z = 8
    w0 = np.zeros((z, DIR_INPUTS + c), np.float32)
    w0[0, 2] = 1.0  # wi.z
    coarse = [Layer(w0, np.zeros(z, np.float32), "relu")]
    w1 = np.zeros((3, z + c), np.float32)
    w1[:, 0] = np.asarray(albedo, np.float32) / np.pi
    fine = [Layer(w1, np.zeros(3, np.float32), "none")]
    tex = {k: np.zeros((tex_res, tex_res, c), np.float16) for k in ("coarse", "fine")}
    return NeuralMaterial(
        "coarse_fine",
        {"coarse": coarse, "fine": fine},
        tex,
        "linear",
        {"name": "lambertian", "albedo": list(map(float, albedo))},
    )


def distilled(mat) -> bool | None:
    """Whether a pack's network was distilled (its recorded config; True for an older record
    without the field), None for a teacher."""
    cfg = (mat.meta.get("provenance") or {}).get("config") or {}
    return cfg.get("distill", True) if mat.meta.get("method") != "teacher" else None


def pack_width(mat) -> int:
    """The hidden width of a pack's network (its first layer's outputs)."""
    return next(iter(mat.networks.values()))[0].n_out


def width_words(mat) -> str:
    """How a student or single8 pack's width differs from the paper's 8: ``" 16 wide"``, or
    ``" (16 -> 8 wide)"`` for one pruned from a wide run (--wide-start / --init-from); ``""``
    for an 8-wide one from random weights and for other packs."""
    if mat.meta.get("method") not in ("student", "single8"):
        return ""
    width = pack_width(mat)
    init = (mat.meta.get("provenance") or {}).get("init_from")
    if init:
        return f" ({init['width']} -> {width} wide)"
    return f" {width} wide" if width != 8 else ""
