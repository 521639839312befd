"""Committed study results and the docs tables that quote them, kept equal by construction.

A study whose numbers the docs quote is committed as ``docs/results/<study>/``: its ``results.csv``, the
``config.yaml`` that made it, its task families' CSV files, and the ``report.md``, ``report.html`` and plots that
``factorworld report`` regenerates from them (``plotly.min.js``, which report.html needs next to it, is a link to
one shared copy: :func:`share_plotly_js`). A table in ``docs/*.md`` that comes from such a report is
fenced by two markers naming the study folder, the report's section (the start of its ``## `` heading) and,
when the section has more than one table, which one (1 = the first)::

    <!-- results: quick "Success rates" -->

    | method | condition | N=2 | N=5 |
    ...

    <!-- /results -->

:func:`sync_docs` rewrites every fenced block from the reports (``factorworld sync-docs``) and
:func:`check_docs` lists the blocks that differ from them, byte for byte (``tests/test_docs_results.py``).
"""

from __future__ import annotations

import os
import re
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from ...core.io import atomic_write_text
from ..results.rows import RESULTS_FILE
from .html_report import HTML_FILE, PLOTLY_JS, write_plotly_js
from .markdown import REPORT_FILE
from .write import PUBLISHED_CONFIG, load_config, regenerate_report

RESULTS_ROOT = Path("docs") / "results"  # of the repository
MARKER = re.compile(r'<!-- results: (?P<study>[\w.-]+) "(?P<section>[^"]+)"(?: table (?P<table>[1-9][0-9]*))? -->')
OPENING = "<!-- results"
CLOSING = "<!-- /results -->"
CODE_FENCES = ("```", "~~~")


@dataclass(frozen=True)
class Fence:
    """One fenced block: where its opening marker is, what it names, and the text between the markers."""

    path: Path
    line: int  # of the opening marker, 1-based
    study: str
    section: str
    table: int
    body: str
    start: int  # offsets of the body in the file's text
    end: int

    def label(self) -> str:
        return f'{self.path}:{self.line} (results: {self.study} "{self.section}" table {self.table})'


def find_fences(text: str, path: Path) -> list[Fence]:
    """The fenced blocks of a Markdown text (markers inside code blocks are examples, not fences); a
    malformed, unclosed or nested marker is refused in one line."""
    fences, opened, offset, code = [], None, 0, ""  # code: the fence that opened the code block, if any
    for number, line in enumerate(text.splitlines(keepends=True), start=1):
        stripped = line.strip()
        if stripped.startswith(CODE_FENCES) and (not code or stripped.startswith(code)):
            code = "" if code else stripped[:3]  # a ~~~ block is closed by ~~~ only, a ``` block by ```
        elif code:
            pass
        elif stripped.startswith(OPENING):
            match = MARKER.fullmatch(stripped)
            if match is None:
                raise ValueError(
                    f'{path}:{number}: malformed marker {stripped!r}; write <!-- results: STUDY "SECTION" -->'
                )
            if opened is not None:
                raise ValueError(f"{path}:{number}: a results marker inside the block opened on line {opened[0]}")
            opened = (number, match, offset + len(line))
        elif stripped == CLOSING:
            if opened is None:
                raise ValueError(f"{path}:{number}: {CLOSING} without an opening marker")
            first, match, start = opened
            table = int(match["table"] or 1)
            body = text[start:offset]
            fences.append(Fence(path, first, match["study"], match["section"], table, body, start, offset))
            opened = None
        offset += len(line)
    if opened is not None:
        raise ValueError(f"{path}:{opened[0]}: results block not closed with {CLOSING}")
    return fences


def report_table(report: str, section: str, table: int = 1) -> str:
    """The ``table``-th Markdown table (1 = first) of the report section whose ``## `` heading starts with
    ``section``, its lines joined by newlines; refused when no section or more than one matches."""
    headings = [i for i, line in enumerate(report.splitlines()) if line.startswith("## ")]
    lines = report.splitlines()
    matches = [i for i in headings if lines[i][3:].startswith(section)]
    if not matches:
        raise ValueError(f"no section heading starts with {section!r}")
    if len(matches) > 1:
        raise ValueError(
            f"several section headings start with {section!r}: " + "; ".join(lines[i][3:] for i in matches)
        )
    start = matches[0] + 1
    end = next((i for i in headings if i > matches[0]), len(lines))
    tables = _tables(lines[start:end])
    if table > len(tables):
        raise ValueError(f"report section {section!r} has {len(tables)} table(s), not {table}")
    return "\n".join(tables[table - 1])


def _tables(lines: list[str]) -> list[list[str]]:
    tables: list[list[str]] = []
    previous = False
    for line in lines:
        row = line.startswith("|")
        if row and not previous:
            tables.append([])
        if row:
            tables[-1].append(line)
        previous = row
    return tables


def fenced_body(table: str) -> str:
    """What stands between the two markers: a blank line, the table, a blank line (so that Markdown renders
    the table and the markers apart)."""
    return f"\n{table}\n\n"


# --- the committed studies ---------------------------------------------------------------------------


def committed_studies(results_root: Path) -> dict[str, Path]:
    """Study name -> its committed folder (each ``<results_root>/<study>/`` holding a ``results.csv``)."""
    if not results_root.is_dir():
        return {}
    return {p.name: p for p in sorted(results_root.iterdir()) if (p / RESULTS_FILE).is_file()}


def regenerate_studies(studies: Mapping[str, Path], out_root: Path | None = None) -> dict[str, str]:
    """Regenerate every committed study's report (in place, or into ``out_root/<study>/``); study -> report
    text. A folder named otherwise than the study its config names is refused."""
    reports = {}
    for name, folder in studies.items():
        if not (folder / PUBLISHED_CONFIG).is_file():
            raise FileNotFoundError(
                f"{folder} has no {PUBLISHED_CONFIG}: commit the config that made its {RESULTS_FILE}"
            )
        study = load_config(folder / PUBLISHED_CONFIG).name
        if study != name:
            raise ValueError(f"{folder} holds study {study!r}: its folder must be named {study}")
        out = None if out_root is None else out_root / name
        report, _ = regenerate_report(folder / RESULTS_FILE, None, out)
        reports[name] = report.read_text()
    return reports


def doc_files(docs_dir: Path) -> list[Path]:
    """The Markdown files whose fenced tables are checked: ``docs/*.md``."""
    return sorted(docs_dir.glob("*.md"))


def expected_body(fence: Fence, reports: Mapping[str, str]) -> str:
    """What ``fence`` must hold; refused in one line when it names no committed study or no such table."""
    if fence.study not in reports:
        committed = ", ".join(sorted(reports)) or "none"
        raise ValueError(
            f"{fence.label()} names study {fence.study!r}, which has no committed results under "
            f"{RESULTS_ROOT}/ (committed: {committed})"
        )
    try:
        return fenced_body(report_table(reports[fence.study], fence.section, fence.table))
    except ValueError as err:
        raise ValueError(f"{fence.label()}: {fence.study}/{REPORT_FILE}: {err}") from None


def check_docs(docs: Iterable[Path], reports: Mapping[str, str]) -> list[str]:
    """One line per fenced block that differs from its report's table or names none (and per malformed file)."""
    problems = []
    for path in docs:
        try:
            fences = find_fences(path.read_text(encoding="utf-8"), path)
        except ValueError as err:
            problems.append(str(err))
            continue
        for fence in fences:
            try:
                if fence.body != expected_body(fence, reports):
                    problems.append(f"{fence.label()} differs from {fence.study}/{REPORT_FILE}")
            except ValueError as err:
                problems.append(str(err))
    return problems


def sync_docs(docs: Iterable[Path], reports: Mapping[str, str]) -> list[Path]:
    """Rewrite every fenced block from its report; the files changed. Nothing is written when any block
    names no committed study or table (the error says which)."""
    updates = {}
    for path in docs:
        text = path.read_text(encoding="utf-8")
        new, last = [], 0
        for fence in find_fences(text, path):
            new += [text[last : fence.start], expected_body(fence, reports)]
            last = fence.end
        new.append(text[last:])
        if "".join(new) != text:
            updates[path] = "".join(new)
    for path, text in updates.items():
        atomic_write_text(path, text)
    return list(updates)


def stale_published(root: Path) -> list[str]:
    """What is stale in a checkout at ``root``: committed reports (report.md, report.html) that differ from their
    regeneration, a ``plotly.min.js`` that is not the installed Plotly's, and fenced docs blocks that differ from
    the reports (``factorworld sync-docs --check``)."""
    studies = committed_studies(root / RESULTS_ROOT)
    problems = []
    with tempfile.TemporaryDirectory() as tmp:
        reports = regenerate_studies(studies, Path(tmp))
        for name, folder in studies.items():
            for file, made in ((REPORT_FILE, reports[name]), (HTML_FILE, _text(Path(tmp) / name / HTML_FILE))):
                if _text(folder / file) != made:
                    problems.append(f"{folder / file} is not what its results.csv regenerates")
            if _text(folder / PLOTLY_JS) != _text(Path(tmp) / name / PLOTLY_JS):
                problems.append(f"{folder / PLOTLY_JS} is missing or not the installed Plotly's")
    return problems + check_docs(doc_files(root / "docs"), reports)


def _text(path: Path) -> str | None:
    return path.read_text(encoding="utf-8") if path.is_file() else None


def sync_published(root: Path) -> list[Path]:
    """Regenerate the committed reports in place (with one shared ``plotly.min.js``: :func:`share_plotly_js`),
    then rewrite the fenced docs blocks; the docs files changed (``factorworld sync-docs``)."""
    studies = committed_studies(root / RESULTS_ROOT)
    share_plotly_js(root / RESULTS_ROOT, studies)
    reports = regenerate_studies(studies)
    return sync_docs(doc_files(root / "docs"), reports)


def share_plotly_js(results_root: Path, studies: Mapping[str, Path]) -> None:
    """One ``plotly.min.js`` (4.8 MB) for every committed report.html: ``results_root/plotly.min.js``, the installed
    Plotly's, and in each study folder a relative link to it, so that a checkout holds it once and each report
    still opens from its folder (a regenerated report keeps a link whose target is current)."""
    shared = write_plotly_js(results_root)
    for folder in studies.values():
        link = folder / PLOTLY_JS
        target = os.path.relpath(shared, folder)
        if link.is_symlink() and os.readlink(link) == target:
            continue
        link.unlink(missing_ok=True)
        link.symlink_to(target)
