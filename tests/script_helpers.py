"""Loading a script of ``scripts/research/`` as a module in tests (the scripts are not a
package)."""

import importlib.util
from pathlib import Path

RESEARCH = Path(__file__).resolve().parents[1] / "scripts" / "research"


def load_research(name: str):
    """``scripts/research/NAME.py`` as a module."""
    spec = importlib.util.spec_from_file_location(name, RESEARCH / f"{name}.py")
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m
