"""Oracles: slow, readable twins of the fast path that the tests check it against.

Nothing on the fast path imports this package. ``literal`` evaluates the trace formulas term by
term (O(n^3) to O(n^4)); ``recursive`` is the recursive form in numpy; ``python_plan`` is a
scene's right-hand side in numpy; ``loops`` runs the integration loops interpreted, on any
Python right-hand side.
"""
