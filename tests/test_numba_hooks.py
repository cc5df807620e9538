"""numba's private hooks, pinned (issue 44): the installed numba is the release pyproject.toml pins, and
each private hook urdf2links relies on still does what it does there. A numba release that changes one
fails here, loudly, before it changes compile times or reference counting unseen (docs/speed.md,
"numba's private hooks"):

- ``Dispatcher.get_call_template``, replaced per kernel by :func:`urdf2links.compilation.one_signature`;
- the ``_nrt`` option of ``njit`` and ``cfunc`` (:func:`urdf2links.compilation.kernel`, ``c_function``);
- ``CacheImpl._locator_classes``, where :mod:`urdf2links.numba_cache` puts its cache locator.

Each check has its control: the same function without the hook, where numba must behave otherwise."""

from __future__ import annotations

import inspect
import json
import os
import subprocess
import sys
import textwrap
import tomllib
from importlib.metadata import requires, version
from pathlib import Path

import numba
import numpy as np
import pytest
from numba import njit
from numba.core import dispatcher as numba_dispatcher
from numba.core import types
from packaging.requirements import Requirement
from packaging.version import Version

from urdf2links import compilation
from urdf2links.dynamics import factor, kernels

ROOT = Path(__file__).resolve().parent.parent


def _pins() -> dict:
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    return {r.name: r.specifier for r in map(Requirement, deps) if r.name in ("numba", "llvmlite")}


def test_numba_is_the_pinned_release():
    """numba and llvmlite are pinned to a closed range (one numba minor release: the hooks below are
    tested on it), the installed ones are inside it, and the llvmlite pin is numba's own."""
    pins = _pins()
    assert set(pins) == {"numba", "llvmlite"}, pins
    for name, spec in pins.items():
        assert Version(version(name)) in spec, f"installed {name} {version(name)} is outside pyproject.toml's {spec}"
    # planted: releases on either side of the pin are refused (an open pin such as ">=0.59" fails here)
    assert Version("0.59.0") not in pins["numba"] and Version("0.69.0") not in pins["numba"], pins["numba"]
    ours = {str(s) for s in pins["llvmlite"]}
    numbas = next(Requirement(r) for r in requires("numba") if r.startswith("llvmlite"))
    for bound in ("0.49.0", "0.50.0", "0.50.9", "0.51.0"):      # the pin: numba 0.68's own llvmlite range
        assert (Version(bound) in pins["llvmlite"]) == (Version(bound) in numbas.specifier), (ours, numbas)


# -- get_call_template: one variant per kernel, whatever constants its callers pass ------------------------
def _pick(x, i, flag):
    return x[i] + (1.0 if flag else 0.0)


_wide = compilation.one_signature(njit(_pick))
_plain = njit(_pick)           # the control: the same function without the hook


@njit
def _call_wide(x, n):
    return _wide(x, 0, True) + _wide(x, n, False) + _wide(x, 1, n > 0)


@njit
def _call_plain(x, n):
    return _plain(x, 0, True) + _plain(x, n, False) + _plain(x, 1, n > 0)


@njit
def _call_floor(n):
    return factor.pivot_floor(1.0, 3) + factor.pivot_floor(2.0, 4) + factor.pivot_floor(1.0, n)


def _literal(sig) -> bool:
    return any(isinstance(t, types.Literal) for t in sig)


def test_one_signature_hook_still_decides_the_variants():
    """numba's dispatcher still has ``get_call_template(args, kws)`` and a compiled caller still types
    its calls through it; with :func:`compilation.one_signature` a callee called with the constants 0,
    1, True, False compiles one variant, without it (the control) one per pattern of constants. A real
    kernel (``factor.pivot_floor``) carries the hook and gets no literal variant."""
    method = numba_dispatcher.Dispatcher.get_call_template
    assert list(inspect.signature(method).parameters) == ["self", "args", "kws"]
    assert "self.dispatcher.get_call_template(" in inspect.getsource(types.Dispatcher.get_call_type)
    assert _call_wide(np.ones(3), 2) == 5.0 and _call_plain(np.ones(3), 2) == 5.0
    assert len(_wide.overloads) == 1 and not any(map(_literal, _wide.overloads)), list(_wide.overloads)
    assert len(_plain.overloads) >= 2 and any(map(_literal, _plain.overloads)), (
        "numba no longer compiles a variant per constant: one_signature may be dropped", list(_plain.overloads))
    for k in (kernels.kinematics, factor.ltdl, factor.pivot_floor):
        assert "get_call_template" in vars(k), f"{k.py_func.__qualname__} is not wrapped by one_signature"
    assert _call_floor(5) > 0.0
    assert not any(map(_literal, factor.pivot_floor.overloads)), list(factor.pivot_floor.overloads)


def test_one_signature_refuses_a_numba_without_the_hook():
    """Without ``get_call_template`` (a numba that renamed it; here a plain function) one_signature
    raises, naming numba's version and the pin, instead of compiling a variant per constant unseen."""
    with pytest.raises(RuntimeError, match=rf"numba {numba.__version__}.*get_call_template.*pyproject.toml"):
        compilation.one_signature(_pick)


# -- _nrt and the cache locator: in a process of their own (a fresh compilation, an empty cache) -----------
_PROBE = '''
import numpy as np

def mat_vec(a, b, out):         # loops over its array arguments: plain njit counts references here
    for i in range(a.shape[0]):
        s = 0.0
        for j in range(a.shape[1]):
            s += a[i, j] * b[j]
        out[i] = s

def copies(x):                  # allocates: refused without NRT
    y = x.copy()
    return y[0]

def zeros(n):                   # allocates through np.zeros: refused without NRT (a typing error)
    return np.zeros(n)[0]
'''

_SCRIPT = '''
import json, sys, numpy as np
sys.path.insert(0, sys.argv[1])
import probe
from numba import njit
from numba.core import caching
from urdf2links import compilation, numba_cache
from urdf2links.dynamics import factor

def counts(d):
    ir = "\\n".join(d.inspect_llvm().values())
    return ir.count("call void @NRT_incref") + ir.count("call void @NRT_decref")

def refused(f, *args, **kw):
    try:
        f(*args, **kw)
    except Exception as e:
        return type(e).__name__ + ": " + ("NRT required but not enabled" if "NRT required but not enabled" in str(e)
                                          else "other")
    return None

got = {}
a, b = np.arange(12.0).reshape(3, 4), np.ones(4)
k, plain = compilation.kernel(probe.mat_vec), njit(probe.mat_vec)
for name, f in (("kernel", k), ("njit", plain)):
    out = np.zeros(3)
    f(a, b, out)
    got[name] = [counts(f), out.tolist()]
got["kernel_copies"] = refused(compilation.kernel(probe.copies), np.ones(3))
got["kernel_zeros"] = refused(compilation.kernel(probe.zeros), 3)
got["njit_copies"] = refused(njit(probe.copies), np.ones(3))
got["cfunc_zeros"] = refused(compilation.c_function, probe.zeros, "float64(int64)", refcounts=False)
got["cfunc_zeros_counting"] = refused(compilation.c_function, probe.zeros, "float64(int64)")
folder = numba_cache.install()
first = caching.CacheImpl._locator_classes[0]
got["locator"] = [str(folder), getattr(first, "_urdf2links", False), first.__mro__[1].__name__]
factor.pivot_floor(1.0, 3)      # a urdf2links kernel (cache=True): its index lands in the folder
got["cached"] = sorted(p.suffix for p in __import__("pathlib").Path(folder).rglob("*pivot_floor*"))
print(json.dumps(got))
'''


def test_nrt_option_and_cache_locator_still_work(tmp_path):
    """``_nrt=False`` (:func:`compilation.kernel`) still compiles a looping kernel with no reference
    counting in its LLVM, where plain ``njit`` (the control) counts, with the same result; a kernel or
    ``c_function(refcounts=False)`` that allocates is still refused (the counting ``cfunc`` of the same
    function compiles: the control). The package's cache locator is still first in numba's private list
    and a urdf2links kernel caches into the package's folder."""
    (tmp_path / "probe.py").write_text(textwrap.dedent(_PROBE))
    cache = tmp_path / "cache"
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    out = subprocess.run([sys.executable, "-c", _SCRIPT, str(tmp_path)], capture_output=True, text=True,
                         timeout=600, cwd=ROOT, env=dict(env, URDF2LINKS_CACHE_DIR=str(cache)))
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.strip().splitlines()[-1])
    expected = [6.0, 22.0, 38.0]        # rows of arange(12).reshape(3, 4) summed: exact in floating point
    assert got["njit"][0] > 0 and got["njit"][1] == expected, ("the control counts no references", got["njit"])
    assert got["kernel"] == [0, expected], got["kernel"]
    assert got["kernel_copies"] == "TypingError: NRT required but not enabled", got
    assert got["kernel_zeros"] is not None and got["kernel_zeros"].startswith("TypingError"), got
    assert got["njit_copies"] is None and got["cfunc_zeros_counting"] is None, got
    assert got["cfunc_zeros"] is not None, got
    assert got["locator"] == [str(cache), True, "UserProvidedCacheLocator"], got["locator"]
    assert ".nbi" in got["cached"] and ".nbc" in got["cached"], got["cached"]
