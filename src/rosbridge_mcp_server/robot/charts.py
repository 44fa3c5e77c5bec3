"""Numeric series against time as a line chart: axes with round ticks, a grid, a legend with units.

Series sharing one unit share the y axis label; gaps (NaN) break a line. Long series are drawn through at
most two points per pixel column (the column's min and max), so a 60,000-sample series costs what 1,600
cost. Pure: no I/O.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from PIL import Image, ImageDraw

from rosbridge_mcp_server.robot.drawing import SERIES_COLOURS, TEXT_COLOUR, font, label, ticks
from rosbridge_mcp_server.robot.series import Series

__all__ = ["Stats", "draw_chart", "stats"]

_LEFT, _RIGHT, _TOP, _BOTTOM = 64, 16, 12, 40


@dataclass(frozen=True)
class Stats:
    """A series' min / max / mean / last over its valid samples (all None when it had none)."""

    count: int
    min: float | None
    max: float | None
    mean: float | None
    last: float | None


def stats(series: Series) -> Stats:
    """Min, max, mean and last of the finite samples."""
    valid = [v for v in series.values if math.isfinite(v)]
    if not valid:
        return Stats(len(series.values), None, None, None, None)
    return Stats(len(series.values), min(valid), max(valid), math.fsum(valid) / len(valid), valid[-1])


def draw_chart(series: Sequence[Series], duration: float, width: int, height: int) -> Image.Image:
    """The chart, ``width`` × ``height`` pixels, time from 0 to ``duration`` seconds."""
    image = Image.new("RGB", (width, height), (255, 255, 255))
    draw = ImageDraw.Draw(image)
    small = font(11)
    plot_w, plot_h = width - _LEFT - _RIGHT, height - _TOP - _BOTTOM
    finite = [v for s in series for v in s.values if math.isfinite(v)]
    low, high = (min(finite), max(finite)) if finite else (0.0, 1.0)
    if high - low < 1e-12:
        pad = abs(high) * 0.1 or 1.0
        low, high = low - pad, high + pad
    else:
        pad = (high - low) * 0.08
        low, high = low - pad, high + pad

    def px(t: float) -> float:
        return _LEFT + t / duration * plot_w

    def py(v: float) -> float:
        return _TOP + (high - v) / (high - low) * plot_h

    for value in ticks(low, high, max(2, plot_h // 50)):
        y = py(value)
        draw.line((_LEFT, y, _LEFT + plot_w, y), fill=(230, 230, 230))
        draw.text((_LEFT - 6, y), label(value), fill=TEXT_COLOUR, font=small, anchor="rm")
    for value in ticks(0.0, duration, max(2, plot_w // 80)):
        x = px(value)
        draw.line((x, _TOP, x, _TOP + plot_h), fill=(230, 230, 230))
        draw.text((x, _TOP + plot_h + 4), label(value), fill=TEXT_COLOUR, font=small, anchor="ma")
    if low < 0 < high:
        draw.line((_LEFT, py(0.0), _LEFT + plot_w, py(0.0)), fill=(160, 160, 160))
    draw.rectangle((_LEFT, _TOP, _LEFT + plot_w, _TOP + plot_h), outline=(120, 120, 120))
    draw.text((_LEFT + plot_w, height - 4), "time (s)", fill=TEXT_COLOUR, font=small, anchor="rd")
    units = {s.unit for s in series}
    if len(units) == 1 and next(iter(units)):
        draw.text((4, 2), next(iter(units)), fill=TEXT_COLOUR, font=small)
    for index, line in enumerate(series):
        colour = SERIES_COLOURS[index % len(SERIES_COLOURS)]
        for run in _runs(line, px, py, plot_w):
            if len(run) > 1:
                draw.line(run, fill=colour, width=2)
            for x, y in run if len(run) <= 40 else ():
                draw.ellipse((x - 2, y - 2, x + 2, y + 2), fill=colour)
    _legend(draw, series, units)
    return image


def _runs(
    line: Series, px: Callable[[float], float], py: Callable[[float], float], plot_w: int
) -> list[list[tuple[float, float]]]:
    """The series as pixel polylines, split at gaps, at most a min and a max per pixel column."""
    runs: list[list[tuple[float, float]]] = []
    current: list[tuple[float, float]] = []
    dense = len(line.values) > 2 * plot_w
    column: float | None = None
    lo = hi = 0.0
    for t, v in zip(line.times, line.values, strict=True):
        if not math.isfinite(v):
            if column is not None:
                current.extend(((column, py(lo)), (column, py(hi))))
                column = None
            if current:
                runs.append(current)
                current = []
            continue
        if not dense:
            current.append((px(t), py(v)))
            continue
        col = float(int(px(t)))
        if column is None or col != column:
            if column is not None:
                current.extend(((column, py(lo)), (column, py(hi))))
            column, lo, hi = col, v, v
        else:
            lo, hi = min(lo, v), max(hi, v)
    if column is not None:
        current.extend(((column, py(lo)), (column, py(hi))))
    if current:
        runs.append(current)
    return runs


def _legend(draw: ImageDraw.ImageDraw, series: Sequence[Series], units: set[str]) -> None:
    small = font(11)
    show_units = len(units) > 1
    names = [s.label + (f" ({s.unit})" if show_units and s.unit else "") for s in series]
    widths = [draw.textbbox((0, 0), n, font=small)[2] for n in names]
    box_w = max(widths, default=0) + 30
    x0, y0 = _LEFT + 8, _TOP + 6
    draw.rectangle(
        (x0, y0, x0 + box_w, y0 + 16 * len(names) + 6), fill=(255, 255, 255), outline=(180, 180, 180)
    )
    for index, name in enumerate(names):
        colour = SERIES_COLOURS[index % len(SERIES_COLOURS)]
        y = y0 + 11 + 16 * index
        draw.line((x0 + 6, y, x0 + 22, y), fill=colour, width=3)
        draw.text((x0 + 26, y), name, fill=TEXT_COLOUR, font=small, anchor="lm")
