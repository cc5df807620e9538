"""Pseudo-inertia matrices H: from URDF inertials, re-expressed, audited, repaired.

``H`` (docs/equations.md (E10)) is the ``(4, 4)`` matrix ``integral(r r^T dm)`` with
``r = (x, y, z, 1)`` in a link's frame::

    H = [[S,      m c],        S = integral(p p^T dm)  (3, 3), second moments about the origin
         [m c^T,  m  ]]        m the mass, c the centre of mass (3,)

From a URDF ``<inertial>`` (tensor ``I`` about the COM, COM frame rotation ``Rc``):
``I' = Rc I Rc^T``, ``S = 0.5 tr(I') 1 - I' + m c c^T``. URDF ``ixy = -integral(x y dm)``
while ``H`` holds ``+integral(x y dm)``.

Properties used throughout:

* Re-expressing a body in another frame: if ``T`` (4, 4) maps coordinates of frame B to
  frame A (``r_A = T r_B``), then ``H_A = T H_B T^T`` (:func:`transform_pseudo_inertia`).
* ``H`` of a rigid union of bodies, all expressed in one frame, is the sum of their ``H``.
* ``H`` is positive definite exactly when the inertia is physically consistent: ``m > 0``
  and the COM second moments ``Sc = S - m c c^T`` positive definite. The eigenvalues of
  ``Sc`` are ``sigma_k = integral(x_k^2 dm)`` along the principal axes, and the principal
  moments are ``lambda_i = sigma_j + sigma_k``; ``sigma_k > 0`` is exactly the (strict)
  triangle inequality ``lambda_i + lambda_j > lambda_k``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InertiaError, URDFValueError

__all__ = [
    "pseudo_inertia", "inertial_from_pseudo", "transform_pseudo_inertia", "principal_moments",
    "axis_inertia", "Finding", "FINDING_KINDS", "audit_pseudo_inertia", "nearest_consistent",
]

FINDING_KINDS = ("nan", "non_positive_mass", "negative_principal_moment", "triangle_inequality",
                 "not_positive_definite")


# --------------------------------------------------------------------------- H algebra


def pseudo_inertia(mass: float, com, inertia_com, *, rotation=None) -> np.ndarray:
    """Pseudo-inertia ``H`` (4, 4) of a URDF inertial, about the link frame's origin.

    Parameters
    ----------
    mass : float
        ``m``.
    com : array_like, shape (3,)
        ``c``, the inertial origin's ``xyz`` (COM in link coordinates).
    inertia_com : array_like, shape (3, 3)
        URDF tensor ``I`` about the COM, in the inertial origin's axes.
    rotation : array_like, shape (3, 3), optional
        ``Rc``, the inertial origin's rotation (``rpy_to_matrix(origin.rpy)``); identity if None.

    Returns
    -------
    H : ndarray, shape (4, 4)
        ``[[S, m c], [m c^T, m]]`` with ``S = 0.5 tr(I') 1 - I' + m c c^T``, ``I' = Rc I Rc^T``.
        No validity check is made: see :func:`audit_pseudo_inertia`.
    """
    m = float(mass)
    c = np.asarray(com, dtype=float).reshape(3)
    I = np.asarray(inertia_com, dtype=float).reshape(3, 3)
    if rotation is not None:
        Rc = np.asarray(rotation, dtype=float).reshape(3, 3)
        I = Rc @ I @ Rc.T
    I = 0.5 * (I + I.T)
    return _assemble(m, c, 0.5 * np.trace(I) * np.eye(3) - I)


def _assemble(m: float, c: np.ndarray, Sc: np.ndarray) -> np.ndarray:
    """``H`` from mass, COM and COM second moments ``Sc`` (3, 3)."""
    H = np.empty((4, 4))
    H[:3, :3] = 0.5 * (Sc + Sc.T) + m * np.outer(c, c)
    H[:3, 3] = H[3, :3] = m * c
    H[3, 3] = m
    return H


def _split(H) -> tuple[float, np.ndarray, np.ndarray]:
    """``(m, c, Sc)`` of ``H``: mass, COM (zeros when m == 0), COM second moments (3, 3)."""
    H = np.asarray(H, dtype=float)
    if H.shape != (4, 4):
        raise URDFValueError(f"pseudo-inertia must be 4x4, got shape {H.shape}")
    H = 0.5 * (H + H.T)
    m = float(H[3, 3])
    if m == 0.0:
        return 0.0, np.zeros(3), H[:3, :3].copy()
    c = H[:3, 3] / m
    return m, c, H[:3, :3] - m * np.outer(c, c)


def inertial_from_pseudo(H) -> tuple[float, np.ndarray, np.ndarray]:
    """Inverse of :func:`pseudo_inertia` (with ``rotation=None``): ``H`` (4, 4) to an inertial.

    Returns ``mass`` (float), ``com`` (3,) and ``inertia_com`` (3, 3), the URDF-convention
    tensor about the COM in the frame's axes, ``tr(Sc) 1 - Sc``. All zero when ``mass == 0``.
    """
    m, c, Sc = _split(H)
    if m == 0.0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    return m, c, np.trace(Sc) * np.eye(3) - Sc


def transform_pseudo_inertia(H, T) -> np.ndarray:
    """``T H T^T``: ``H`` (4, 4) given in frame B re-expressed in frame A, ``T`` (4, 4) = ``A_T_B``.

    Sums of such results (all in frame A) give the ``H`` of the rigid union.
    """
    H = np.asarray(H, dtype=float)
    T = np.asarray(T, dtype=float)
    if H.shape != (4, 4) or T.shape != (4, 4):
        raise URDFValueError(f"need H (4, 4) and T (4, 4), got {H.shape} and {T.shape}")
    out = T @ H @ T.T
    return 0.5 * (out + out.T)


def principal_moments(inertia_com) -> np.ndarray:
    """Principal moments (3,), ascending: eigenvalues of the symmetric part of ``inertia_com`` (3, 3)."""
    I = np.asarray(inertia_com, dtype=float).reshape(3, 3)
    return np.linalg.eigvalsh(0.5 * (I + I.T))


def axis_inertia(H, axis) -> float:
    """Moment of inertia of ``H`` (4, 4) about the line through the frame origin along ``axis`` (3,).

    ``integral(|p|^2 - (u.p)^2 dm) = tr(S) - u^T S u`` with ``u = axis/|axis|`` (normalized here).
    """
    u = np.asarray(axis, dtype=float).reshape(3)
    n = float(np.linalg.norm(u))
    if not np.isfinite(n) or n < 1e-12:
        raise URDFValueError(f"axis {u.tolist()} must be a finite non-zero direction")
    u = u / n
    S = np.asarray(H, dtype=float)[:3, :3]
    S = 0.5 * (S + S.T)
    return float(np.trace(S) - u @ S @ u)


# --------------------------------------------------------------------------- audit


@dataclass(frozen=True)
class Finding:
    """One audit result: ``kind`` (one of :data:`FINDING_KINDS`), a readable ``message``, raw ``values``."""

    link: str
    kind: str
    message: str
    values: dict = field(default_factory=dict)


def audit_pseudo_inertia(H, *, link: str, rtol: float = 1e-9) -> list[Finding]:
    """Check that ``H`` (4, 4) describes a physically consistent rigid body.

    Parameters
    ----------
    H : array_like, shape (4, 4)
    link : str
        Named in every finding.
    rtol : float
        Relative tolerance. Moments are compared with ``tol = rtol * sum(|lambda|)``
        (the size of the inertia itself, so the test is independent of units and of
        the body's size and mass). URDF files print 6-10 significant digits, and the
        rotation, parallel-axis shift and eigen-solver add errors of ~1e-16 * |I|; 1e-9
        is far above the arithmetic while genuine errors in real files are percent-level.

    Returns
    -------
    list of Finding
        Empty when consistent. Kinds: ``"nan"`` (non-finite entries; nothing else is
        checked), ``"non_positive_mass"``, ``"negative_principal_moment"`` (some
        ``lambda < -tol``), ``"triangle_inequality"`` (``lambda_i + lambda_j < lambda_k - tol``),
        ``"not_positive_definite"`` (``m <= 0`` or a COM second moment
        ``sigma_k <= tol/2``; reports the eigenvalues of ``H``). A body with zero thickness
        (``lambda_i + lambda_j == lambda_k``) meets the triangle inequality but is reported
        as not positive definite.
    """
    Ha = np.asarray(H, dtype=float)
    if Ha.shape != (4, 4):
        raise URDFValueError(f"link {link!r}: pseudo-inertia must be 4x4, got shape {Ha.shape}")
    findings: list[Finding] = []

    def add(kind: str, what: str, **values) -> None:
        findings.append(Finding(link, kind, f"link {link!r}: {what}", values))

    if not np.all(np.isfinite(Ha)):
        bad = [(int(i), int(j)) for i, j in np.argwhere(~np.isfinite(Ha))]
        add("nan", f"inertia has non-finite entries at {bad}", H=Ha.tolist(), entries=bad)
        return findings
    eig_H = np.linalg.eigvalsh(0.5 * (Ha + Ha.T)).tolist()
    m, c, Sc = _split(Ha)
    if m <= 0.0:
        add("non_positive_mass", f"mass {m:.6g} is not positive", mass=m)
        add("not_positive_definite", f"H is not positive definite (mass {m:.6g}); "
            f"eigenvalues of H {eig_H}", eigenvalues=eig_H, mass=m)
        return findings
    lam = principal_moments(np.trace(Sc) * np.eye(3) - Sc)
    tol = rtol * float(np.sum(np.abs(lam)))
    if lam[0] < -tol:
        add("negative_principal_moment", f"principal moments {lam.tolist()} include a negative "
            f"value (tolerance {tol:.3g})", principal_moments=lam.tolist(), tolerance=tol)
    excess = float(lam[2] - lam[0] - lam[1])  # ascending: only lam0 + lam1 >= lam2 can fail
    if excess > tol:
        add("triangle_inequality", f"principal moments {lam.tolist()} violate the triangle "
            f"inequality: {lam[0]:.6g} + {lam[1]:.6g} < {lam[2]:.6g} (by {excess:.3g})",
            principal_moments=lam.tolist(), excess=excess, tolerance=tol)
    sigma = np.linalg.eigvalsh(Sc)
    if sigma[0] <= 0.5 * tol:  # sigma_k = (lam_i + lam_j - lam_k) / 2
        add("not_positive_definite", f"H is not (numerically) positive definite: COM second "
            f"moments {sigma.tolist()} (need > {0.5 * tol:.3g}); eigenvalues of H {eig_H}",
            eigenvalues=eig_H, second_moments=sigma.tolist(), principal_moments=lam.tolist(),
            tolerance=0.5 * tol)
    return findings


def nearest_consistent(H, *, min_eig_ratio: float = 1e-6, link: str = "", rtol: float = 1e-9) -> np.ndarray:
    """The nearest physically consistent ``H`` with the same mass and COM.

    If :func:`audit_pseudo_inertia` (with ``rtol``) finds nothing, a copy of ``H`` is
    returned unchanged. Otherwise mass ``m`` and COM ``c`` are kept, and the COM second
    moments ``Sc = V diag(sigma) V^T`` get ``sigma_k <- max(sigma_k, min_eig_ratio * max(sigma))``
    (principal axes ``V`` kept). Among all ``H'`` with the same ``m`` and ``c`` whose ``Sc``
    has every eigenvalue at least that floor, this is the closest in the Frobenius norm
    (eigenvalue clipping is the projection onto that set). In terms of principal moments
    it raises the too-small ones so the triangle inequalities hold with the margin
    ``2 * floor``, changing as little as needed.

    Parameters
    ----------
    H : array_like, shape (4, 4)
    min_eig_ratio : float
        Smallest allowed ``sigma_k / max(sigma)`` after repair (``1e-6``: a plate 1000 times
        wider than thick).
    link : str
        Named in errors.

    Returns
    -------
    ndarray, shape (4, 4)

    Raises
    ------
    InertiaError
        Non-finite ``H``, ``m <= 0`` (no mass to keep), or no positive second moment at all
        (e.g. an all-zero tensor: no size to keep). Use :func:`geometry_inertia` instead.
    """
    Ha = np.array(H, dtype=float)
    findings = audit_pseudo_inertia(Ha, link=link, rtol=rtol)
    if not findings:
        return Ha
    kinds = {f.kind for f in findings}
    if "nan" in kinds or "non_positive_mass" in kinds:
        raise InertiaError(f"link {link!r}: inertia cannot be repaired keeping mass and COM: "
                           + "; ".join(f.message for f in findings)
                           + " (estimate it from the geometry instead)")
    m, c, Sc = _split(Ha)
    sigma, V = np.linalg.eigh(Sc)
    if sigma[-1] <= 0.0:
        raise InertiaError(f"link {link!r}: inertia tensor has no positive second moment (COM "
                           f"second moments {sigma.tolist()}); its size is unknown, estimate "
                           "it from the geometry instead")
    sigma = np.maximum(sigma, min_eig_ratio * sigma[-1])
    return _assemble(m, c, (V * sigma) @ V.T)
