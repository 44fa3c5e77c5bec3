"""The garbage collector paused while the server starts (docs/performance.md, row 6a).

A start makes some 150 000 objects that live as long as the process: the modules of the MCP SDK and ours,
their classes, the tools' pydantic models and schemas. With the collector on, every few hundred new objects
start a collection of the young ones, and every tenth of those a larger one; nearly all they walk is kept, so
they free almost nothing, yet they were about a quarter of what our start added to the SDK's.
:func:`pause_collector` turns it off as the console script starts; :func:`resume_collector`, once the server
is built and before it serves, moves everything made so far to the collector's permanent generation
(``gc.freeze``: no later collection walks it again) and turns the collector back on. The price: the ~6 000
objects the start left unreachable in cycles stay allocated for the process's life (about 1 MiB, once).
"""

from __future__ import annotations

import gc

__all__ = ["pause_collector", "resume_collector"]


def pause_collector() -> None:
    """Turn the collector off until :func:`resume_collector`."""
    gc.disable()


def resume_collector() -> None:
    """Keep what the start made out of every later collection and turn the collector on, if
    :func:`pause_collector` turned it off (a test that calls ``run`` or ``serve`` leaves it as it is)."""
    if gc.isenabled():
        return
    gc.freeze()
    gc.enable()
