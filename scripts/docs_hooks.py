"""mkdocs hooks of the documentation site (``mkdocs.yml``: ``hooks:``).

Two pages are generated when the site is built, never written by hand:

- ``index.md``, the home page: the repository's README.md with its ``docs/`` link prefixes
  dropped (the README links into ``docs/``; the site's pages live at its root), so the README
  and the home page cannot drift apart;
- ``reference/cli.md``: :func:`vrneural.cli.reference.markdown`, from the command's parsers.

The docstrings use Sphinx roles (``:func:`~vrneural.x.f```); on the rendered pages the role
names are dropped, leaving the code span (:func:`on_page_content`).
"""

from __future__ import annotations

import re
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]


def home_page(readme: str) -> str:
    """README.md as the site's home page: links and images into ``docs/`` made site-relative."""
    return re.sub(r"\]\(docs/", "](", readme)


#: a Sphinx role before a rendered code span, and a leading ``~`` inside it
_ROLE = re.compile(r":(?:mod|func|class|meth|data|attr|exc|obj):(<code>)~?")


def on_page_content(html, page, config, files):
    return _ROLE.sub(r"\1", html)


def on_files(files, config):
    from vrneural.cli.reference import PAGE, markdown

    home = home_page((ROOT / "README.md").read_text(encoding="utf-8"))
    for uri, text in (("index.md", home), (PAGE, markdown())):
        old = files.get_file_from_path(uri)
        if old is not None:
            files.remove(old)
        files.append(File.generated(config, uri, content=text))
    return files
