"""Code comments say what the code does; experiment history lives in docs/experiments.md.

Every ``.py`` file under ``explore_seg/`` and ``sim_bridge/`` is scanned, comment and string
tokens only (docstrings, parameter descriptions and log strings are strings), for:

* a commit hash: a 7-40 character lowercase hexadecimal token with at least one digit and
  one letter that is not part of a longer word (so SHA-256 digests, ``#abcdef`` colours,
  ``0x7f`` literals and identifiers do not count);
* an ``out/`` folder (the benchmark's git-ignored output folders);
* "tried, not kept" / "tried (not kept)" (a verdict belongs in the decision record).

The scanner is checked against ``router.py`` as it was before the history moved out, so the
tree test cannot pass because the scanner finds nothing.
"""

from __future__ import annotations

import ast
import io
import re
import subprocess
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCANNED = ("explore_seg", "sim_bridge")
ROUTER = ROOT / "explore_seg" / "core" / "selection" / "router.py"
#: router.py before its history moved to docs/experiments.md.
HISTORY_COMMIT = "eca803b"
MAX_ROUTER_DOCSTRING_LINES = 60

HASH = re.compile(r"(?<![0-9A-Za-z_#])[0-9a-f]{7,40}(?![0-9A-Za-z_])")
OUT_FOLDER = re.compile(r"(?<![0-9A-Za-z_./-])out/[A-Za-z0-9_.-]+")
NOT_KEPT = re.compile(r"tried[,:;]?\s*\(?\s*not\s+kept", re.IGNORECASE)
#: The before-stop hook's rule; every hit of it must also be a hit of the rules above.
HOOK = re.compile(r"(code|commit) [0-9a-f]{7,12}\b|tried, not kept|\bout/[a-z0-9_]+/")


def _is_hash(token: str) -> bool:
    return any(c.isdigit() for c in token) and any(c.isalpha() for c in token)


def text_findings(text: str, *, out_folders: bool = True) -> list[str]:
    """What one comment or string names: hashes, ``out/`` folders, "tried, not kept"."""
    found = [f"commit hash {m.group()!r}" for m in HASH.finditer(text) if _is_hash(m.group())]
    if out_folders:
        found += [f"out/ folder {m.group()!r}" for m in OUT_FOLDER.finditer(text)]
    found += [f"verdict {m.group()!r}" for m in NOT_KEPT.finditer(text)]
    return found


def _is_path_value(token: str) -> bool:
    """A string literal that is a bare relative path (a default the code uses, such as
    ``"out/sim"``), not prose that quotes one."""
    try:
        value = ast.literal_eval(token)
    except (ValueError, SyntaxError):
        return False
    return isinstance(value, str) and re.fullmatch(r"[A-Za-z0-9_./-]+", value) is not None


def source_findings(source: str) -> list[str]:
    """``line: finding`` for every comment and string token of a Python source."""
    kinds = {tokenize.COMMENT, tokenize.STRING}
    if hasattr(tokenize, "FSTRING_MIDDLE"):     # Python >= 3.12 splits f-strings
        kinds.add(tokenize.FSTRING_MIDDLE)
    out: list[str] = []
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type not in kinds:
            continue
        value_path = tok.type == tokenize.STRING and _is_path_value(tok.string)
        out += [f"{tok.start[0]}: {f}"
                for f in text_findings(tok.string, out_folders=not value_path)]
    return out


def _files() -> list[Path]:
    return sorted(p for sub in SCANNED for p in (ROOT / sub).rglob("*.py"))


@pytest.mark.parametrize("text", [
    "measured on code 308b78b with the metric disk",
    "(code 489a459 on the local branch exp_opt)",
    "the commit before routed, e43b08d",
    "full hash 951cbc5c0ffee1234567890abcdef0123456789a here",
    "``paired.py --out out/s25_ll3 --strategies routed``",
    "runs in out/margin",
    "Tried, not kept: the first leg",
    "a local tour horizon (tried (not kept))",
])
def test_history_is_found(text):
    assert text_findings(text), text


@pytest.mark.parametrize("text", [
    "sha256 " + "0123456789abcdef" * 4,   # a 64-character digest
    "colour #a1b2c3d and #abcdef",
    "mask 0x7f00ff1 and 0xdeadbeef1",
    "cell 1234567 of 7654321",             # digits only
    "accepted deadbeef, decade",          # letters only
    "name foo_1a2b3c4d and 1a2b3c4dx",    # part of a longer word
    "write to --out DIR; the output folder",
    "tried first, then kept",
])
def test_not_history(text):
    assert not text_findings(text), text_findings(text)


def test_a_path_default_is_not_history_but_prose_quoting_it_is():
    assert not source_findings('output_dir = "out/sim"\n')
    assert source_findings('x = "runs in out/s25_ll3 were faster"\n')
    assert source_findings('# runs in out/margin\n')
    assert source_findings('x = f"made with code {n} 489a459"\n')


def test_the_scanner_finds_the_history_that_was_in_router_py():
    try:
        old = subprocess.run(
            ["git", "show", f"{HISTORY_COMMIT}:explore_seg/core/selection/router.py"],
            cwd=ROOT, capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError) as e:
        pytest.skip(f"git history not available: {e}")
    found = source_findings(old)
    kinds = {f.split(": ", 1)[1].split(" '")[0] for f in found}
    assert {"commit hash", "out/ folder", "verdict"} <= kinds, found
    assert any("308b78b" in f for f in found) and any("out/s25_ll3" in f for f in found)
    for line in old.splitlines():
        if HOOK.search(line):
            assert text_findings(line), line


@pytest.mark.parametrize("path", _files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_experiment_history_in_code(path):
    src = path.read_text(encoding="utf-8")
    found = source_findings(src)
    hook = [f"{i}: hook rule {m.group()!r}" for i, line in enumerate(src.splitlines(), 1)
            for m in [HOOK.search(line)] if m]
    assert not found + hook, (
        f"{path.relative_to(ROOT)} holds experiment history (move it to docs/experiments.md "
        f"and link the entry): {found + hook}")


def test_router_docstring_is_short():
    doc = ast.get_docstring(ast.parse(ROUTER.read_text(encoding="utf-8")), clean=False) or ""
    n = len(doc.strip().splitlines())
    assert 0 < n <= MAX_ROUTER_DOCSTRING_LINES, (
        f"router.py's module docstring is {n} lines, expected at most "
        f"{MAX_ROUTER_DOCSTRING_LINES}: the algorithm, not its experiments")


EXPERIMENTS = ROOT / "docs" / "experiments.md"
LINK = re.compile(r"docs/experiments\.md#([A-Za-z0-9_-]+)")


def github_anchor(heading: str) -> str:
    """The anchor GitHub generates for a Markdown heading's text."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def test_github_anchor():
    assert github_anchor("Routed leftover length") == "routed-leftover-length"
    assert github_anchor("Selection: routed") == "selection-routed"
    assert github_anchor("Lock-step speed") == "lock-step-speed"


def test_every_link_to_the_decision_record_has_its_entry():
    headings = [line.lstrip("#").strip() for line in EXPERIMENTS.read_text().splitlines()
                if line.startswith("#")]
    anchors = [github_anchor(h) for h in headings]
    assert len(anchors) == len(set(anchors)), "headings must be unique (stable anchors)"
    links = {(p.relative_to(ROOT), m.group(1)) for p in _files()
             for m in LINK.finditer(p.read_text(encoding="utf-8"))}
    links |= {(EXPERIMENTS.relative_to(ROOT), m.group(1))
              for m in re.finditer(r"\]\(#([A-Za-z0-9_-]+)\)", EXPERIMENTS.read_text())}
    assert links, "no code links to docs/experiments.md"
    missing = sorted((str(p), a) for p, a in links if a not in anchors)
    assert not missing, f"links to entries that docs/experiments.md does not have: {missing}"


def test_the_decision_record_names_only_commits_in_the_repository():
    text = EXPERIMENTS.read_text()
    hashes = sorted({m.group() for m in HASH.finditer(text) if _is_hash(m.group())})
    assert hashes
    try:
        missing = [h for h in hashes if subprocess.run(
            ["git", "cat-file", "-e", f"{h}^{{commit}}"], cwd=ROOT,
            capture_output=True).returncode != 0]
    except OSError as e:
        pytest.skip(f"git not available: {e}")
    if len(missing) == len(hashes):
        pytest.skip("no history in this checkout (shallow clone or source archive)")
    assert not missing, f"docs/experiments.md names commits not in the repository: {missing}"
