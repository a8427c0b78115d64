"""The one GPU layer: default device, shader loading, pipeline cache, read-back, timestamps.

Everything that talks to wgpu goes through here, so lavapipe and real GPUs behave the same.
Reference (numpy) implementations elsewhere never import this package.
"""

from vrneural.gpu.device import AdapterSummary, adapter_summary, get_device, has_feature
from vrneural.gpu.pipelines import PipelineCache, compute_pipeline
from vrneural.gpu.readback import read_buffer, read_texture, upload_buffer, upload_texture
from vrneural.gpu.shaders import load_wgsl, render_wgsl
from vrneural.gpu.timing import GpuTimer

__all__ = [
    "AdapterSummary",
    "GpuTimer",
    "PipelineCache",
    "adapter_summary",
    "compute_pipeline",
    "get_device",
    "has_feature",
    "load_wgsl",
    "read_buffer",
    "read_texture",
    "render_wgsl",
    "upload_buffer",
    "upload_texture",
]
