"""Unrolled MLP layers as WGSL lines: plain Python, so the generated code can be unit-tested
(its multiply-adds counted against the network's: tests/runtime_helpers.py) and stepped
through in a debugger.

A layer ``y = act(W x + b)`` (:class:`vrneural.mlp.Layer`) becomes one ``let`` per output unit
with its weights as WGSL constants; zero weights are skipped, so the cost follows the network.
:func:`mlp_lines` names the values ``{prefix}{layer}_{unit}`` (layers counted from 1; the last
layer's outputs are ``{prefix}{n_layers}_{k}``). Used by the batched evaluator
(:mod:`vrneural.gpu.mlp_kernel`) and the material kernels (:mod:`vrneural.runtime.codegen_mlp`).

Hoisting (``first_base``, ``first_cols``): a first layer ``W [a | b] x + c`` whose inputs split
into a part that changes in a loop (a: directions, per light) and a part that does not (b:
neural-texture features) is evaluated as ``W_a a + (c + W_b b)``, the bracket computed once
outside the loop by :func:`affine_lines`. :func:`mlp_lines` then gets the bracket's names as
``first_base`` (one expression per first-layer unit) and only the loop-varying input columns as
``first_cols``: the same function, fewer multiply-adds per light.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from vrneural.gpu.shaders import wgsl_float
from vrneural.mlp import ACT_CODE, LEAKY_SLOPE, Layer

IND = "    "  # one level of WGSL indentation


def act_expr(act: str, e: str, T: str) -> str:
    """Activation ``act`` (:data:`vrneural.mlp.ACTIVATIONS`) applied to the WGSL expression
    ``e`` of scalar type ``T``."""
    if ACT_CODE[act] == ACT_CODE["relu"]:
        return f"max({e}, {T}(0))"
    if ACT_CODE[act] == ACT_CODE["leaky_relu"]:
        return f"max({e}, {T}({LEAKY_SLOPE}) * {e})"
    return e


def literal(x: float, T: str) -> str:
    """An exact WGSL literal of ``x`` in type ``T`` (f32 | f16)."""
    return wgsl_float(x, "h" if T == "f16" else "")


def _lists(layer: Layer) -> tuple[list, list]:
    """``W`` and ``b`` as float32 values in Python lists (a zero in float32 is skipped)."""
    w, b = (np.asarray(a, np.float32).tolist() for a in (layer.weight, layer.bias))
    return w, b


def _terms(w_row: list, cols, inputs, T: str) -> list[str]:
    """``w * input`` for the columns ``cols`` whose weight is not zero."""
    return [f"{literal(w_row[i], T)} * {inputs[i]}" for i in cols if w_row[i] != 0.0]


def affine_lines(
    prefix: str, inputs: Mapping | Sequence, layer: Layer, cols, T: str, with_bias: bool
) -> list[str]:
    """The pre-activation part of ``layer`` over input columns ``cols`` (``inputs[i]``: the
    WGSL name of column i), with or without the bias, as ``let {prefix}_{unit}``; no
    activation."""
    w, b = _lists(layer)
    lines = []
    for o in range(layer.n_out):
        parts = ([literal(b[o], T)] if with_bias else []) + _terms(w[o], cols, inputs, T)
        lines.append(f"{IND}let {prefix}_{o} = {' + '.join(parts) if parts else f'{T}(0)'};")
    return lines


def mlp_lines(
    prefix: str,
    inputs: Mapping | Sequence,
    layers: Sequence[Layer],
    T: str,
    first_base: Sequence[str] | None = None,
    first_cols: Sequence[int] | None = None,
) -> list[str]:
    """Every layer of ``layers`` unrolled: ``let {prefix}{layer}_{unit}`` lines. ``inputs[i]``
    names the first layer's input column i; ``first_base`` / ``first_cols``: hoisting (see the
    module)."""
    lines = []
    for li, layer in enumerate(layers, 1):
        w, b = _lists(layer)
        hoisted = li == 1 and first_cols is not None
        cols = first_cols if hoisted else range(layer.n_in)
        src = inputs if li == 1 else [f"{prefix}{li - 1}_{i}" for i in range(layer.n_in)]
        for o in range(layer.n_out):
            base = first_base[o] if li == 1 and first_base is not None else literal(b[o], T)
            pre = " + ".join([base, *_terms(w[o], cols, src, T)])
            name = f"{prefix}{li}_{o}"
            if layer.act == "leaky_relu":  # the pre-activation named: it is used twice
                lines.append(f"{IND}let {name}_p = {pre};")
                pre = f"{name}_p"
            lines.append(f"{IND}let {name} = {act_expr(layer.act, pre, T)};")
    return lines
