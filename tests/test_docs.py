"""The manual stays true to the command line and to itself.

Every option of ``weldplan plan --help`` is documented in docs/ (the bench pages aside: they are
regenerated measurements, not the manual), and every relative link in docs/*.md and README.md
resolves: to a file that exists and, for a ``#anchor`` into a markdown page, to one of its
headings (GitHub's anchors). The checkers are tested on pages made to fail, so that they can.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
from pathlib import Path

import pytest

from weldplan.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"

_FENCE = re.compile(r"^\s*(```|~~~)")
_LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")


def _prose_lines(text: str) -> list[str]:
    """The lines of a markdown text outside fenced code blocks."""
    out, fenced = [], False
    for line in text.splitlines():
        if _FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            out.append(line)
    return out


def slug(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link's text only
    text = re.sub(r"[^\w\- ]", "", text.lower())
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """Every heading anchor of a markdown file (repeated headings get ``-1``, ``-2``...)."""
    seen: dict[str, int] = {}
    out = set()
    for line in _prose_lines(path.read_text(encoding="utf-8")):
        m = _HEADING.match(line)
        if not m:
            continue
        s = slug(m.group(2))
        n = seen.get(s, 0)
        seen[s] = n + 1
        out.add(s if n == 0 else f"{s}-{n}")
    return out


def broken_links(page: Path) -> list[str]:
    """``"page:line: target (why)"`` for every relative link of ``page`` that does not resolve."""
    bad = []
    lines = page.read_text(encoding="utf-8").splitlines()
    fenced = False
    for n, line in enumerate(lines, start=1):
        if _FENCE.match(line):
            fenced = not fenced
            continue
        if fenced:
            continue
        for target in _LINK.findall(re.sub(r"`[^`]*`", "", line)):
            if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
                continue
            file, _, anchor = target.partition("#")
            dest = page if not file else (page.parent / file).resolve()
            if not dest.exists():
                bad.append(f"{page.name}:{n}: {target} (no such file)")
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                bad.append(f"{page.name}:{n}: {target} (no heading '#{anchor}' in {dest.name})")
    return bad


def plan_options() -> list[str]:
    """The long options of ``weldplan plan`` (``--help`` aside)."""
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    plan = sub.choices["plan"]
    return sorted(
        s for a in plan._actions for s in a.option_strings if s.startswith("--") and s != "--help"
    )


def undocumented(options: list[str], texts: list[str]) -> list[str]:
    """The options that no text names as a whole word (``--tool`` is not ``--tool-csv``)."""
    return [
        o
        for o in options
        if not any(re.search(rf"(?<![\w-]){re.escape(o)}(?![\w-])", t) for t in texts)
    ]


def manual_pages() -> list[Path]:
    return sorted(p for p in DOCS.glob("*.md") if not p.name.startswith("bench-"))


def test_plan_options_are_read_from_the_parser() -> None:
    opts = plan_options()
    assert len(opts) > 40
    assert {"--tool", "--tool-csv", "--robot", "--up", "--se3-time", "-o"} - set(opts) == {"-o"}


def test_every_plan_option_is_in_the_manual() -> None:
    texts = [p.read_text(encoding="utf-8") for p in manual_pages()]
    missing = undocumented(plan_options(), texts)
    assert not missing, f"weldplan plan options documented nowhere in docs/: {missing}"


def test_the_option_check_tells_prefixes_apart() -> None:
    assert undocumented(["--tool", "--tool-csv"], ["give --tool-csv F"]) == ["--tool"]
    assert undocumented(["--tool"], ["`--tool URDF`"]) == []


def station_keys() -> set[str]:
    """Every key a station file may hold (:mod:`weldplan.station.load`'s tables and the settings
    objects' fields)."""
    import weldplan.station.load as load
    import weldplan.station.model as m

    keys = set(load._TOP) | load._PART | load._ROBOT | load._TOOL | load._SEARCH
    for cls in (m.CellSettings, m.RouteSettings, m.ToolSettings, m.OutputSpec):
        keys |= {f.name for f in dataclasses.fields(cls)}
    return keys


def test_every_station_key_is_in_station_md() -> None:
    text = (DOCS / "station.md").read_text(encoding="utf-8")
    code = re.findall(r"`([^`]*)`", text)
    keys = station_keys()
    assert {"pitch", "se3_time", "weld_time", "up", "tool_csv"} <= keys
    missing = sorted(k for k in keys if not any(re.search(rf"\b{k}\b", c) for c in code))
    assert not missing, f"station keys not in docs/station.md: {missing}"


@pytest.mark.parametrize(
    "page", [*sorted(DOCS.glob("*.md")), ROOT / "README.md"], ids=lambda p: p.name
)
def test_every_relative_link_resolves(page: Path) -> None:
    assert broken_links(page) == []


def test_the_link_check_finds_missing_files_and_headings(tmp_path: Path) -> None:
    (tmp_path / "b.md").write_text("# The `--cost time`: a title\n\n## Twice\n\n## Twice\n")
    a = tmp_path / "a.md"
    a.write_text(
        "[ok](b.md) [ok](b.md#the---cost-time-a-title) [ok](b.md#twice-1) [ok](#top)\n"
        "# Top\n"
        "[gone](c.md) [no heading](b.md#nowhere) [web](https://example.org/x.md)\n"
        "```\n[in code](d.md)\n```\n"
    )
    assert broken_links(a) == [
        "a.md:3: c.md (no such file)",
        "a.md:3: b.md#nowhere (no heading '#nowhere' in b.md)",
    ]
