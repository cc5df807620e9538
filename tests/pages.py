"""Checks of generated HTML pages shared by the tests: offline, and the animation's poses decoded."""

from __future__ import annotations

import re

import numpy as np
from scipy.spatial.transform import Rotation


def poses_4x4(p7: np.ndarray) -> np.ndarray:
    """(..., 7) position + quaternion (x, y, z, w) -> (..., 4, 4)."""
    flat = p7.reshape(-1, 7).astype(float)
    out = np.tile(np.eye(4), (len(flat), 1, 1))
    out[:, :3, :3] = Rotation.from_quat(flat[:, 3:]).as_matrix()
    out[:, :3, 3] = flat[:, :3]
    return out.reshape(*p7.shape[:-1], 4, 4)


def assert_offline(page: str) -> None:
    """Nothing is fetched: every <script> is inline, no <link href>, and the only http(s) text is
    the XHTML namespace inside three.js (a name, never loaded)."""
    assert re.search(r"<script[^>]*\bsrc\s*=", page, re.I) is None
    assert re.search(r"<link[^>]*\bhref\s*=", page, re.I) is None
    urls = set(re.findall(r"https?://[^\s\"'<>)]+", page))
    assert urls <= {"http://www.w3.org/1999/xhtml"}, urls
