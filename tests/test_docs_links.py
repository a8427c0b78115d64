"""The documentation's links and images resolve.

Two levels: the Markdown sources (README.md, whose ``docs/`` links GitHub follows, and every
page under docs/, with the two pages the site generates: see scripts/docs_hooks.py) by GitHub's
slug rules, which the site's ``toc`` slugify follows; and the built site itself (mkdocs build
--strict, tests/docs_helpers.py): every ``href`` and ``src`` of every page is a file of the
site and every ``#anchor`` an id on its target page. Every page of the site has content."""

from __future__ import annotations

import re
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest
from docs_helpers import ROOT, article, built_site, pages, plain

from vrneural.cli.reference import PAGE, markdown

DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
LINK = re.compile(r"\]\(([^)\s]+)\)")
IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")


@pytest.fixture(scope="module")
def generated() -> dict[Path, str]:
    """The pages the site's build hook generates: path in the tree -> Markdown."""
    return {
        (ROOT / "docs" / "index.md").resolve(): (ROOT / "README.md").read_text(),
        (ROOT / "docs" / PAGE).resolve(): markdown(),
    }


def slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading: lower case, punctuation dropped, spaces -> '-'."""
    text = heading.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(text: str) -> set[str]:
    seen: dict[str, int] = {}
    out = set()
    in_code = False
    for line in text.splitlines():
        if line.startswith("```"):
            in_code = not in_code
        m = None if in_code else re.match(r"#{1,6} (.+)", line)
        if m:
            s = slug(m.group(1))
            n = seen.get(s, 0)
            seen[s] = n + 1
            out.add(s if n == 0 else f"{s}-{n}")
    return out


def links(text: str) -> list[str]:
    return [t for t in LINK.findall(text) if not re.match(r"\w+:", t)]


def test_slug_rules():
    assert slug("The paper's own Table 1 against the targets") == (
        "the-papers-own-table-1-against-the-targets"
    )
    assert slug("Scoring a pack (`vrneural eval`)") == "scoring-a-pack-vrneural-eval"
    assert slug("Kernels: generated constants vs storage buffer vs PyTorch CPU, f32 vs f16") == (
        "kernels-generated-constants-vs-storage-buffer-vs-pytorch-cpu-f32-vs-f16"
    )


def test_the_site_slugs_headings_as_github_does():
    """The site's toc slugify gives GitHub's anchors, so one link works in both."""
    from pymdownx.slugs import slugify

    site_slug = slugify(case="lower")
    for h in ("A wide start pruned to 8 (--width, --init-from)", "Carpet and fabric at 128^2"):
        assert site_slug(h, "-") == slug(h)


def test_the_docs_have_links():
    assert sum(len(links(p.read_text())) for p in DOCS) > 20  # the regex still finds them
    assert sum(len(IMAGE.findall(p.read_text())) for p in DOCS) > 10


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_resolve(doc, generated):
    bad = []
    for target in links(doc.read_text(encoding="utf-8")):
        file, _, anchor = target.partition("#")
        dest = (doc.parent / file).resolve() if file else doc.resolve()
        text = generated.get(dest)
        if text is None and not dest.exists():
            bad.append(f"{target}: no file {dest.relative_to(ROOT)}")
            continue
        if anchor and dest.suffix == ".md":
            text = text if text is not None else dest.read_text(encoding="utf-8")
            if anchor not in anchors(text):
                bad.append(f"{target}: no heading with anchor #{anchor} in {dest.name}")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: str(p.relative_to(ROOT)))
def test_images_exist(doc):
    bad = []
    for target in IMAGE.findall(doc.read_text(encoding="utf-8")):
        if re.match(r"\w+:", target):
            bad.append(f"{target}: an image from outside the repository")
        elif not (doc.parent / target).is_file():
            bad.append(f"{target}: no image file")
    assert not bad, "\n".join(bad)


def _ids(page: Path, cache: dict[Path, set[str]]) -> set[str]:
    if page not in cache:
        cache[page] = set(re.findall(r'\bid="([^"]+)"', page.read_text(encoding="utf-8")))
    return cache[page]


def test_every_link_and_image_of_the_built_site_resolves():
    site = built_site()
    bad, ids, n = [], {}, 0
    for page in pages(site):
        text = page.read_text(encoding="utf-8")
        for attr, url in re.findall(r'\b(href|src)="([^"]*)"', text):
            parts = urlsplit(url)
            if parts.scheme or parts.netloc or url.startswith(("mailto:", "data:")):
                continue
            n += 1
            path = unquote(parts.path)
            dest = (page.parent / path).resolve() if path else page
            if path.endswith("/") or dest.is_dir():
                dest = dest / "index.html"
            where = f"{page.relative_to(site)}: {attr}={url}"
            if not dest.is_file():
                bad.append(f"{where}: no file {dest}")
            elif parts.fragment and dest.suffix == ".html":
                if unquote(parts.fragment) not in _ids(dest, ids):
                    bad.append(f"{where}: no id #{parts.fragment} on the target page")
    assert n > 500  # every page's navigation, links and images were seen
    assert not bad, "\n".join(bad[:50])


def test_the_built_pages_show_their_images():
    site = built_site()
    home = article(site / "index.html")
    assert 'src="demo_eyes.png"' in home  # the README's picture, on the home page
    imgs = [src for p in pages(site) for src in re.findall(r'<img[^>]*src="([^"]+)"', article(p))]
    assert len(imgs) > 10


def test_every_page_of_the_site_has_content():
    """No stubs: each page in the navigation holds at least 150 words of its own."""
    site = built_site()
    home = (site / "index.html").read_text(encoding="utf-8")
    nav = re.findall(r'<a href="([^"#]*)" class="md-nav__link', home)
    targets = {(site / (h or ".")).resolve() for h in nav}
    assert len(targets) >= 18
    thin = []
    for t in sorted(targets):
        page = t / "index.html" if t.is_dir() else t
        words = len(plain(article(page)).split())
        if words < 150:
            thin.append(f"{page.relative_to(site)}: {words} words")
    assert not thin, "\n".join(thin)


def test_the_api_pages_show_no_sphinx_role_names():
    """The docstrings' ``:func:`x``` render as the code span alone (scripts/docs_hooks.py)."""
    site = built_site()
    api = article(site / "reference" / "api" / "index.html")
    assert api.count("<code>") > 100  # the docstrings are there
    bad = [p.relative_to(site) for p in pages(site) if re.search(r":\w+:<code>", article(p))]
    assert not bad
