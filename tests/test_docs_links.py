"""The documents' relative links resolve: every linked file exists and every #anchor names a heading of its file.

The README, the results page and the experiment log link into each other by heading anchors; a renamed heading or a
moved section would otherwise leave links that open the top of a page (or nothing) without anyone noticing.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ("README.md", "reports/RESULTS.md", "reports/experiments/README.md")
LINK = re.compile(r"\]\(([^()\s]+(?:\([^()\s]*\))?[^()\s]*)\)")  # [text](target), a target may hold one (...) pair
HEADING = re.compile(r"^#{1,6}\s+(.*?)\s*#*\s*$")
FENCE = re.compile(r"^\s*(```|~~~)")


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: markup dropped, lower case, punctuation other than - and _ removed, spaces
    to hyphens."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link in a heading keeps its text
    text = text.replace("`", "").lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def prose(path: Path) -> Iterator[tuple[int, str]]:
    """(line number, line) of a Markdown file's lines outside code fences."""
    fenced = False
    for number, line in enumerate(path.read_text().splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
        elif not fenced:
            yield number, line


def anchors(path: Path) -> set[str]:
    """Every heading anchor of a Markdown file, with GitHub's -1, -2 ... suffixes for repeated headings."""
    seen: dict[str, int] = {}
    out: set[str] = set()
    for _, line in prose(path):
        match = HEADING.match(line)
        if match:
            base = slug(match.group(1))
            n = seen.get(base, 0)
            seen[base] = n + 1
            out.add(base if n == 0 else f"{base}-{n}")
    return out


def links(path: Path) -> list[tuple[int, str]]:
    """(line number, target) of each relative link outside code fences and inline code."""
    out = []
    for number, line in prose(path):
        for target in LINK.findall(re.sub(r"`[^`]*`", "``", line)):
            if not re.match(r"[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto: ... are not checked
                out.append((number, target))
    return out


@pytest.mark.parametrize("doc", DOCS)
def test_relative_links_resolve(doc: str) -> None:
    source = ROOT / doc
    broken = []
    cache: dict[Path, set[str]] = {}
    for number, target in links(source):
        file_part, _, anchor = target.partition("#")
        linked = (source.parent / unquote(file_part)).resolve() if file_part else source
        if not linked.exists():
            broken.append(f"{doc}:{number}: {target} (no such file)")
            continue
        if anchor and linked.suffix == ".md":
            known = cache.setdefault(linked, anchors(linked))
            if anchor not in known:
                broken.append(f"{doc}:{number}: {target} (no heading with that anchor)")
    assert not broken, "\n".join(broken)


def test_slug_follows_github() -> None:
    assert slug("more150: the result: rule not met, by 0.002 rad") == "more150-the-result-rule-not-met-by-0002-rad"
    assert slug("The default pipeline (`make repro`: `cycle125`, best of three PPO seeds)") == (
        "the-default-pipeline-make-repro-cycle125-best-of-three-ppo-seeds")
    assert slug("[ahead150](x.md): a - b") == "ahead150-a---b"
