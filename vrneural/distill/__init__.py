"""Teacher, student and baselines (PyTorch): training, distillation, export to ``.vrnm``.

Dependencies point one way: ``cli`` -> ``distill`` -> ``material``/``formats``/``btf``. torch is
imported by these modules, so the CLI imports them only inside its handlers.

- :mod:`.config`    TeachConfig / DistillConfig (one dataclass per stage)
- :mod:`.models`    torch twins of :mod:`vrneural.material` (``single`` and ``coarse_fine``)
- :mod:`.data`      BTF slices -> batches, held-out test directions, jittered lookups, sharding
- :mod:`.train`     the shared trainer loop (checkpoint/resume/Ctrl-C/DDP/progress bar)
- :mod:`.checkpoint` safe ``weights_only`` checkpoint loading and validation
- :mod:`.outputs`   the files a stage writes, checked before any work (inputs, --force, --resume)
- :mod:`.teach`, :mod:`.distill`  the two stages; :mod:`.lafortune` the analytic baseline
- :mod:`.export`    checkpoint -> :class:`~vrneural.material.NeuralMaterial` -> ``.vrnm``
"""
