"""Terms at identical states: the project's ``A`` and ``e + G`` against MuJoCo's own URDF import.

The "terms" level of the MuJoCo comparison (the others: trajectories, energies) on route 2: the
URDF file goes through MuJoCo's own URDF reader (:func:`urdf2links.compare.mujoco_side.mujoco_urdf.mujoco_from_urdf`)
and, at seeded random states, ``A`` is compared with ``mj_fullM`` and ``e + G`` with
``qfrc_bias``, coordinate by coordinate (the project's coordinates are the URDF joint names and
joint positions, as are MuJoCo's hinge/slide ``qpos``).

Which inertias are compared -- the two sides must describe the same bodies:

* MuJoCo accepts the original file (route ``"mujoco-urdf"``): the project's side has the file's
  inertias as written, i.e. a model loaded with ``inertia="audit"``. A model loaded with
  ``inertia="repair"`` may have changed links MuJoCo accepts (the project's audit is stricter in
  places, and also looks at links that end up folded); the file is then re-imported with
  ``inertia="audit"`` for the comparison, and ``notes`` says so.
* MuJoCo refuses the original (route ``"mujoco-urdf-repaired"``, ``refusal`` = MuJoCo's words):
  the documented fix is to hand MuJoCo the project's own repair, written back into the URDF text
  by :func:`repaired_urdf_text`, and to compare the project's repaired model with MuJoCo on that
  text. This needs a model loaded with ``inertia="repair"``.
* MuJoCo also refuses massless MOVING links, which the project accepts when something after them
  has mass (a ball joint written as three revolute joints through massless "virtual" links,
  ``human_description``). The project finds nothing to repair there, so there is no repaired
  text. Only when asked (``massless_moving=<kg>``) such links get a small sphere ON BOTH SIDES:
  MuJoCo loads the modified text, and the project's side is the project's import of that very
  text; ``notes`` records how much the spheres change the given model's ``A``.

MuJoCo's ``fusestatic`` is off by default here: every URDF link stays a MuJoCo body, so the
project's folding of fixed joints is checked against MuJoCo's kinematics of the welded bodies,
not against MuJoCo's own fusion. (MuJoCo's fusion drops the rotational inertia of a zero-mass
link: ``bolt_description`` has feet with ``mass 0`` but an inertia tensor; fused, ``A`` differs
by exactly that tensor -- 1.5e-4 relative -- while unfused MuJoCo agrees with the project to
1e-15.)

Only a fixed base is handled (a model loaded with ``floating_base=False``); mimic joints must be
independent coordinates (``mimic="independent"``; route 2 disables MuJoCo's mimic equalities).
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from lxml import etree

from urdf2links import load_urdf
from urdf2links.dynamics.inertia import inertial_from_pseudo, pseudo_inertia
from urdf2links.scenes.excitation import coordinate_ranges

from ..mujoco_side.mujoco_urdf import MujocoRefused, MujocoURDF, mujoco_data_at, mujoco_from_urdf, mujoco_terms

__all__ = ["TermsComparison", "repaired_urdf_text", "compare_terms_urdf", "massless_moving_links",
           "ROUTE_ORIGINAL", "ROUTE_REPAIRED"]

ROUTE_ORIGINAL = "mujoco-urdf"
ROUTE_REPAIRED = "mujoco-urdf-repaired"

#: Radius (m) of the small sphere given to massless moving links with ``massless_moving``.
SPHERE_RADIUS = 0.01


# --------------------------------------------------------------------------- repaired URDF text


def _num(x: float) -> str:
    """Shortest text that reads back as the same double (``repr``); zero written ``0``."""
    x = float(x)
    return "0" if x == 0.0 else repr(x)


def _inertial_xml(H, *, indent: str, step: str, nl: str) -> str:
    """URDF ``<inertial>`` text for the pseudo-inertia ``H`` (4, 4) in the link frame.

    origin xyz = COM, rpy = 0; the full URDF tensor about the COM in the link axes
    (``ixy = -integral(x y dm)``: the tensor of :func:`urdf2links.dynamics.inertia.inertial_from_pseudo`).
    ``indent``: indentation of the ``</inertial>`` line (the first line is not indented),
    ``step``: one more level, ``nl``: the file's line break.
    """
    m, c, I = inertial_from_pseudo(np.asarray(H, dtype=float))
    I = 0.5 * (I + I.T)
    inner = nl + indent + step
    xyz = " ".join(_num(v) for v in c)
    tensor = " ".join(f'{k}="{_num(v)}"' for k, v in (
        ("ixx", I[0, 0]), ("ixy", I[0, 1]), ("ixz", I[0, 2]),
        ("iyy", I[1, 1]), ("iyz", I[1, 2]), ("izz", I[2, 2])))
    return (f'<inertial>{inner}<origin xyz="{xyz}" rpy="0 0 0"/>{inner}<mass value="{_num(m)}"/>'
            f'{inner}<inertia {tensor}/>{nl}{indent}</inertial>')


# A tokenizer just good enough to find element spans in a URDF: comments, CDATA, processing
# instructions, DOCTYPE and tags (attribute values may contain '>').
_TOKEN = re.compile(
    r"<!--.*?-->|<!\[CDATA\[.*?\]\]>|<\?.*?\?>|<!DOCTYPE(?:[^>\[]|\[.*?\])*>"
    r"|<(?P<close>/)?(?P<tag>[^\s/>!?]+)(?P<attrs>(?:[^>\"']|\"[^\"]*\"|'[^']*')*?)(?P<empty>/)?>",
    re.DOTALL)
_NAME = re.compile(r"""\bname\s*=\s*(?:"([^"]*)"|'([^']*)')""")


@dataclass
class _Span:
    start: int          # of the start tag
    start_end: int      # end of the start tag
    end: int            # end of the end tag (== start_end for <x/>)
    empty: bool
    inertials: list = field(default_factory=list)   # (start, end) of <inertial> children


def _link_spans(text: str) -> dict[str, _Span]:
    """Spans of the root's ``<link>`` children, by name, and of their ``<inertial>`` children."""
    links: dict[str, _Span] = {}
    stack: list[tuple[str, int, int]] = []   # (tag, start, start_end)
    for m in _TOKEN.finditer(text):
        tag = m.group("tag")
        if tag is None:
            continue
        if m.group("close"):
            if not stack or stack[-1][0] != tag:
                raise ValueError(f"unbalanced </{tag}> at offset {m.start()}")
            _, s, se = stack.pop()
            _record(text, links, stack, tag, s, se, m.end(), False)
        elif m.group("empty"):
            _record(text, links, stack, tag, m.start(), m.end(), m.end(), True)
        else:
            stack.append((tag, m.start(), m.end()))
    if stack:
        raise ValueError(f"unclosed <{stack[-1][0]}>")
    return links


def _record(text, links, stack, tag, start, start_end, end, empty):
    depth = len(stack)  # of the element just closed: 0 = root, 1 = a root child
    if tag == "link" and depth == 1:
        nm = _NAME.search(text, start, start_end)
        if nm:
            name = nm.group(1) if nm.group(1) is not None else nm.group(2)
            span = links.setdefault(name, _Span(start, start_end, end, empty))
            span.start, span.start_end, span.end, span.empty = start, start_end, end, empty
    elif tag == "inertial" and depth == 2 and stack[-1][0] == "link":
        nm = _NAME.search(text, stack[-1][1], stack[-1][2])
        if nm:
            name = nm.group(1) if nm.group(1) is not None else nm.group(2)
            links.setdefault(name, _Span(-1, -1, -1, False)).inertials.append((start, end))


def _line_indent(text: str, pos: int) -> str | None:
    """The whitespace between the line start and ``pos``, or None if something else is there."""
    ls = text.rfind("\n", 0, pos) + 1
    lead = text[ls:pos]
    return lead if not lead.strip() else None


def _set_inertials(raw: bytes, H_by_link: dict, source: str) -> str:
    """``raw`` URDF bytes with the ``<inertial>`` of each link in ``H_by_link`` replaced (or
    created), as text: every other byte of the file is kept."""
    text = raw.decode("utf-8")
    try:
        out = _splice_inertials(text, H_by_link, source)
        _check_spliced(out, text, H_by_link)
        return out
    except (ValueError, etree.XMLSyntaxError, AssertionError):  # odd file: let lxml write it
        return _lxml_inertials(raw, H_by_link, source)


def _splice_inertials(text: str, H_by_link: dict, source: str) -> str:
    spans = _link_spans(text)
    missing = sorted(n for n in H_by_link if n not in spans or spans[n].start < 0)
    if missing:
        raise KeyError(f"{source}: link(s) {missing} are not <link> elements of the file")
    nl = "\r\n" if "\r\n" in text else "\n"
    edits: list[tuple[int, int, str]] = []
    for name, H in H_by_link.items():
        sp = spans[name]
        outer = _line_indent(text, sp.start)
        outer = "  " if outer is None else outer
        if sp.inertials:
            s0, e0 = sp.inertials[0]
            ind = _line_indent(text, s0)
            ind = outer + (outer or "  ") if ind is None else ind
            step = ind[len(outer):] if ind.startswith(outer) and len(ind) > len(outer) else "  "
            edits.append((s0, e0, _inertial_xml(H, indent=ind, step=step, nl=nl)))
            for s1, e1 in sp.inertials[1:]:  # a second <inertial> is read by nobody: drop it
                lead = _line_indent(text, s1)
                edits.append((s1 - len(lead) - len(nl) if lead is not None and
                              text[s1 - len(lead) - len(nl):s1 - len(lead)] == nl else s1, e1, ""))
        else:
            step = outer or "  "
            ind = outer + step
            el = _inertial_xml(H, indent=ind, step=step, nl=nl)
            if sp.empty:   # <link name="x"/> -> <link name="x">\n  <inertial>...</inertial>\n</link>
                tag = text[sp.start:sp.end]
                opened = re.sub(r"\s*/>$", ">", tag)
                edits.append((sp.start, sp.end, f"{opened}{nl}{ind}{el}{nl}{outer}</link>"))
            else:
                edits.append((sp.start_end, sp.start_end, f"{nl}{ind}{el}"))
    out = text
    for s, e, new in sorted(edits, reverse=True):
        out = out[:s] + new + out[e:]
    return out


def _check_spliced(out: str, text: str, H_by_link: dict) -> None:
    """The spliced text parses, and differs from ``text`` only in the repaired inertials."""
    def strip(t):
        root = etree.fromstring(t.encode("utf-8"), etree.XMLParser(resolve_entities=False))
        for link in root.iterchildren("link"):
            if link.get("name") in H_by_link:
                for el in link.findall("inertial"):
                    link.remove(el)
                link.text = None if link.text is None or not link.text.strip() else link.text
                for ch in link:
                    ch.tail = None if ch.tail is None or not ch.tail.strip() else ch.tail
        return etree.tostring(root)
    assert strip(out) == strip(text)
    root = etree.fromstring(out.encode("utf-8"), etree.XMLParser(resolve_entities=False))
    for link in root.iterchildren("link"):
        if link.get("name") in H_by_link:
            assert len(link.findall("inertial")) == 1


def _lxml_inertials(raw: bytes, H_by_link: dict, source: str) -> str:
    """Fallback: replace the inertials on lxml's tree and let lxml write the document."""
    parser = etree.XMLParser(remove_comments=False, remove_blank_text=False,
                             resolve_entities=False, strip_cdata=False)
    doc = etree.ElementTree(etree.fromstring(raw, parser))
    links = {el.get("name"): el for el in doc.getroot().iterchildren("link")}
    missing = sorted(set(H_by_link) - set(links))
    if missing:
        raise KeyError(f"{source}: link(s) {missing} are not <link> elements of the file")
    for name, H in H_by_link.items():
        link = links[name]
        new = etree.fromstring(_inertial_xml(H, indent="    ", step="  ", nl="\n"))
        olds = link.findall("inertial")
        for old in olds[1:]:
            link.remove(old)
        if olds:
            new.tail = olds[0].tail
            link.replace(olds[0], new)
        else:
            new.tail = link.text
            link.text = "\n    "
            link.insert(0, new)
    decl = re.match(rb"\s*<\?xml[^>]*\?>", raw)
    body = etree.tostring(doc, encoding="unicode")
    return (raw[:decl.end()].decode("utf-8") + "\n" + body) if decl else body


def repaired_urdf_text(urdf_path, model) -> str:
    """The original URDF text with the project's repaired inertias written in.

    Every URDF link of ``model.info["repaired_H"]`` (a model loaded with ``inertia="repair"``)
    gets its ``<inertial>`` replaced -- or created, as its first child, when it had none -- by
    the repaired one: ``origin xyz`` = COM, ``rpy="0 0 0"``, the mass, and the full tensor about
    the COM in the link axes in the URDF sign convention (``ixy = -integral(x y dm)``), each
    number written with ``repr`` (17 significant digits at most), so that the text reads back as
    the repaired ``H`` to rounding.

    Every other byte of the file is kept: the new elements are spliced into the text (indented
    like their neighbours, with the file's line breaks), and lxml checks that the result parses
    and differs from the original only in those inertials. A file the splice cannot handle is
    rewritten by lxml instead (comments and whitespace kept, quoting normalized). Without
    repaired links the file's text is returned unchanged. Raises ``KeyError`` if a repaired link
    is not in the file.
    """
    path = Path(urdf_path)
    raw = path.read_bytes()
    repaired = dict(model.info.get("repaired_H") or {})
    if not repaired:
        return raw.decode("utf-8")
    return _set_inertials(raw, repaired, str(path))


def massless_moving_links(text: str) -> list[str]:
    """Links that are the child of a non-fixed joint and have no mass in ``text`` (URDF):
    the moving bodies MuJoCo refuses ("mass and inertia of moving bodies must be larger than
    mjMINVAL") although the project accepts them when their subtree has mass."""
    root = etree.fromstring(text.encode("utf-8") if isinstance(text, str) else text,
                            etree.XMLParser(remove_comments=True, resolve_entities=False))
    links = {el.get("name"): el for el in root.iterchildren("link")}
    out = []
    for j in root.iterchildren("joint"):
        if (j.get("type") or "").strip() == "fixed":
            continue
        child = j.find("child")
        name = child.get("link") if child is not None else None
        if name not in links:
            continue
        mass_el = links[name].find("inertial/mass")
        try:
            mass = float(mass_el.get("value")) if mass_el is not None else 0.0
        except (TypeError, ValueError):
            continue
        if mass == 0.0:
            out.append(name)
    return out


# --------------------------------------------------------------------------- comparison


@dataclass(frozen=True)
class TermsComparison:
    """Result of :func:`compare_terms_urdf`.

    ``route``: ``"mujoco-urdf"`` (MuJoCo loaded the original file) or ``"mujoco-urdf-repaired"``
    (it refused it: ``refusal`` is MuJoCo's reason, and MuJoCo loaded the project's repaired
    text). ``max_rel_error_A`` / ``max_rel_error_bias``: the largest over the states of
    ``max|ours - MuJoCo| / max|MuJoCo|`` for ``A`` against ``mj_fullM`` and for ``e + G`` against
    ``qfrc_bias`` (when MuJoCo's ``e + G`` is zero -- a rotor spinning about its own vertical axis
    -- the denominator is ``max|M| * max(1, max|qd|^2)``, the size of ``A qdd`` at unit
    accelerations, and ``notes`` says so); ``max_rel_error``: the larger of the two. ``n``:
    number of coordinates, ``states``: number of states, ``coordinates``: their order.
    ``worst``: the states (``q``, ``qd``) where each maximum occurred. ``notes``: MuJoCo's side
    (what was edited, disabled, fused) and which project model was compared.
    ``passed``: ``max_rel_error <= tolerance`` when a tolerance was given, else ``None``.
    ``max_rel_error_damping``: with ``dampers`` given, the damper forces ``-c qd`` against MuJoCo's
    ``qfrc_damper`` from its own reading of ``<dynamics damping>`` (included in ``max_rel_error``);
    None otherwise.
    """

    route: str
    refusal: str | None
    max_rel_error_A: float
    max_rel_error_bias: float
    max_rel_error: float
    n: int
    states: int
    coordinates: tuple[str, ...] = ()
    worst: dict = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    tolerance: float | None = None
    max_rel_error_damping: float | None = None

    @property
    def passed(self) -> bool | None:
        return None if self.tolerance is None else bool(self.max_rel_error <= self.tolerance)

    def summary(self) -> str:
        s = (f"route {self.route}: n={self.n}, {self.states} states, max rel. error "
             f"A {self.max_rel_error_A:.2e}, e+G {self.max_rel_error_bias:.2e}")
        if self.refusal:
            s += f" (original refused by MuJoCo: {self.refusal.splitlines()[0]})"
        return s


def _rel(ours: np.ndarray, theirs: np.ndarray, floor: float = 0.0) -> tuple[float, bool]:
    """(max|ours - theirs| / max|theirs|, whether ``floor`` replaced a zero denominator)."""
    if theirs.size == 0:
        return 0.0, False
    diff = float(np.max(np.abs(ours - theirs)))
    scale = float(np.max(np.abs(theirs)))
    used_floor = scale <= 1e-12 * floor
    if used_floor:
        scale = floor
    if scale == 0.0:
        return (0.0 if diff == 0.0 else float("inf")), used_floor
    return diff / scale, used_floor


def _check_model(model, path) -> None:
    coords = model.info.get("coordinates", [])
    if any(c.get("joint") is None for c in coords):
        raise ValueError(f"{path}: compare_terms_urdf handles a fixed base only; load the model "
                         "with floating_base=False")
    odd = sorted({c.get("type") for c in coords} - {"revolute", "continuous", "prismatic"})
    if odd:
        raise ValueError(f"{path}: joints of type {odd} have no MuJoCo hinge/slide counterpart "
                         "in route 2")


def _import_quietly(source, gravity):
    """The project's import of ``source`` (path or text) with the inertias as written."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        m = load_urdf(source, floating_base=False, inertia="audit", mimic="independent")
    if not np.array_equal(m.gravity_vector, gravity):
        from urdf2links import Model
        m = Model(m.tree, gravity=gravity, name=m.name, source=m.source, audit=m.audit,
                  info=m.info)
    return m


def _sphere_H(mass: float, com) -> np.ndarray:
    return pseudo_inertia(mass, com, np.eye(3) * 0.4 * mass * SPHERE_RADIUS**2)


def compare_terms_urdf(urdf_path, model, *, states: int = 8, seed: int = 0,
                       tolerance: float | None = None, fusestatic: bool = False,
                       massless_moving: float | None = None, dampers: dict | None = None) -> TermsComparison:
    """Compare ``A`` and ``e + G`` of ``model`` with MuJoCo's own import of ``urdf_path``.

    ``model``: the project's import of the same file (``floating_base=False``,
    ``mimic="independent"``). MuJoCo's import of the original is tried first (route
    ``"mujoco-urdf"``; a repaired ``model`` is then replaced by the file re-imported with
    ``inertia="audit"``, as MuJoCo uses the inertias as written). When MuJoCo refuses it, the
    project's repair is written into the text (:func:`repaired_urdf_text`) and MuJoCo loads that
    (route ``"mujoco-urdf-repaired"``), which needs ``model`` loaded with ``inertia="repair"``;
    otherwise :class:`MujocoRefused` is raised again, saying why there is no fallback.

    ``massless_moving`` (kg, off by default): when MuJoCo still refuses because of massless
    moving links (:func:`massless_moving_links`), give each a sphere of this mass (radius
    :data:`SPHERE_RADIUS`, at the link origin) in the text MuJoCo loads AND compare with the
    project's import of that same text; ``notes`` gives the spheres' effect on ``model``'s ``A``.

    At ``states`` seeded random states (``q`` uniform within the joints' limits, a [-1, 1] window (rad or
    m) where a joint has none (:func:`urdf2links.scenes.excitation.coordinate_ranges`), ``qd`` standard
    normal) in ``model.coordinate_names`` order, the relative errors (see
    :class:`TermsComparison`) are computed and their maxima returned. Gravity is
    ``model.gravity_vector`` on both sides. ``fusestatic`` is MuJoCo's compiler option (off:
    see the module docstring). ``tolerance``, if given, sets ``result.passed``. ``dampers``
    (``{coordinate: c}``, the project's reading of ``<dynamics damping>``): MuJoCo keeps the damping
    it read from the file and the damper forces are compared too (``max_rel_error_damping``).
    """
    path = Path(urdf_path)
    _check_model(model, path)
    gravity = np.asarray(model.gravity_vector, dtype=float)
    g = tuple(float(x) for x in gravity)
    load = dict(gravity=g, fusestatic=fusestatic, damping=dampers is not None)
    notes: list[str] = []
    refusal = None
    ours = model
    try:
        mj = mujoco_from_urdf(path, **load)
        route = ROUTE_ORIGINAL
        repaired = sorted({r.link for r in model.audit if getattr(r, "action", "") == "repaired"})
        if repaired:
            ours = _import_quietly(path, gravity)
            notes.append(
                "MuJoCo accepts the original file: compared with the project's import of the "
                f"inertias as written (inertia='audit'), not with the given repaired model "
                f"(repaired links {repaired} are not what MuJoCo loads)")
    except MujocoRefused as err:
        refusal = err.reason
        route = ROUTE_REPAIRED
        mj, ours, extra = _repaired_route(path, model, err, load, gravity, massless_moving)
        notes += extra
    notes = list(mj.notes) + notes

    names = tuple(ours.coordinate_names)
    if set(names) != set(mj.joint_names) or len(names) != len(mj.joint_names):
        raise ValueError(
            f"{path}: coordinates differ: the project's {sorted(set(names) - set(mj.joint_names))} "
            f"are not in MuJoCo's import, MuJoCo's {sorted(set(mj.joint_names) - set(names))} not "
            "in the project's (load mimic joints with mimic='independent')")

    err_A, err_b, worst, floors = _seeded_errors(mj, ours, names, states, seed)
    if floors:
        notes.append(f"MuJoCo's e + G is zero at {floors} of {states} state(s): relative to "
                     "max|M| * max(1, max|qd|^2) there")
    err_d = None if dampers is None else _damping_error(mj, names, dampers, states, seed)
    return TermsComparison(route=route, refusal=refusal, max_rel_error_A=err_A,
                           max_rel_error_bias=err_b, max_rel_error=max(err_A, err_b, err_d or 0.0), n=len(names),
                           states=states, coordinates=names, worst=worst, notes=notes,
                           tolerance=tolerance, max_rel_error_damping=err_d)


def _damping_error(mj, names, dampers: dict, states: int, seed: int) -> float:
    """Largest ``max|-c qd - qfrc_damper| / max|qfrc_damper|`` over seeded velocities (0 when neither
    side damps anything; inf when only one does)."""
    c = np.array([float(dampers.get(nm, 0.0)) for nm in names])
    dofs = [mj.dof_of_joint[nm] for nm in names]
    rng = np.random.default_rng(seed + 1)
    worst = 0.0
    for _ in range(states):
        q, qd = rng.uniform(-1.0, 1.0, len(names)), rng.standard_normal(len(names))
        d = mujoco_data_at(mj, dict(zip(names, q)), dict(zip(names, qd)))
        worst = max(worst, _rel(-c * qd, np.asarray(d.qfrc_damper)[dofs])[0])
    return worst


def _seeded_errors(mj, ours, names, states, seed):
    """Largest relative errors of ``A`` and ``e + G`` at seeded random states, the worst states, and
    how many states fell back to the floor (MuJoCo's ``e + G`` zero)."""
    rng = np.random.default_rng(seed)
    n = len(names)
    err_A = err_b = 0.0
    worst: dict = {}
    floors = 0
    span = coordinate_ranges(ours)      # the states span the joints' limits (a +-1 window where none)
    for k in range(states):
        q = rng.uniform(span.lower, span.upper)
        qd = rng.standard_normal(n)
        t = mujoco_terms(mj, dict(zip(names, q)), dict(zip(names, qd)), order=names)
        A = ours.mass_matrix(q)
        eG = ours.bias(q, qd) + ours.gravity(q)
        ra, _ = _rel(A, t.M)
        floor = float(np.max(np.abs(t.M))) * max(1.0, float(np.max(np.abs(qd)))**2) if n else 0.0
        rb, used = _rel(eG, t.bias, floor)
        floors += used
        if ra > err_A or "A" not in worst:
            err_A = max(err_A, ra)
            worst["A"] = dict(state=k, q=q.tolist(), qd=qd.tolist(), rel=ra)
        if rb > err_b or "bias" not in worst:
            err_b = max(err_b, rb)
            worst["bias"] = dict(state=k, q=q.tolist(), qd=qd.tolist(), rel=rb)
    return err_A, err_b, worst, floors


def _repaired_route(path: Path, model, err: MujocoRefused, load: dict, gravity,
                    massless_moving) -> tuple[MujocoURDF, object, list[str]]:
    """MuJoCo refused the original: load the project's repaired text (and, if asked, spheres on
    massless moving links); return MuJoCo's import, the project model to compare, notes."""
    reported = sorted({r.link for r in model.audit if getattr(r, "action", "") != "repaired"})
    if reported:
        raise MujocoRefused(str(path), (
            f"{err.reason}\n-> no repaired text to fall back to: the model has unrepaired inertia "
            f"findings on links {reported}; load it with inertia='repair'")) from err
    repaired = sorted(model.info.get("repaired_H") or {})
    text = repaired_urdf_text(path, model)
    notes = []
    ours = model
    if repaired:
        notes.append(f"MuJoCo refused the original; compared the project's repaired model with "
                     f"MuJoCo on the repaired text (links {repaired})")
    massless = massless_moving_links(text)
    if massless and massless_moving is not None:
        raw = text.encode("utf-8")
        spheres = {name: _sphere_H(float(massless_moving), np.zeros(3)) for name in massless}
        text = _set_inertials(raw, spheres, str(path))
        ours = _import_quietly(text, gravity)
        rng = np.random.default_rng(1)
        q = rng.uniform(-1, 1, model.n)
        A0 = model.mass_matrix(q)
        dA = float(np.max(np.abs(ours.mass_matrix(q) - A0)) / np.max(np.abs(A0))) if model.n else 0.0
        notes.append(
            f"MuJoCo refuses massless moving links {massless}, which the project accepts: "
            f"each given a {massless_moving:g} kg sphere of radius {SPHERE_RADIUS} m at its "
            f"origin on BOTH sides (MuJoCo's text and the project's import of it); the spheres "
            f"change the given model's A by {dA:.1e} (relative)")
    try:
        mj = mujoco_from_urdf(path, repair_urdf_text=text, **load)
    except MujocoRefused as err2:
        if not repaired and not (massless and massless_moving is not None):
            hint = ("the project finds nothing to repair" +
                    (f"; MuJoCo refuses the massless moving links {massless}, which the project "
                     "accepts (their subtree has mass): pass massless_moving=<kg> to compare "
                     "with a small sphere on them on both sides" if massless else ""))
            raise MujocoRefused(str(path), f"{err.reason}\n-> no repaired text to fall back "
                                f"to: {hint}") from err
        raise MujocoRefused(str(path), (
            f"{err.reason}\n-> and MuJoCo also refuses the project's repaired text (links "
            f"{repaired} repaired): {err2.reason}")) from err2
    return mj, ours, notes
