"""The sub-commands of ``urdf2links``, by concern: :mod:`.inspect` (inspect, list), :mod:`.run` (simulate,
sweep, cache), :mod:`.comparisons` (compare, report, tradeoff, check: options here, handlers in ``urdf2links.compare``)
and their shared options, :mod:`.options`. :data:`urdf2links.cli.COMMANDS` is the table that names them.

Part of the command line's layer (docs/layout.md): with ``urdf2links.cli``, the only modules under ``urdf2links/`` that
reach ``urdf2links.compare`` (only inside a handler, when it runs).
"""
