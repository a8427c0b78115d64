"""vrneural: neural materials at VR frame rates.

Pipeline: BTF -> teacher -> distilled 8-wide student -> runtime pack (.vrnm) -> generated WGSL
that shades per-eye radiance textures in texture space, reused for N frames.
"""

__version__ = "0.1.0"
