"""Small MLPs as plain data, and their numpy forward pass (the reference twin of the WGSL kernel).

A layer is ``y = act(W @ x + b)`` with ``W: [out, in]`` float32, ``b: [out]`` float32 and
``act`` one of ``"relu"``, ``"leaky_relu"`` (slope 0.01) or ``"none"``. This module never imports
wgpu; :mod:`vrneural.gpu.mlp_kernel` has the GPU twin with the same function name.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from vrneural.errors import VrnError

ACTIVATIONS = ("relu", "leaky_relu", "none")
#: the one table of activation codes (the WGSL loops over buffer weights branch on them)
ACT_CODE = {a: i for i, a in enumerate(ACTIVATIONS)}
LEAKY_SLOPE = 0.01


@dataclass(frozen=True)
class Layer:
    """One dense layer. ``weight: [out, in]``, ``bias: [out]`` (float32)."""

    weight: np.ndarray
    bias: np.ndarray
    act: str = "relu"

    def __post_init__(self):
        if self.weight.ndim != 2 or self.bias.shape != (self.weight.shape[0],):
            raise ValueError(f"layer shapes {self.weight.shape} / {self.bias.shape} do not match")
        if self.act not in ACTIVATIONS:
            raise ValueError(f"activation {self.act!r} not in {ACTIVATIONS}")

    @property
    def n_in(self) -> int:
        return int(self.weight.shape[1])

    @property
    def n_out(self) -> int:
        return int(self.weight.shape[0])


def random_mlp(sizes: list[int], seed: int = 0, last_act: str = "none") -> list[Layer]:
    """He-initialised layers ``sizes[0] -> sizes[1] -> ... -> sizes[-1]`` (ReLU between)."""
    rng = np.random.default_rng(seed)
    layers = []
    for i, (a, b) in enumerate(itertools.pairwise(sizes)):
        w = (rng.standard_normal((b, a)) * np.sqrt(2.0 / a)).astype(np.float32)
        bias = (rng.standard_normal(b) * 0.1).astype(np.float32)
        layers.append(Layer(w, bias, last_act if i == len(sizes) - 2 else "relu"))
    return layers


def activate(x: np.ndarray, act: str) -> np.ndarray:
    if act == "relu":
        return np.maximum(x, 0)
    if act == "leaky_relu":
        return np.where(x > 0, x, x * x.dtype.type(LEAKY_SLOPE))
    return x


#: the precisions the shaders run in (and their numpy twins round to)
PRECISIONS = ("f32", "f16")


def check_precision(precision: str) -> None:
    """One-line :class:`VrnError` unless ``precision`` is one of :data:`PRECISIONS`."""
    if precision not in PRECISIONS:
        raise VrnError(
            f"precision = {precision!r} is not allowed; choose {' or '.join(PRECISIONS)}"
        )


def wgsl_type(precision: str) -> str:
    """The WGSL scalar type ``T`` a shader generated for ``precision`` computes in (checked)."""
    check_precision(precision)
    return precision


def mlp_forward(x: np.ndarray, layers: list[Layer], precision: str = "f32") -> np.ndarray:
    """Evaluate the MLP on ``x: [N, in]``; returns ``[N, out]`` float32.

    ``precision="f16"`` rounds weights, inputs and each layer's result to float16 (the GPU's f16
    path also accumulates in f16, so expect differences of a few f16 ulps per layer).
    """
    check_precision(precision)
    dt = np.float16 if precision == "f16" else np.float32
    h = np.asarray(x, dtype=np.float32).astype(dt).astype(np.float32)
    n_in = layers[0].n_in if layers else h.shape[-1]
    if h.ndim != 2 or h.shape[1] != n_in:
        raise VrnError(f"mlp_forward: x has shape {list(h.shape)}, expected [N, {n_in}]")
    for layer in layers:
        w = layer.weight.astype(dt).astype(np.float32)
        b = layer.bias.astype(dt).astype(np.float32)
        h = activate(h @ w.T + b, layer.act).astype(dt).astype(np.float32)
    return h


def macs(layers: list[Layer]) -> int:
    """Multiply-adds per evaluation: the non-zero weights, which is what the generated kernels
    execute (they skip zero weights; a dense network has ``n_in * n_out`` per layer)."""
    return sum(int(np.count_nonzero(layer.weight)) for layer in layers)


def pack_weights(layers: list[Layer]) -> np.ndarray:
    """Flatten to float32: per layer ``W`` row-major then ``b`` (the storage-buffer layout)."""
    return np.concatenate(
        [np.concatenate([lay.weight.ravel(), lay.bias]) for lay in layers]
    ).astype(np.float32)
