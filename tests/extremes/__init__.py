"""The numerical-extreme cases of ``vrneural bench extremes`` (docs/extremes.md): one module
per group of case functions ``case(quick) -> dict`` and ``test_cases.py``, which runs each one
as a test marked ``extremes`` (the table of cases: :data:`vrneural.bench.configs.CASES`)."""
