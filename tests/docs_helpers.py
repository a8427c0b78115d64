"""The documentation site for the docs tests: built once per test session with
``mkdocs build --strict`` (or the one ``scripts/test.sh`` just built, named by
``VRNEURAL_DOCS_SITE``), and helpers to read its HTML."""

from __future__ import annotations

import atexit
import functools
import html
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@functools.lru_cache(maxsize=1)
def built_site() -> Path:
    """The built site's folder (``index.html`` at its root)."""
    given = os.environ.get("VRNEURAL_DOCS_SITE")
    if given and (Path(given) / "index.html").is_file():
        return Path(given)
    out = Path(tempfile.mkdtemp(prefix="vrneural-site-"))
    atexit.register(shutil.rmtree, out, True)
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    cmd = [sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet", "--site-dir", str(out)]
    r = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, f"mkdocs build --strict failed:\n{r.stdout}\n{r.stderr}"
    return out


def pages(site: Path) -> list[Path]:
    """Every HTML page of the site but the 404 page."""
    return sorted(p for p in site.rglob("*.html") if p.name != "404.html")


def article(page: Path) -> str:
    """The page's main content (the theme's ``<article>``), HTML."""
    text = page.read_text(encoding="utf-8")
    m = re.search(r"<article[^>]*>(.*)</article>", text, flags=re.S)
    return m.group(1) if m else ""


def plain(fragment: str) -> str:
    """HTML to text: tags dropped, entities decoded, whitespace collapsed."""
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", fragment)).split())
