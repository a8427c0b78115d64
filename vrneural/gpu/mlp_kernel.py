"""GPU twin of :func:`vrneural.mlp.mlp_forward`: a batched MLP evaluator generated from
``shaders/mlp_eval.wgsl`` with weights as constants (or, for comparison, in a storage buffer)."""

from __future__ import annotations

import math

import numpy as np

from vrneural.gpu.bindings import Binding, Bindings
from vrneural.gpu.device import get_device
from vrneural.gpu.pipelines import compute_pipeline
from vrneural.gpu.readback import read_texture, upload_buffer
from vrneural.gpu.shaders import render_wgsl
from vrneural.gpu.timing import GpuTimer
from vrneural.gpu.unroll import IND, mlp_lines
from vrneural.mlp import ACT_CODE, Layer, pack_weights, wgsl_type

MAX_GROUPS_X = 32768
#: the evaluator's bindings (``weights``: buffer weights only)
BINDINGS = Bindings([
    Binding(0, "inputs", "storage", "array<f32>", "[N, N_IN]"),
    Binding(1, "out_tex", "storage_texture", "texture_storage_2d<rgba32float, write>"),
    Binding(2, "weights", "storage", "array<f32>", "per layer W[out, in], b[out]"),
])  # fmt: skip


def mlp_wgsl(layers: list[Layer], precision: str = "f32", buffer_weights: bool = False) -> str:
    """Generate the evaluator's WGSL for ``layers``."""
    dims = [layers[0].n_in] + [lay.n_out for lay in layers]
    T = wgsl_type(precision)
    return render_wgsl(
        "mlp_eval",
        layers=layers,
        n_in=dims[0],
        n_out=dims[-1],
        T=T,
        buffer_weights=buffer_weights,
        dims=dims,
        acts=[ACT_CODE[lay.act] for lay in layers],
        act_code=ACT_CODE,
        max_width=max(dims),
        bindings=BINDINGS.wgsl(None if buffer_weights else ("inputs", "out_tex")),
        body="" if buffer_weights else "\n".join(unrolled_body(layers, T)),
    )


def unrolled_body(layers: list[Layer], T: str) -> list[str]:
    """The constant-weight evaluator's body: inputs ``x0_k`` read from ``inputs[base + k]``,
    the unrolled layers, ``let y`` (the first four outputs, zero-padded)."""
    n_in, n_out, L = layers[0].n_in, layers[-1].n_out, len(layers)
    lines = [f"{IND}let x0_{k} = {T}(inputs[base + {k}u]);" for k in range(n_in)]
    lines += mlp_lines("x", [f"x0_{k}" for k in range(n_in)], layers, T)
    outs = [f"f32(x{L}_{k})" if k < n_out else "0.0" for k in range(4)]
    return [*lines, f"{IND}let y = vec4<f32>({', '.join(outs)});"]


class MlpKernel:
    """A compiled evaluator for one network; call :meth:`run` on ``[N, in]`` inputs."""

    def __init__(self, layers: list[Layer], precision: str = "f32", buffer_weights: bool = False):
        import wgpu

        self.layers = layers
        self.code = mlp_wgsl(layers, precision, buffer_weights)
        self.dev = get_device()
        self._wbuf = None
        if buffer_weights:
            self._wbuf = upload_buffer(pack_weights(layers), wgpu.BufferUsage.STORAGE)

    def run(self, x: np.ndarray, repeats: int = 1, timer: GpuTimer | None = None) -> np.ndarray:
        """Evaluate on ``x: [N, in]``; returns ``[N, min(out, 4)]`` float32.

        ``repeats`` > 1 dispatches the same work several times in one submission (for timing);
        pass a :class:`GpuTimer` to collect per-dispatch milliseconds under the name ``"mlp"``.
        """
        import wgpu

        x = np.ascontiguousarray(x, dtype=np.float32)
        n = x.shape[0]
        width = min(n, 4096)
        height = math.ceil(n / width)
        groups = math.ceil(n / 64)
        gx = min(groups, MAX_GROUPS_X)
        gy = math.ceil(groups / gx)
        pipe = compute_pipeline(
            self.code, constants={"N": n, "WIDTH": width, "STRIDE": gx * 64}, label="mlp_eval"
        )
        inp = upload_buffer(x, wgpu.BufferUsage.STORAGE)
        out = self.dev.create_texture(
            size=(width, height, 1),
            format="rgba32float",
            usage=wgpu.TextureUsage.STORAGE_BINDING | wgpu.TextureUsage.COPY_SRC,
        )
        res = {"inputs": {"buffer": inp}, "out_tex": out.create_view()}
        if self._wbuf is not None:
            res["weights"] = {"buffer": self._wbuf}
        entries = BINDINGS.entries(res)
        bg = self.dev.create_bind_group(layout=pipe.get_bind_group_layout(0), entries=entries)
        enc = self.dev.create_command_encoder()
        for _ in range(repeats):
            cp = enc.begin_compute_pass(timestamp_writes=timer.writes("mlp") if timer else None)
            cp.set_pipeline(pipe)
            cp.set_bind_group(0, bg)
            cp.dispatch_workgroups(gx, gy, 1)
            cp.end()
        if timer:
            timer.resolve(enc)
        self.dev.queue.submit([enc.finish()])
        y = read_texture(out).reshape(-1, 4)[:n]
        return y[:, : min(self.layers[-1].n_out, 4)]


def mlp_forward(
    x: np.ndarray, layers: list[Layer], precision: str = "f32", buffer_weights: bool = False
) -> np.ndarray:
    """GPU evaluation of the MLP on ``x: [N, in]`` -> ``[N, min(out, 4)]`` float32."""
    return MlpKernel(layers, precision, buffer_weights).run(x)
