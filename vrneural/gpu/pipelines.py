"""One cache of shader modules and compute pipelines, keyed by a hash of their inputs."""

from __future__ import annotations

import hashlib
import sys
from dataclasses import dataclass, field

from vrneural.gpu.device import get_device
from vrneural.gpu.shaders import debug_enabled, numbered


@dataclass
class PipelineCache:
    """Shader modules and pipelines by content hash, with a hit counter."""

    modules: dict = field(default_factory=dict)
    pipelines: dict = field(default_factory=dict)
    hits: int = 0

    def module(self, code: str, label: str = ""):
        key = hashlib.sha256(code.encode()).hexdigest()
        if key in self.modules:
            self.hits += 1
            return self.modules[key]
        try:
            m = get_device().create_shader_module(code=code, label=label)
        except Exception:
            if debug_enabled():
                print(f"--- WGSL for {label or 'shader'} ---\n{numbered(code)}", file=sys.stderr)
            raise
        self.modules[key] = m
        return m

    def compute(
        self, code: str, entry: str = "main", constants: dict | None = None, label: str = ""
    ):
        """A compute pipeline with ``layout="auto"`` for WGSL ``code``."""
        consts = dict(sorted((constants or {}).items()))
        key = hashlib.sha256(f"{code}\0{entry}\0{consts}".encode()).hexdigest()
        if key in self.pipelines:
            self.hits += 1
            return self.pipelines[key]
        mod = self.module(code, label)
        stage = {"module": mod, "entry_point": entry}
        if consts:
            stage["constants"] = consts
        p = get_device().create_compute_pipeline(layout="auto", compute=stage, label=label)
        self.pipelines[key] = p
        return p


#: the process-wide cache
PIPELINES = PipelineCache()


def compute_pipeline(
    code: str, entry: str = "main", constants: dict | None = None, label: str = ""
):
    """Cached compute pipeline from the process-wide :class:`PipelineCache`."""
    return PIPELINES.compute(code, entry, constants, label)
