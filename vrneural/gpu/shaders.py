"""WGSL lives in ``vrneural/shaders/*.wgsl`` (package data), loaded by name and cached.

Templates use Jinja2 (``{{ }}`` and ``{% %}``) for structure and includes; generated code (an
unrolled MLP with constant weights, the samplers, the bindings and uniform structs) comes from
Python functions that return WGSL lines (:mod:`vrneural.gpu.unroll`, :mod:`vrneural.gpu.bindings`,
``vrneural/runtime/codegen_*.py``), which tests can check and a debugger can step through.
Set ``VRNEURAL_DEBUG_WGSL=1`` to print generated WGSL with line numbers when compilation fails.
"""

from __future__ import annotations

import functools
import os
from importlib import resources

import jinja2
import numpy as np


@functools.cache
def load_wgsl(name: str) -> str:
    """Source text of ``vrneural/shaders/<name>`` (``.wgsl`` appended when missing)."""
    if not name.endswith(".wgsl"):
        name += ".wgsl"
    return resources.files("vrneural.shaders").joinpath(name).read_text()


@functools.cache
def _env() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FunctionLoader(lambda n: load_wgsl(n)),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
    )
    env.filters["wgsl"] = lambda x, t="f32": wgsl_float(x, "h" if t == "f16" else "")
    return env


def wgsl_float(x: float, suffix: str = "") -> str:
    """A float literal WGSL accepts, exact for float32 (``repr`` round-trips float64)."""
    v = float(np.float32(x)) if suffix == "" else float(np.float16(x))
    s = repr(v)
    if "inf" in s or "nan" in s:
        raise ValueError(f"non-finite constant {x} cannot go into WGSL")
    if "e" not in s and "." not in s:
        s += ".0"
    return s + (suffix or "f")


def render_wgsl(name: str, **ctx) -> str:
    """Render template ``shaders/<name>`` (``.wgsl`` appended when missing) with ``ctx``."""
    return _env().get_template(name).render(**ctx)


def numbered(src: str) -> str:
    """WGSL with line numbers, for error messages."""
    return "\n".join(f"{i + 1:5d}  {line}" for i, line in enumerate(src.splitlines()))


def debug_enabled() -> bool:
    return os.environ.get("VRNEURAL_DEBUG_WGSL", "") not in ("", "0")
