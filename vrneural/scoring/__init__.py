"""Scoring runtime packs against a BTF (`vrneural eval`), with numpy alone.

Dependencies point one way: ``cli`` and ``bench`` -> ``scoring`` -> ``material``, ``formats``,
``btf``.

- :mod:`.score`   the pack's slices as the shader computes them, and the metrics
- :mod:`.run`     which packs and BTF, the checks, the printed table and the written outputs
- :mod:`.figure`  slices.png: the BTF, each pack and its error at characteristic slices
- :mod:`.metrics` image metrics (FLIP, PSNR, SSIM), shared with the benchmarks
"""
