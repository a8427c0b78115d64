"""The networks of a material kernel as WGSL lines (the evaluation API of
``shaders/neural_material.wgsl``), generated in Python so each piece can be unit-tested and
stepped through; the templates keep the structure and include :func:`network_wgsl`'s text.

The API, the same in every weight variant (:data:`vrneural.runtime.codegen.WEIGHTS`): the first
layer of every network is split into the part that does not change with the light (bias +
``W_f`` features: ``pre_a``, ``pre_b``, once per texel or block outside the light loop) and the
part that does (``W_d`` dirs, and for the fine network ``W_z z_c``: ``fine_z``, once per block
per light, shared by the block's 4 texels)::

    coarse_fine: z = eval_coarse(dirs, pre_a(U_c(u_c))); zz = fine_z(z);
                 rgb_k = eval_fine(zz, pre_b(U_f(u_k)))
    single:      rgb_k = eval_single(dirs, pre_a(U(u_k)))

The variants are described in :mod:`vrneural.runtime.codegen`: :func:`constant_nets` (unrolled
by :mod:`vrneural.gpu.unroll`), :func:`storage_nets` and :func:`streamed_single`.
"""

from __future__ import annotations

from vrneural.gpu.unroll import IND, act_expr, affine_lines, mlp_lines
from vrneural.runtime.codegen_offset import offset_wgsl

I2 = IND * 2


def network_wgsl(spec, T: str) -> str:
    """The evaluation API of ``spec`` (a :class:`~vrneural.runtime.codegen.MaterialSpec`) in
    scalar type ``T``, as WGSL text; with a neural offset also its stage
    (:mod:`vrneural.runtime.codegen_offset`)."""
    if spec.weights in ("uniform", "streamed"):
        lines = streamed_single(spec, T)
    elif spec.weights == "storage":
        lines = storage_nets(spec, T)
    else:
        lines = constant_nets(spec, T)
    return "\n".join(lines + offset_wgsl(spec, T))  # the neural offset: constants in any variant


# --- weights as constants -------------------------------------------------------------------


def const_pre(fname: str, prefix: str, layer, T: str, n_arg: int, col0: int) -> list[str]:
    """``fname(f)``: the loop-invariant part of a first layer, bias + ``W[:, col0:col0+n_arg]
    f`` (``f``: ``n_arg`` texture features)."""
    lines = [f"fn {fname}(f: array<f32, {n_arg}>) -> array<{T}, {layer.n_out}> {{"]
    lines += [f"{IND}let in_{k} = {T}(f[{k}]);" for k in range(n_arg)]
    ins = {col0 + k: f"in_{k}" for k in range(n_arg)}
    lines += affine_lines(prefix + "p", ins, layer, range(col0, col0 + n_arg), T, True)
    outs = ", ".join(f"{prefix}p_{o}" for o in range(layer.n_out))
    return [*lines, f"{IND}return array<{T}, {layer.n_out}>({outs});", "}"]


def const_net(
    fname, prefix, layers, T, arg_decls, input_exprs, first_cols, base_exprs, rgb
) -> list[str]:
    """``fname``: ``layers`` unrolled. ``input_exprs``: one f32 expression per loop-varying
    input column (``first_cols``); ``base_exprs``: the first layer's hoisted part per unit;
    returns the RGB (``rgb``) or the last layer's values."""
    L, n = len(layers), layers[-1].n_out
    ret = "vec3<f32>" if rgb else f"array<{T}, {n}>"
    lines = [f"fn {fname}({arg_decls}) -> {ret} {{"]
    lines += [f"{IND}let in_{i} = {T}({e});" for i, e in enumerate(input_exprs)]
    ins = {c: f"in_{i}" for i, c in enumerate(first_cols)}
    lines += mlp_lines(prefix, ins, layers, T, base_exprs, first_cols)
    if rgb:
        outs = ", ".join(f"f32({prefix}{L}_{k})" for k in range(3))
        lines.append(f"{IND}return vec3<f32>({outs});")
    else:
        outs = ", ".join(f"{prefix}{L}_{k}" for k in range(n))
        lines.append(f"{IND}return array<{T}, {n}>({outs});")
    return [*lines, "}"]


def constant_nets(spec, T: str) -> list[str]:
    """The API with constant weights: hoisted first layers, the rest unrolled."""
    dexprs = [f"d[{k}]" for k in range(9)]
    if spec.arch != "coarse_fine":
        sl = spec.networks["mlp"]
        n = sl[0].n_out
        return [
            *const_pre("pre_a", "s", sl[0], T, spec.ca, 9),
            *const_net("single_net", "s", sl, T, f"d: array<f32, 9>, pa: array<{T}, {n}>",
                       dexprs, range(9), [f"pa[{o}]" for o in range(n)], True),
            f"fn eval_single(d: array<f32, 9>, pa: array<{T}, {n}>) -> vec3<f32> {{",
            f"{IND}return apply_output(single_net(d, pa));",
            "}",
        ]  # fmt: skip
    cl, fl = spec.networks["coarse"], spec.networks["fine"]
    nc, nf, z = cl[0].n_out, fl[0].n_out, spec.z
    zz = ", ".join(f"zz_{o}" for o in range(nf))
    return [
        *const_pre("pre_a", "c", cl[0], T, spec.ca, 9),
        *const_pre("pre_b", "q", fl[0], T, spec.cb, z),
        f"fn fine_z(z: array<{T}, {z}>) -> array<{T}, {nf}> {{",
        *affine_lines("zz", [f"z[{k}]" for k in range(z)], fl[0], range(z), T, False),
        f"{IND}return array<{T}, {nf}>({zz});",
        "}",
        *const_net("eval_coarse", "c", cl, T, f"d: array<f32, 9>, pa: array<{T}, {nc}>",
                   dexprs, range(9), [f"pa[{o}]" for o in range(nc)], False),
        *const_net("fine_net", "q", fl, T, f"zz: array<{T}, {nf}>, pb: array<{T}, {nf}>",
                   [], [], [f"(zz[{o}] + pb[{o}])" for o in range(nf)], True),
        f"fn eval_fine(zz: array<{T}, {nf}>, pb: array<{T}, {nf}>) -> vec3<f32> {{",
        f"{IND}return apply_output(fine_net(zz, pb));",
        "}",
    ]  # fmt: skip


# --- weights in a storage buffer, layer loops -----------------------------------------------

STORAGE_DOC = """\
// Storage-buffer weights, networks in order {order}: per layer W[out, in]
// row-major then b[out] (mlp.pack_weights). The first layers are split
// exactly as in the constant-weight code (loop-invariant part hoisted), so the two variants do
// the same arithmetic and differ only in where the weights come from. Layer shapes, offsets
// and activations are generated constants; activations ping-pong between two local arrays. Only
// for narrow networks: lavapipe computes wrong results once an invocation's dynamically indexed
// arrays grow large (a 64-wide net in the texture pass; see streamed_single for wide ones).
const MAXW: u32 = {maxw}u;"""


def buf_layer(spec, T, li, dst, src, c0, n, with_bias, act=True, pre=None) -> list[str]:
    """``dst[o] = act(base + sum_k W_l[o, c0 + k] * src[k])`` for ``o < n_out(li), k < n``;
    ``base``: the bias (``with_bias``), ``pre[o]`` when ``pre`` names an array, or 0."""
    n_in, n_out, off = spec.buf_dims_in[li], spec.buf_dims_out[li], spec.buf_offsets[li]
    if pre is not None:
        s0 = f"{pre}[o]"
    elif with_bias:
        s0 = f"{T}(weights[{off + n_out * n_in}u + o])"
    else:
        s0 = f"{T}(0)"
    return [
        f"{IND}for (var o = 0u; o < {n_out}u; o++) {{",
        f"{I2}var s = {s0};",
        f"{I2}let row = {off + c0}u + o * {n_in}u;",
        f"{I2}for (var k = 0u; k < {n}u; k++) {{ s += {T}(weights[row + k]) * {src}[k]; }}",
        f"{I2}{dst}[o] = {act_expr(spec.buf_acts[li] if act else 'none', 's', T)};",
        f"{IND}}}",
    ]


def buf_rest(spec, T, first, last) -> list[str]:
    """Layers ``first .. last - 1`` on ``a`` (their input), ping-ponging between ``a`` and
    ``b``; ends with ``let y`` = the array holding the last output."""
    lines = [f"{IND}var b: array<{T}, MAXW>;"]
    names = ("a", "b")
    for i, li in enumerate(range(first, last)):
        lines += buf_layer(spec, T, li, names[(i + 1) % 2], names[i % 2], 0, spec.buf_dims_in[li],
                           True)  # fmt: skip
    return [*lines, f"{IND}let y = {names[(last - first) % 2]};"]


def buf_pre(spec, T, fname, li, n, c0) -> list[str]:
    """``fname(f)``: the hoisted part (bias + features) of first layer ``li`` into ``p``."""
    return [
        f"fn {fname}(f: array<f32, {n}>) -> array<{T}, MAXW> {{",
        f"{IND}var x: array<{T}, {n}>;",
        f"{IND}for (var k = 0u; k < {n}u; k++) {{ x[k] = {T}(f[k]); }}",
        f"{IND}var p: array<{T}, MAXW>;",
        *buf_layer(spec, T, li, "p", "x", c0, n, True, False),
        f"{IND}return p;",
        "}",
    ]


def dirs_first(spec, T, li) -> list[str]:
    """The first layer's direction part on top of its hoisted part ``base``, activated, -> a."""
    return [
        f"{IND}var x: array<{T}, 9>;",
        f"{IND}for (var k = 0u; k < 9u; k++) {{ x[k] = {T}(d[k]); }}",
        f"{IND}var a: array<{T}, MAXW>;",
        *buf_layer(spec, T, li, "a", "x", 0, 9, False, True, "base"),
    ]


def storage_nets(spec, T: str) -> list[str]:
    """The API with storage-buffer weights (layer loops over local arrays)."""
    rgb = f"{IND}return apply_output(vec3<f32>(f32(y[0]), f32(y[1]), f32(y[2])));"
    head = STORAGE_DOC.format(order=", ".join(spec.net_order), maxw=spec.max_width)
    lines = [*head.splitlines(), *buf_pre(spec, T, "pre_a", 0, spec.ca, 9)]
    if spec.arch != "coarse_fine":
        return [
            *lines,
            f"fn eval_single(d: array<f32, 9>, base: array<{T}, MAXW>) -> vec3<f32> {{",
            *dirs_first(spec, T, 0),
            *buf_rest(spec, T, 1, spec.n_layers[0]),
            rgb,
            "}",
        ]
    nc, nf = spec.n_layers
    return [
        *lines,
        f"fn eval_coarse(d: array<f32, 9>, base: array<{T}, MAXW>) -> array<{T}, MAXW> {{",
        *dirs_first(spec, T, 0),
        *buf_rest(spec, T, 1, nc),
        f"{IND}return y;",
        "}",
        *buf_pre(spec, T, "pre_b", nc, spec.cb, spec.z),
        f"fn fine_z(z: array<{T}, MAXW>) -> array<{T}, MAXW> {{",
        f"{IND}var p: array<{T}, MAXW>;",
        *buf_layer(spec, T, nc, "p", "z", 0, spec.z, False, False),
        f"{IND}return p;",
        "}",
        f"fn eval_fine(zz: array<{T}, MAXW>, pb: array<{T}, MAXW>) -> vec3<f32> {{",
        f"{IND}var a: array<{T}, MAXW>;",
        f"{IND}for (var o = 0u; o < {spec.buf_dims_out[nc]}u; o++) {{",
        f"{I2}let s = zz[o] + pb[o];",
        f"{I2}a[o] = {act_expr(spec.buf_acts[nc], 's', T)};",
        f"{IND}}}",
        *buf_rest(spec, T, nc + 1, nc + nf),
        rgb,
        "}",
    ]


# --- wide single-level networks streamed from buffers ---------------------------------------


def wld(spec, li: int, idx: str) -> str:
    """One weight of layer ``li`` at the (dynamic) index expression ``idx``: from the layer's
    uniform buffer (codegen.uniform_weights) or the storage buffer (mlp.pack_weights)."""
    if spec.weights == "uniform":
        return f"wl{li}[({idx}) >> 2u][({idx}) & 3u]"
    return f"weights[{spec.buf_offsets[li]}u + {idx}]"


def bld(spec, li: int, idx: str) -> str:
    """One bias of layer ``li`` at index expression ``idx`` (as :func:`wld`)."""
    if spec.weights == "uniform":
        i = f"{spec.buf_bias_offsets[li]}u + {idx}"
        return f"wbias[({i}) >> 2u][({i}) & 3u]"
    return (
        f"weights[{spec.buf_offsets[li] + spec.buf_dims_in[li] * spec.buf_dims_out[li]}u + {idx}]"
    )


def streamed_single(spec, T: str) -> list[str]:
    """A single-level net from buffer weights (``"uniform"`` | ``"streamed"``) for wide
    networks (the 128-wide reference teacher). Layers go in pairs (A, B): one loop over A's
    units o computes unit o from all of A's inputs, then adds its contribution to every output
    of B (B's column o). Every activation is a named value with a constant index; the loops
    index only the weights (the same index in every invocation: one scalar load per step from
    a uniform buffer on a CPU adapter). An odd last layer is unrolled (it is 3 wide). No
    hoisting: ``pre_a`` returns the features and the first layer reads all its inputs each time
    (for the teacher 8 x 128 more multiply-adds per light, 3%)."""
    ca, dims_in, dims_out, acts = spec.ca, spec.buf_dims_in, spec.buf_dims_out, spec.buf_acts
    lines = [
        f"fn pre_a(f: array<f32, {ca}>) -> array<{T}, {ca}> {{",
        f"{IND}var x: array<{T}, {ca}>;",
        *(f"{IND}x[{k}] = {T}(f[{k}]);" for k in range(ca)),
        f"{IND}return x;",
        "}",
        f"fn eval_single(d: array<f32, 9>, f: array<{T}, {ca}>) -> vec3<f32> {{",
        *(f"{IND}let v0_{k} = {T}(d[{k}]);" for k in range(9)),
        *(f"{IND}let v0_{9 + k} = f[{k}];" for k in range(ca)),
    ]
    cur = [f"v0_{k}" for k in range(9 + ca)]
    L, li = len(dims_in), 0
    while li < L:
        if li + 1 < L:  # a pair: A = layer li, B = layer li + 1
            H, nb = dims_out[li], dims_out[li + 1]
            lines += [
                f"{IND}var acc{li}_{j} = {T}({bld(spec, li + 1, f'{j}u')});" for j in range(nb)
            ]
            lines += [
                f"{IND}for (var o = 0u; o < {H}u; o++) {{",
                f"{I2}let r = o * {dims_in[li]}u;",
                f"{I2}var s = {T}({bld(spec, li, 'o')});",
                *(f"{I2}s += {T}({wld(spec, li, f'r + {k}u')}) * {cur[k]};"
                  for k in range(dims_in[li])),
                f"{I2}let h = {act_expr(acts[li], 's', T)};",
                *(f"{I2}acc{li}_{j} += {T}({wld(spec, li + 1, f'{j * H}u + o')}) * h;"
                  for j in range(nb)),
                f"{IND}}}",
            ]  # fmt: skip
            cur = [f"v{li + 2}_{j}" for j in range(nb)]
            lines += [f"{IND}let {v} = {act_expr(acts[li + 1], f'acc{li}_{j}', T)};"
                      for j, v in enumerate(cur)]  # fmt: skip
            li += 2
        else:  # an odd last layer, unrolled
            nxt = []
            for j in range(dims_out[li]):
                lines.append(f"{IND}var p{li}_{j} = {T}({bld(spec, li, f'{j}u')});")
                lines += [
                    f"{IND}p{li}_{j} += {T}({wld(spec, li, f'{j * dims_in[li] + k}u')}) * {cur[k]};"
                    for k in range(dims_in[li])
                ]
                lines.append(f"{IND}let v{li + 1}_{j} = {act_expr(acts[li], f'p{li}_{j}', T)};")
                nxt.append(f"v{li + 1}_{j}")
            cur, li = nxt, li + 1
    out = ", ".join(f"f32({c})" for c in cur[:3])
    return [*lines, f"{IND}return apply_output(vec3<f32>({out}));", "}"]
