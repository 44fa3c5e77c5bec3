"""What the list tools share: a name filter, a page (``offset``, ``limit``), and a text budget.

A real robot's graph (Nav2: ~80 topics, ~400 services, 1,000+ parameters) makes whole listings far longer
than a model should read. Every list tool takes ``filter`` (a glob such as ``*costmap*`` or a substring such
as ``nav2_msgs``, matched case-insensitively against names and, where the tool says so, types), ``limit`` and
``offset``; its text ends by saying how many more there are and how to get them. The text also stays within
:data:`TEXT_BUDGET` characters whatever the names' lengths: rows past the budget move to the next page. The
structured content carries the same page.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Annotated, Generic, TypeVar

from pydantic import Field

__all__ = [
    "FRAME_RESERVE",
    "TEXT_BUDGET",
    "FilterArg",
    "OffsetArg",
    "Page",
    "limit_arg",
    "matcher",
    "page_note",
    "page_of",
    "page_of_groups",
    "typed_line",
]

#: The most characters a list tool's text holds (~2,000 tokens).
TEXT_BUDGET = 8_000
#: What a page's heading and closing note may take: the rows get the rest.
FRAME_RESERVE = 400

FilterArg = Annotated[
    str | None,
    Field(description="Glob or substring of names (or types), e.g. *costmap*"),
]
OffsetArg = Annotated[int, Field(ge=0, description="Matches to skip, e.g. 100")]


def typed_line(name: str, type_name: str | None) -> str:
    """One listed name and its type, as every list tool writes it: ``/scan (sensor_msgs/msg/LaserScan)``."""
    return f"{name} ({type_name or 'type unknown'})"


def limit_arg(default: int) -> object:
    """The ``limit`` parameter's annotation metadata, with the tool's default in its description."""
    return Field(ge=1, le=1000, description=f"Most rows, e.g. {default // 2}")


def matcher(pattern: str | None) -> Callable[[str], bool]:
    """A test for a name or type: a glob when the pattern has ``*?[``, else a substring; both ignore case."""
    if not pattern:
        return lambda _text: True
    wanted = pattern.strip().lower()
    if any(char in wanted for char in "*?["):
        return lambda text: fnmatch.fnmatchcase(text.lower(), wanted)
    return lambda text: wanted in text.lower()


T = TypeVar("T")


@dataclass(frozen=True)
class Page(Generic[T]):
    """The rows of one page, how many matched in all, and where the page starts."""

    rows: list[T]
    matched: int
    offset: int

    @property
    def more(self) -> int:
        """Matches after this page."""
        return max(0, self.matched - self.offset - len(self.rows))


def page_of(
    rows: Sequence[T],
    *,
    offset: int,
    limit: int,
    line: Callable[[T], str],
    budget: int = TEXT_BUDGET - FRAME_RESERVE,
) -> Page[T]:
    """The page of ``rows`` from ``offset``: at most ``limit`` rows, and no more than fit ``budget``
    characters of text when each is rendered by ``line`` (always at least one row)."""
    shown: list[T] = []
    used = 0
    for row in rows[offset : offset + limit]:
        used += len(line(row)) + 1
        if shown and used > budget:
            break
        shown.append(row)
    return Page(shown, len(rows), offset)


K = TypeVar("K")


def page_of_groups(
    groups: Sequence[tuple[K, Sequence[T]]],
    *,
    offset: int,
    limit: int,
    line: Callable[[T], str],
    budget: int = TEXT_BUDGET - FRAME_RESERVE,
) -> tuple[list[tuple[K, list[T]]], Page[T]]:
    """:func:`page_of` over rows that come in groups (a node's parameter names), without flattening them all:
    the groups on the page, each with its rows there, and the :class:`Page` of those rows."""
    shown: list[tuple[K, list[T]]] = []
    rows: list[T] = []
    matched = used = 0
    skip = offset
    full = False
    for key, items in groups:
        matched += len(items)
        if full:
            continue
        if skip >= len(items):
            skip -= len(items)
            continue
        taken: list[T] = []
        for row in items[skip : skip + limit - len(rows)]:
            used += len(line(row)) + 1
            if (rows or taken) and used > budget:
                full = True
                break
            taken.append(row)
        skip = 0
        if taken:
            shown.append((key, taken))
            rows += taken
        full = full or len(rows) >= limit
    return shown, Page(rows, matched, offset)


def page_note(page: Page[T], noun: str, filter_text: str | None, total: int) -> str:
    """The line a paged text ends with ("" when the page shows everything there is)."""
    parts: list[str] = []
    if filter_text:
        parts.append(f"{page.matched} of {total} {noun} match {filter_text!r}")
    if page.offset or page.more:
        first = page.offset + 1 if page.rows else page.offset
        parts.append(f"shown {first}-{page.offset + len(page.rows)} of {page.matched}")
    if page.more:
        narrow = "" if filter_text else ", or narrow with filter (e.g. a name part or a glob like */scan*)"
        parts.append(f"{page.more} more: call again with offset={page.offset + len(page.rows)}{narrow}")
    return ("(" + "; ".join(parts) + ")") if parts else ""
