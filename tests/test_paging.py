"""The list tools' pages: rows that come in groups are paged exactly as the same rows flattened."""

from __future__ import annotations

import itertools

import pytest

from rosbridge_mcp_server.tools.paging import page_of, page_of_groups

GROUPS = [("/a", ["x"] * 3), ("/b", []), ("/c", [f"name{i}" for i in range(7)]), ("/d", ["y", "zz"])]


def _listed(name: str) -> str:
    return name + ", "


@pytest.mark.parametrize(
    ("offset", "limit", "budget"),
    list(itertools.product([0, 1, 3, 5, 11, 12, 20], [1, 2, 4, 100], [1, 12, 15, 20, 10_000])),
)
def test_grouped_rows_page_as_the_same_rows_flattened(offset: int, limit: int, budget: int) -> None:
    """Same rows, count, offset and rest; each group keeps its own rows, in order."""
    flat = [(key, row) for key, rows in GROUPS for row in rows]
    expected = page_of(flat, offset=offset, limit=limit, line=lambda pair: _listed(pair[1]), budget=budget)
    shown, page = page_of_groups(GROUPS, offset=offset, limit=limit, line=_listed, budget=budget)
    assert [(key, row) for key, rows in shown for row in rows] == expected.rows
    assert page.rows == [row for _, row in expected.rows]
    assert (page.matched, page.offset, page.more) == (expected.matched, expected.offset, expected.more)
    assert all(rows for _, rows in shown)
    assert len({key for key, _ in shown}) == len(shown)
