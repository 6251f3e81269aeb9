"""The user documentation holds together: README.md stays short, the docs/ pages exist, and
every relative link (and #anchor) in README.md, BENCHMARKS.md and docs/*.md resolves inside
the repository.

Anchors are GitHub's heading ids: the heading text without markdown, lower-cased, with
everything but letters, digits, ``_``, ``-`` and spaces removed and spaces turned into
``-`` (a repeated heading gets ``-1``, ``-2``, ...). Links inside fenced code blocks and
inline code are not links.
"""

from __future__ import annotations

import re
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
#: The longest README allowed (reference material goes to docs/).
README_MAX_LINES = 300
#: The pages the README and the other pages point a reader to.
PAGES = ("ros_api.md", "parameters.md", "real_robot.md", "simulation.md", "strategies.md",
         "benchmarking.md", "architecture.md", "robustness.md")
#: Pages written on another branch: a link to one may dangle only while it does not exist
#: (once it exists its anchors are checked like any other page's).
PENDING_PAGES = {DOCS / "experiments.md"}
#: Largest committed documentation image.
IMAGE_MAX_BYTES = 300 * 1024

_FENCE = re.compile(r"^\s*(```|~~~)")
_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
_INLINE_CODE = re.compile(r"`[^`]*`")
_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
_HTML_ID = re.compile(r"<a\s+(?:name|id)=\"([^\"]+)\"")


def _prose_lines(text: str) -> list[tuple[int, str]]:
    """(line number, line) of the lines outside fenced code blocks."""
    out, fenced = [], False
    for i, line in enumerate(text.splitlines(), 1):
        if _FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            out.append((i, line))
    return out


def slug(heading: str) -> str:
    """GitHub's anchor of a heading's text."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)   # links -> their text
    text = re.sub(r"<[^>]+>", "", text)                          # inline HTML
    text = text.replace("`", "").strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """Every anchor a link may name in ``path``."""
    seen: dict[str, int] = {}
    out: set[str] = set()
    for _, line in _prose_lines(path.read_text()):
        out.update(_HTML_ID.findall(line))
        m = _HEADING.match(line)
        if not m:
            continue
        base = slug(m.group(2))
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    return out


def links(path: Path) -> list[tuple[int, str]]:
    """(line, target) of every link and image in ``path``'s prose."""
    out = []
    for i, line in _prose_lines(path.read_text()):
        for m in _LINK.finditer(_INLINE_CODE.sub("", line)):
            out.append((i, m.group(1)))
    return out


def _doc_files() -> list[Path]:
    return [README, ROOT / "BENCHMARKS.md"] + sorted(DOCS.glob("*.md"))


def test_readme_is_short():
    n = len(README.read_text().splitlines())
    assert n <= README_MAX_LINES, (f"README.md has {n} lines, at most {README_MAX_LINES}: "
                                   "move reference material to docs/")


@pytest.mark.parametrize("page", PAGES)
def test_docs_page_exists_and_the_readme_links_it(page):
    path = DOCS / page
    assert path.is_file(), f"docs/{page} is missing"
    assert path.read_text().strip(), f"docs/{page} is empty"
    targets = {t.split("#")[0] for _, t in links(README)}
    assert f"docs/{page}" in targets, f"README.md does not link docs/{page}"


@pytest.mark.parametrize("path", _doc_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_and_anchors_resolve(path):
    bad = []
    for line, target in links(path):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):     # http:, https:, mailto:
            continue
        file_part, _, anchor = target.partition("#")
        dest = (path.parent / unquote(file_part)).resolve() if file_part else path
        where = f"{path.relative_to(ROOT)}:{line}: {target}"
        if ROOT not in dest.parents and dest != ROOT:
            bad.append(f"{where} (leaves the repository)")
            continue
        if not dest.exists():
            if dest not in PENDING_PAGES:
                bad.append(f"{where} (no such file)")
            continue
        if anchor and dest.suffix == ".md" and unquote(anchor) not in anchors(dest):
            bad.append(f"{where} (no heading with anchor #{anchor} in "
                       f"{dest.relative_to(ROOT)})")
    assert not bad, "broken links:\n" + "\n".join(bad)


def test_documentation_images_are_small():
    images = sorted((DOCS / "images").glob("*"))
    assert images, "docs/images/ holds no picture"
    big = [f"{p.name}: {p.stat().st_size} bytes" for p in images
           if p.stat().st_size > IMAGE_MAX_BYTES]
    assert not big, f"images over {IMAGE_MAX_BYTES} bytes: {big}"


@pytest.mark.parametrize("heading,anchor", [
    ("## `target_selector` parameters", "target_selector-parameters"),
    ("## 7. Nav2", "7-nav2"),
    ("### Watch it live in RViz", "watch-it-live-in-rviz"),
    ("## Navigation: goal_pose and navigate_to_pose", "navigation-goal_pose-and-navigate_to_pose"),
    ("## [Link](x.md) & more!", "link--more"),
])
def test_slug_follows_github(heading, anchor):
    assert slug(_HEADING.match(heading).group(2)) == anchor


def test_the_link_checker_finds_broken_links_and_anchors(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("# Title\n\n## A `b` c\n\n[ok](#a-b-c) [bad](#nope) `[code](#x)`\n"
                    "```\n[fenced](#y)\n```\n[file](missing.md)\n")
    assert links(page) == [(5, "#a-b-c"), (5, "#nope"), (9, "missing.md")]
    assert anchors(page) == {"title", "a-b-c"}
