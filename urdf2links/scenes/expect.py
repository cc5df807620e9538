"""``[expect]``: a hard case whose run stops by design, and the error it stops with.

Some shipped hard cases are there to show where the method stops: a closed loop thrown through its change point,
where the constraint rows lose their independence and the multipliers are not determined
(``robots/loops/closed_leg_change_point.toml``). Such a scene says so::

    [expect]
    stop = "DynamicsError"                        # the error's class name
    message = "knee_loop.x are not independent"   # words its message must hold

``urdf2links report`` then lists the scene as stopping by design, with the error's message, and does not count
it as a failure; a stop with another error, or another message, is a failure, and so is a run that reaches the
scene's own ``t_end`` without stopping (the change point was not caught). Nothing else changes: ``simulate`` and
``compare`` raise the error as they would without ``[expect]``.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["ExpectedStop", "parse_expect", "expect_toml", "STOP_ERRORS"]

#: The errors a run may stop with by design (urdf2links.errors).
STOP_ERRORS = ("DynamicsError", "IntegrationError")


@dataclass(frozen=True)
class ExpectedStop:
    """The run stops with ``error`` (a class name of :data:`STOP_ERRORS`) whose message holds ``message``."""

    error: str
    message: str

    def matches(self, exc: BaseException) -> bool:
        """True when ``exc`` is this stop: its class (or a base class) is named ``error``, its message holds
        ``message``."""
        names = {c.__name__ for c in type(exc).__mro__}
        return self.error in names and self.message in str(exc)

    def text(self) -> str:
        return f"stops by design with {self.error} ({self.message!r})"


def parse_expect(r, data: dict) -> ExpectedStop | None:
    """``[expect]`` of a scene's TOML ``data`` (module doc); ``r`` the scene's reader (its errors name the file
    and key)."""
    if "expect" not in data:
        return None
    t = data["expect"]
    r.keys(t, ("stop", "message"), "expect")
    error, message = t.get("stop"), t.get("message")
    if error not in STOP_ERRORS:
        r.fail("expect.stop", f"must name the error the run stops with, one of {list(STOP_ERRORS)}; got {error!r}")
    if not isinstance(message, str) or not message.strip():
        r.fail("expect.message", "must give words the error's message holds (a non-empty string), so that another "
                                 f"stop is not taken for this one; got {message!r}")
    return ExpectedStop(error, message)


def expect_toml(stop: ExpectedStop | None, value) -> list[str]:
    """The ``[expect]`` table of a written scene (``value``: the TOML writer of a value)."""
    if stop is None:
        return []
    return ["[expect]", "# a hard case: the run stops by design with this error (urdf2links.scenes.expect)",
            f"stop = {value(stop.error)}", f"message = {value(stop.message)}", ""]
