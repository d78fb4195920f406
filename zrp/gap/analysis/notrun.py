"""An analysis that cannot run on a data set's shape says why (:class:`NotRun`), and the
diagnosis records the reason (in diagnosis.json and the report) and goes on with the others.

Raised, never escaping the diagnosis: the stage that calls an optional analysis (the test of
what remains, the learned residual term) catches it and keeps its message.
"""

from __future__ import annotations

from zrp.errors import ZRPError

__all__ = ["NotRun"]


class NotRun(ZRPError):
    """An analysis cannot run on these data; the message says why, in words for the report
    (a clause: no leading capital, no full stop)."""
