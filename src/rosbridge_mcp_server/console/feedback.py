"""A running goal's last feedback as the console shows it: its numbers and words by name, rounded
(``distance_remaining 2.31, number_of_recoveries 0, navigation_time 12 s``), not the raw JSON."""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any, Final

__all__ = ["FEEDBACK_FIELDS", "feedback_text"]

#: The most fields a goal's feedback shows on the page.
FEEDBACK_FIELDS: Final = 6
#: Longest feedback shown as JSON when it has no field to name (arrays only, say).
JSON_SHOWN: Final = 200
#: Parts of a feedback a person does not read on the page: where the robot is (the map shows it), stamps.
_SKIPPED: Final = frozenset({"header", "current_pose", "pose", "stamp"})


def feedback_text(feedback: Any) -> str:
    """Named numbers and words (durations in seconds), at most :data:`FEEDBACK_FIELDS`; else short JSON."""
    shown: list[str] = []
    for path, value in _leaves(feedback, ""):
        if len(shown) == FEEDBACK_FIELDS:
            shown.append("…")
            break
        shown.append(f"{path} {value}")
    if shown:
        return ", ".join(shown)
    text = json.dumps(feedback, ensure_ascii=False, default=str)
    return text if len(text) <= JSON_SHOWN else f"{text[:JSON_SHOWN]}… ({len(text)} characters)"


def _leaves(value: Any, path: str) -> Iterator[tuple[str, str]]:
    if isinstance(value, bool) or value is None:
        return
    if isinstance(value, int | float):
        yield path, f"{value:.2f}".rstrip("0").rstrip(".") if isinstance(value, float) else str(value)
    elif isinstance(value, str) and value:
        yield path, value[:40]
    elif isinstance(value, dict):
        if (seconds := _seconds(value)) is not None:
            yield path, f"{seconds:.0f} s"
            return
        for key, item in value.items():
            if isinstance(key, str) and key not in _SKIPPED:
                yield from _leaves(item, f"{path}.{key}" if path else key)


def _seconds(value: dict[str, Any]) -> float | None:
    """A ROS duration (``sec``/``nanosec``, ROS 1 ``secs``/``nsecs``) in seconds, or None."""
    for whole, part in (("sec", "nanosec"), ("secs", "nsecs")):
        if set(value) == {whole, part}:
            numbers = value[whole], value[part]
            if all(isinstance(n, int | float) and not isinstance(n, bool) for n in numbers):
                return float(numbers[0]) + float(numbers[1]) / 1e9
    return None
