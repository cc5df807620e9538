"""urdf2links.compare.check: ``urdf2links check`` and its pytest plugin -- a repository's robots, pairs and
scenes checked on every change (docs/ci.md)."""
