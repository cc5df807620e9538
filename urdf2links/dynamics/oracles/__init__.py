"""Oracles of the dynamics: slow, readable twins of the compiled kernels that the tests check them against.

``literal`` evaluates the trace formulas term by term (O(n^3) to O(n^4)); ``recursive`` is the
recursive form in numpy. Nothing on the fast path imports them (``Model(method="literal"|"numpy")``
loads them when asked). A scene's right-hand side in numpy is :mod:`urdf2links.scenes.python_plan`;
the integration loops run interpreted through :func:`urdf2links.integration.loops.run`.
"""
