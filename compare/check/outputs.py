"""What ``urdf2links check`` writes: the terminal lines, JUnit XML (``--junit``) and a Markdown summary
(``--markdown``).

JUnit: one ``<testcase>`` per robot, pair and scene (``classname`` its kind, ``name`` its file), a
``<failure>`` for a check that falls short, an ``<error>`` for a file that cannot be used; the message is the
largest problem, the text all of them. Markdown: a verdict line, the problems of every case that did not
pass, largest first (errors, then by value over tolerance), and a table of every case; fit for a pull
request comment or ``$GITHUB_STEP_SUMMARY``.
"""

from __future__ import annotations

import math
from pathlib import Path

from lxml import etree

from .cases import CaseResult

__all__ = ["write_junit", "markdown", "write_markdown", "verdict", "exit_status", "ordered"]


def exit_status(results: list[CaseResult]) -> int:
    """2 when a file could not be used, 1 when a check falls short, 0 when all hold."""
    statuses = {r.status for r in results}
    return 2 if "error" in statuses else 1 if "fail" in statuses else 0


def ordered(results: list[CaseResult]) -> list[CaseResult]:
    """The cases that did not pass, largest problem first: errors, then by value over tolerance."""
    bad = [r for r in results if r.status != "pass"]
    return sorted(bad, key=lambda r: (r.status != "error", -r.worst))


def verdict(results: list[CaseResult]) -> str:
    """One line: how many cases of each kind, how many fell short or could not run."""
    kinds = {k: sum(r.case.kind == k for r in results) for k in ("robot", "pair", "scene")}
    failed = sum(r.status == "fail" for r in results)
    errors = sum(r.status == "error" for r in results)
    what = ", ".join(f"{n} {k}{'s' if n != 1 else ''}" for k, n in kinds.items())
    if not failed and not errors:
        return (f"urdf2links check: all {len(results)} checks hold ({what})" if len(results) != 1
                else f"urdf2links check: the one check holds ({what})")
    return (f"urdf2links check: {failed} failed, {errors} could not run, {len(results) - failed - errors} passed "
            f"({what})")


def write_junit(results: list[CaseResult], path, *, suite: str = "urdf2links check") -> Path:
    """JUnit XML of ``results`` (module doc) at ``path``."""
    root = etree.Element("testsuites")
    ts = etree.SubElement(root, "testsuite", name=suite, tests=str(len(results)),
                          failures=str(sum(r.status == "fail" for r in results)),
                          errors=str(sum(r.status == "error" for r in results)),
                          time=f"{sum(r.seconds for r in results):.3f}")
    for r in results:
        tc = etree.SubElement(ts, "testcase", classname=f"urdf2links.{r.case.kind}", name=r.case.name,
                              file=r.case.file, time=f"{r.seconds:.3f}")
        if r.status != "pass":
            text = r.message()
            el = etree.SubElement(tc, "failure" if r.status == "fail" else "error", message=text.splitlines()[0],
                                  type=f"urdf2links.{r.case.kind}")
            el.text = text
        if r.lines:
            etree.SubElement(tc, "system-out").text = "\n".join(r.lines)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(etree.tostring(root, pretty_print=True, xml_declaration=True, encoding="utf-8"))
    return path


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def markdown(results: list[CaseResult], *, title: str = "urdf2links check", note: str = "") -> str:
    """The Markdown summary (module doc)."""
    out = [f"## {title}", "", f"**{verdict(results).removeprefix('urdf2links check: ')}**", ""]
    if note:
        out += [note, ""]
    bad = ordered(results)
    if bad:
        out += ["### Problems, largest first", ""]
        for r in bad:
            label = "could not run" if r.status == "error" else "failed"
            out.append(f"- **{r.case.kind} `{r.case.name}`** {label}:")
            for p in sorted(r.problems, key=lambda p: -p.ratio):
                ratio = "" if not math.isfinite(p.ratio) else f" ({p.ratio:.3g} x the tolerance)"
                out.append(f"  - {_cell(p.text)}{ratio}")
        out.append("")
    out += ["| check | file | result | seconds |", "|---|---|---|---|"]
    for r in results:
        mark = {"pass": "pass", "fail": "**FAIL**", "error": "**ERROR**"}[r.status]
        out.append(f"| {r.case.kind} | `{_cell(r.case.name)}` | {mark} | {r.seconds:.1f} |")
    return "\n".join(out) + "\n"


def write_markdown(results: list[CaseResult], path, **kw) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(markdown(results, **kw))
    return path
