"""Counts and sizes are said one way in every answer: no "1 topics", no 40 KB file shown as "0.0 MB"."""

from __future__ import annotations

import pytest

from rosbridge_mcp_server.robot.wording import counted, full_stop, size_text


@pytest.mark.parametrize(
    ("number", "noun", "plural", "said"),
    [
        (0, "topic", None, "0 topics"),
        (1, "topic", None, "1 topic"),
        (2, "action server", None, "2 action servers"),
        (1, "status", "statuses", "1 status"),
        (4, "status", "statuses", "4 statuses"),
    ],
)
def test_a_count_agrees_with_its_noun(number: int, noun: str, plural: str | None, said: str) -> None:
    assert counted(number, noun, plural) == said


@pytest.mark.parametrize(
    ("size", "said"),
    [
        (0, "0 B"),
        (999, "999 B"),
        (1_000, "1 KB"),
        (40_000, "40 KB"),
        (58_321, "58 KB"),
        (999_499, "999 KB"),
        (999_999, "1.0 MB"),
        (1_234_567, "1.2 MB"),
        (99_960_000, "100 MB"),
        (999_960_000, "1.0 GB"),
        (2_500_000_000, "2.5 GB"),
    ],
)
def test_a_size_keeps_its_digits_in_the_unit_that_fits(size: int, said: str) -> None:
    assert size_text(size) == said


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("nothing publishes transforms", "nothing publishes transforms."),
        ("nothing publishes transforms.", "nothing publishes transforms."),
        ("is it running? ", "is it running?"),
        ("cut…", "cut…"),
    ],
)
def test_a_text_joined_before_another_ends_in_one_stop(text: str, said: str) -> None:
    assert full_stop(text) == said
