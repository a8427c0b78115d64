"""One default device per process, with features and limits requested in one place."""

from __future__ import annotations

import functools
import os
import threading
import time
from dataclasses import asdict, dataclass, field

from vrneural.errors import VrnError

#: Features we use when the adapter has them. Requested here and nowhere else.
WANTED_FEATURES = ("shader-f16", "timestamp-query", "timestamp-query-inside-passes", "subgroup")
#: Limits we raise to the adapter's maximum (large radiance textures, big triangle buffers).
WANTED_LIMITS = (
    "max-texture-dimension-2d",
    "max-storage-buffer-binding-size",
    "max-buffer-size",
    "max-compute-workgroup-storage-size",
    "max-storage-textures-per-shader-stage",
)


#: Backends whose WGSL compute path we test (storage textures, f16, constant weights). wgpu
#: also offers OpenGL (e.g. Mesa's llvmpipe through EGL when no Vulkan driver is installed),
#: but our kernels give wrong results there (its view-dimension heuristics, no shader-f16),
#: so it is refused with the fix rather than used.
BACKENDS = ("Vulkan", "Metal", "D3D12")
#: Adapter types, best first (what power_preference="high-performance" means to us).
ADAPTER_TYPES = ("DiscreteGPU", "IntegratedGPU", "VirtualGPU", "CPU")
INSTALL_HINT = "on Debian install Mesa's CPU Vulkan driver: apt-get install -y mesa-vulkan-drivers"


def pick_adapter(infos: list[dict]) -> int:
    """Index of the adapter to use among ``infos`` (wgpu adapter info dicts), or -1.

    Only the backends in ``BACKENDS``; among them a discrete GPU before an integrated one
    before a CPU driver, then Vulkan before Metal before D3D12, then enumeration order.
    """

    def rank(i: int) -> tuple[int, int, int]:
        info = infos[i]
        kind = info.get("adapter_type", "")
        kind_rank = ADAPTER_TYPES.index(kind) if kind in ADAPTER_TYPES else len(ADAPTER_TYPES)
        return (kind_rank, BACKENDS.index(info["backend_type"]), i)

    usable = [i for i, info in enumerate(infos) if info.get("backend_type") in BACKENDS]
    return min(usable, key=rank) if usable else -1


@functools.cache
def _adapter():
    # lavapipe (and other Mesa drivers) warn about XDG_RUNTIME_DIR when it is unset; harmless
    os.environ.setdefault("XDG_RUNTIME_DIR", "/tmp")
    import wgpu

    try:
        adapters = list(wgpu.gpu.enumerate_adapters_sync())
    except Exception as e:  # wgpu raises a plain RuntimeError when no driver exists
        err = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise VrnError(f"no GPU adapter found (wgpu: {err}); {INSTALL_HINT}") from None
    infos = [dict(a.info) for a in adapters]
    i = pick_adapter(infos)
    if i < 0:
        found = ", ".join(
            f"{info.get('device', '') or info.get('description', '') or '?'} "
            f"({info.get('backend_type', '?')})"
            for info in infos
        )
        raise VrnError(
            f"no Vulkan, Metal or D3D12 GPU adapter found (wgpu found: {found or 'none'}; "
            f"OpenGL is not supported); {INSTALL_HINT}"
        )
    return adapters[i]


@functools.cache
def get_device():
    """The process-wide ``GPUDevice`` with every wanted feature the adapter offers."""
    adapter = _adapter()
    feats = [f for f in WANTED_FEATURES if f in adapter.features]
    limits = {k: adapter.limits[k] for k in WANTED_LIMITS if k in adapter.limits}
    return adapter.request_device_sync(required_features=feats, required_limits=limits)


def poll_thread_cpu() -> float | None:
    """CPU seconds used so far by wgpu-py's device-poll thread(s): they poll the device and run
    the map callbacks of read-backs, host work a frame causes off the calling thread (0 before
    any exists; None where the platform has no per-thread CPU clocks)."""
    if not hasattr(time, "pthread_getcpuclockid"):
        return None
    total = 0.0
    for t in threading.enumerate():
        if type(t).__name__ == "PollThread" and t.ident is not None:
            try:
                total += time.clock_gettime(time.pthread_getcpuclockid(t.ident))
            except OSError:  # it ended meanwhile
                pass
    return total


def has_feature(name: str) -> bool:
    """Whether the default device was created with feature ``name``."""
    return name in get_device().features


@dataclass
class AdapterSummary:
    """What a user needs to know about the adapter, for `vrneural info` and every result file."""

    name: str
    vendor: str
    backend: str
    adapter_type: str
    driver: str
    is_cpu: bool
    features: dict[str, bool] = field(default_factory=dict)
    limits: dict[str, int] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return asdict(self)


@functools.cache
def adapter_summary() -> AdapterSummary:
    """Summarise the default adapter (name, backend, type, driver, key features and limits)."""
    a = _adapter()
    info = a.info
    dev = get_device()
    name = info.get("device", "") or info.get("description", "")
    keys = ("shader-f16", "timestamp-query", "subgroup")
    return AdapterSummary(
        name=name,
        vendor=info.get("vendor", ""),
        backend=info.get("backend_type", ""),
        adapter_type=info.get("adapter_type", ""),
        driver=info.get("description", ""),
        is_cpu=info.get("adapter_type", "") == "CPU" or "llvmpipe" in name.lower(),
        features={k: k in dev.features for k in keys},
        limits={
            "max_texture_dimension_2d": int(dev.limits["max-texture-dimension-2d"]),
            "max_storage_buffer_binding_size": int(dev.limits["max-storage-buffer-binding-size"]),
            "max_buffer_size": int(dev.limits["max-buffer-size"]),
            "max_compute_workgroup_size_x": int(dev.limits["max-compute-workgroup-size-x"]),
        },
    )
