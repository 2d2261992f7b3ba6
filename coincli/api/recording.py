"""What the public functions that record to Rerun as they run share: the checked destination of
a live recording, chaining the caller's callback with the recorder's, and the warning of a
recording that failed (a recording never fails the work it shows)."""

from __future__ import annotations

import warnings


def live_destination(rrd, spawn: bool, connect, notebook=False):
    """The checked destination of a live recording (None if none is asked for)."""
    if rrd is None and not spawn and connect is None and notebook is False:
        return None  # Rerun's code is not even imported
    from ..recordings.stream import check_destination

    return check_destination(rrd, spawn, connect, notebook)


def both(first, second):
    """A callback calling ``first`` then ``second`` with the same arguments (either may be
    None)."""
    if first is None or second is None:
        return first or second
    return lambda *args: (first(*args), second(*args))


def warn_if_failed(recorder, stacklevel: int = 3) -> None:
    """A RuntimeWarning if ``recorder``'s recording failed, attributed to the line that
    called the public function that calls this (``stacklevel``)."""
    if recorder is None or recorder.error is None:
        return
    from ..files import explain

    warnings.warn(f"the live recording failed: {explain(recorder.error)}", RuntimeWarning,
                  stacklevel=stacklevel)
