"""The XML of a robot description: from a path, URDF text or a xacro file to the ``<robot>`` element.

:func:`read_source` is the first step of :func:`urdf2links.parsers.urdf.parse_urdf`. It reads the bytes
(strict XML parser, no entities, no network), tolerates what urdfdom's XML reader (tinyxml2)
tolerates and lxml does not -- an XML declaration of an unusual version such as
``<?xml version="0.0" ?>``, read as 1.0; blank lines before the declaration; a NUL byte, where
tinyxml2's C string ends -- each with a note, expands ``.xacro`` files
(:mod:`urdf2links.parsers.xacro_input`), and refuses leftover ``xacro:`` elements in a URDF by name
(urdfdom would skip them silently, and with them every link a macro was meant to make).

Public API: :func:`read_source`, :class:`Source`.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

from ..errors import URDFError, URDFSyntaxError
from .xacro_input import expand_xacro, is_xacro_path

__all__ = ["read_source", "Source", "XACRO_NAMESPACE"]

XACRO_NAMESPACE = "http://www.ros.org/wiki/xacro"
#: ``<?xml version="..."`` at the start of a document (after an optional BOM and blanks).
_DECLARATION = re.compile(rb'^(\xef\xbb\xbf)?(\s*<\?xml\s+version\s*=\s*)(["\'])([^"\']*)\3')
#: an entity declaration in a DOCTYPE's internal subset (UTF-8 or ASCII-compatible text)
_ENTITY = re.compile(rb"<!DOCTYPE[^\[>]*\[[^\]]*?<!ENTITY", re.DOTALL)


@dataclass
class Source:
    """``root``: the ``<robot>`` element; ``label``: the file (or ``<string>``) for messages;
    ``directory``: where relative paths start (None for text); ``stem``: fallback robot name;
    ``notes``: what was tolerated on the way."""

    root: etree._Element
    label: str
    directory: Path | None
    stem: str
    notes: list[str] = field(default_factory=list)


def _bytes_of(source, *, xacro_args, package_dirs) -> tuple[bytes, str, Path | None, str, list[str]]:
    """(data, label, directory, stem, notes) of a path, URDF text or xacro file (text and expanded
    xacro are UTF-8 whatever their declaration says; a file is read as its declaration says)."""
    notes: list[str] = []
    if isinstance(source, bytes):
        source = source.decode("utf-8")
    if isinstance(source, str) and source.lstrip().startswith("<"):
        return source.encode("utf-8"), "<string>", None, "robot", notes
    if not isinstance(source, (str, os.PathLike)):
        raise TypeError(f"parse_urdf: source must be a path or URDF text, not {type(source).__name__}")
    path = Path(source)
    label = str(path)
    try:
        is_file, is_dir = path.is_file(), path.is_dir()
    except OSError as err:  # e.g. a name too long to be a path
        raise URDFError(f"{label[:80]}: not a readable path ({err.strerror}); pass the path "
                        "of a .urdf file or the URDF text itself (starting with '<')") from err
    if not is_file:
        why = "is a directory" if is_dir else "does not exist"
        raise URDFError(f"{label}: the URDF file {why}; pass the path of a .urdf (or .xacro) file "
                        "or the URDF text itself (starting with '<')")
    stem = path.name.split(".")[0] or path.stem
    if is_xacro_path(path):
        text = expand_xacro(path, xacro_args=xacro_args, package_dirs=package_dirs)
        shown = ", ".join(f"{k}:={v}" for k, v in (xacro_args or {}).items()) or "no arguments"
        notes.append(f"{path.name}: expanded by xacro ({shown})")
        return text.encode("utf-8"), label, path.resolve().parent, stem, notes
    if xacro_args:
        raise URDFError(f"{label}: xacro_args were given ({xacro_args}) but the file is not a .xacro file")
    try:
        data = path.read_bytes()
    except OSError as err:
        raise URDFError(f"{label}: cannot read the URDF file ({err})") from err
    return data, label, path.resolve().parent, stem, notes


def _declaration(data: bytes, label: str, strict: bool, notes: list[str]) -> bytes:
    """Read an XML declaration of a version other than 1.0/1.1 as 1.0 (with a note), unless strict."""
    m = _DECLARATION.match(data)
    if m is None or m.group(4) in (b"1.0", b"1.1"):
        return data
    version = m.group(4).decode("utf-8", "replace")
    if strict:
        raise URDFSyntaxError(f"{label}, line 1: the XML declaration says version=\"{version}\"; XML has "
                              "versions 1.0 and 1.1: write <?xml version=\"1.0\"?> (or load with strict=False)")
    notes.append(f"XML declaration: version=\"{version}\" read as 1.0 (urdfdom's XML reader, tinyxml2, does not "
                 "check the version)")
    return data[:m.start(4)] + b"1.0" + data[m.end(4):]


#: blanks before an XML declaration (which XML allows nowhere but at the very start)
_LATE_DECLARATION = re.compile(rb"^(\xef\xbb\xbf)?([ \t\r\n]+)(<\?xml\s)")


def _before_declaration(data: bytes, label: str, strict: bool, notes: list[str]) -> bytes:
    """Blank lines before the XML declaration: XML refuses them, urdfdom's reader (tinyxml2) skips them.
    Read like urdfdom (the blanks moved after the declaration, so that every line keeps its number),
    with a note; refused when strict."""
    m = _LATE_DECLARATION.match(data)
    if m is None:
        return data
    blanks = m.group(2)
    lines = blanks.count(b"\n")
    if strict:
        raise URDFSyntaxError(f"{label}, line {lines + 1}: the XML declaration (<?xml ...?>) does not stand at the start "
                              f"of the file: {lines} blank line(s) come before it, and XML allows nothing there; "
                              "delete them (or load with strict=False, which reads the file as urdfdom does)")
    notes.append(f"XML declaration on line {lines + 1} after {lines} blank line(s): read as if at the start (XML allows "
                 "nothing before it; urdfdom's reader, tinyxml2, skips the blanks)")
    end = data.index(b"?>", m.end(2)) + 2
    return (m.group(1) or b"") + data[m.end(2):end] + blanks + data[end:]


def _nul(data: bytes, label: str, strict: bool, notes: list[str]) -> bytes:
    """A NUL byte: urdfdom hands the text to tinyxml2 as a C string, which ends at the first NUL, so
    whatever follows is never read. Read like urdfdom (the text up to the NUL) with a note saying where
    it stands and what was dropped; refused when strict."""
    k = data.find(b"\x00")
    if k < 0:
        return data
    line = data[:k].count(b"\n") + 1
    col = k - (data.rfind(b"\n", 0, k) + 1) + 1
    rest = data[k:]
    where = f"byte 0x00 (NUL) at line {line}, column {col}"
    after = "nothing (the last byte of the file)" if len(rest) == 1 else f"{len(rest) - 1} more byte(s)"
    if strict:
        raise URDFSyntaxError(f"{label}: {where}, followed by {after}: a NUL is no XML character; delete it (or load "
                              "with strict=False, which reads the file up to the NUL, as urdfdom does)")
    notes.append(f"{where}: the file is read up to it, as urdfdom does (its XML reader stops at the first NUL); "
                 f"dropped: the NUL" + ("" if len(rest) == 1 else f" and the {after} after it"))
    return data[:k]


def _describe_position(data: bytes, line: int | None, col: int | None) -> str:
    """What stands at (``line``, ``col``) of ``data`` when it is not plain text: `` (byte 0x1b there)``;
    empty otherwise (a message then quotes lxml alone)."""
    if not line:
        return ""
    rows = data.split(b"\n")
    if line > len(rows):
        return ""
    row = rows[line - 1]
    bad = [(i, b) for i, b in enumerate(row) if b < 0x20 and b not in (0x09, 0x0d)]
    if not bad:
        return ""
    i, b = next(((i, b) for i, b in bad if col is None or i >= col - 2), bad[0])
    return f" (byte 0x{b:02x}, a control character, at line {line}, column {i + 1})"


def _entities(data: bytes, label: str) -> None:
    """Entity declarations (``<!DOCTYPE robot [<!ENTITY ...>]>``) are refused before parsing: a URDF has
    no use for them, urdfdom's XML reader (tinyxml2) does not expand them, and they are how entity bombs
    and external entities get in. (The parser would refuse a bomb and never fetch an external entity;
    this says so before anything is expanded.)"""
    m = _ENTITY.search(data)
    if m is not None:
        line = data[:m.start()].count(b"\n") + 1
        raise URDFSyntaxError(f"{label}, line {line}: the document declares XML entities (<!ENTITY ...>); a URDF "
                              "does not use them and they are not read (entity expansion and external entities "
                              "are refused): write the values out")


def _leftover_xacro(root, label: str) -> None:
    """A URDF (not a .xacro) that still holds ``xacro:`` elements is an error naming them."""
    found = []
    for el in root.iter():
        if not isinstance(el.tag, str):
            continue
        qn = etree.QName(el)
        prefix = el.prefix or ""
        if qn.namespace == XACRO_NAMESPACE or prefix == "xacro" or qn.localname.startswith("xacro:"):
            found.append(f"<xacro:{qn.localname}> (line {el.sourceline})")
    if found:
        listed = ", ".join(found[:8]) + (f" and {len(found) - 8} more" if len(found) > 8 else "")
        raise URDFSyntaxError(f"{label}: the file holds xacro elements that were never expanded: {listed}; "
                              "expand it first (save it as .xacro and load that, with the xacro extra: "
                              "pip install \"urdf2links[xacro]\"), or run `xacro FILE > robot.urdf`")


def read_source(source, *, strict: bool = False, xacro_args=None, package_dirs=()) -> Source:
    """The ``<robot>`` element of ``source`` (a path, URDF text, or a ``.xacro`` path)."""
    data, label, directory, stem, notes = _bytes_of(source, xacro_args=xacro_args, package_dirs=package_dirs)
    data = _nul(data, label, strict, notes)
    data = _before_declaration(data, label, strict, notes)
    data = _declaration(data, label, strict, notes)
    _entities(data, label)
    utf8 = label == "<string>" or is_xacro_path(source)
    parser = etree.XMLParser(remove_comments=True, resolve_entities=False, no_network=True,
                             **({"encoding": "utf-8"} if utf8 else {}))
    try:
        root = etree.fromstring(data, parser=parser)
    except etree.XMLSyntaxError as err:
        line = f", line {err.lineno}" if getattr(err, "lineno", None) else ""
        what = _describe_position(data, getattr(err, "lineno", None), getattr(err, "offset", None))
        raise URDFSyntaxError(f"{label}{line}: malformed XML: {err.msg}{what}; fix the XML "
                              "(unclosed or mismatched tag, stray '&' or '<', truncated file?)") from err
    except ValueError as err:  # e.g. lxml refusing some encodings
        raise URDFSyntaxError(f"{label}: cannot parse the XML: {err}") from err
    if root is None:
        raise URDFSyntaxError(f"{label}: the document is empty; a URDF needs a <robot> element")
    tag = etree.QName(root).localname if isinstance(root.tag, str) else str(root.tag)
    if tag != "robot":
        raise URDFSyntaxError(f"{label}, line {root.sourceline}: the root element is <{tag}>, "
                              "not <robot>; a URDF file must have <robot name=\"...\"> as its "
                              "root (is this a xacro, SDF or MJCF file?)")
    _leftover_xacro(root, label)
    return Source(root, label, directory, stem, notes)
