"""Benchmarks that write JSON + Markdown + PNG. ``quality``: the paper's Table 1 on our BTFs."""
