"""WGSL sources and templates (package data), loaded with :func:`vrneural.gpu.load_wgsl`."""
