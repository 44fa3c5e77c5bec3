"""Numeric series against time as a line chart: axes with round ticks, a grid, a legend with units.

Series sharing one unit share a panel and its y axis, labelled with the unit; another unit gets its own
panel, with its own scale. Each series has a colour, a dash and a marker of its own, so coinciding series
both show; gaps (NaN) break a line. Long series are drawn through at most two points per pixel column (the
column's min and max), so a 60,000-sample series costs what 1,600 cost. Pure: no I/O.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from PIL import Image, ImageDraw

from rosbridge_mcp_server.pictures.drawing import SERIES_COLOURS, TEXT_COLOUR, font, label, ticks
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
    """The chart, ``width`` × ``height`` pixels, time from 0 to ``duration`` seconds.

    Series of one unit share a panel and its y axis, labelled with the unit; each further unit (m/s beside
    rad/s) gets a panel of its own below, with its own scale. Each series has its colour, its dash and its
    marker, so two that coincide still both show.
    """
    image = Image.new("RGB", (width, height), (255, 255, 255))
    draw = ImageDraw.Draw(image)
    small = font(11)
    plot_w = width - _LEFT - _RIGHT
    units = list(dict.fromkeys(s.unit for s in series)) or [""]
    gap = 10
    panel_h = max(20, (height - _TOP - _BOTTOM - gap * (len(units) - 1)) // len(units))

    def px(t: float) -> float:
        return _LEFT + t / duration * plot_w

    for value in ticks(0.0, duration, max(2, plot_w // 80)):
        x = px(value)
        draw.text((x, height - _BOTTOM + 4), label(value), fill=TEXT_COLOUR, font=small, anchor="ma")
    for number, unit in enumerate(units):
        top = _TOP + number * (panel_h + gap)
        members = [(index, s) for index, s in enumerate(series) if s.unit == unit]
        py = _panel(
            draw,
            [s for _, s in members],
            unit=unit,
            top=top,
            plot_h=panel_h,
            plot_w=plot_w,
            px=px,
            duration=duration,
            with_unit=len(units) > 1,
        )
        for index, line in members:
            _draw_series(draw, index, _runs(line, px, py, plot_w))
    draw.text((_LEFT + plot_w, height - 4), "time (s)", fill=TEXT_COLOUR, font=small, anchor="rd")
    if len(units) == 1 and units[0]:
        draw.text((4, 2), units[0], fill=TEXT_COLOUR, font=small)
    _legend(image, draw, series, set(units), plot_w=plot_w, bottom=height - _BOTTOM)
    return image


def _panel(
    draw: ImageDraw.ImageDraw,
    members: Sequence[Series],
    *,
    unit: str,
    top: int,
    plot_h: int,
    plot_w: int,
    px: Callable[[float], float],
    duration: float,
    with_unit: bool,
) -> Callable[[float], float]:
    """One panel's grid, y ticks and frame (its unit at the top of its axis); returns value → pixel row."""
    small = font(11)
    finite = [v for s in members for v in s.values if math.isfinite(v)]
    low, high = (min(finite), max(finite)) if finite else (0.0, 1.0)
    if high - low < 1e-12:
        pad = abs(high) * 0.1 or 1.0
        low, high = low - pad, high + pad
    else:
        pad = (high - low) * 0.08
        low, high = low - pad, high + pad

    def py(v: float) -> float:
        return top + (high - v) / (high - low) * plot_h

    for value in ticks(low, high, max(2, plot_h // 50)):
        y = py(value)
        draw.line((_LEFT, y, _LEFT + plot_w, y), fill=(230, 230, 230))
        if not with_unit or y > top + 14:  # room for the unit
            draw.text((_LEFT - 6, y), label(value), fill=TEXT_COLOUR, font=small, anchor="rm")
    bottom = top + plot_h
    for value in ticks(0.0, duration, max(2, plot_w // 80)):
        draw.line((px(value), top, px(value), bottom), fill=(230, 230, 230))
    if low < 0 < high:
        draw.line((_LEFT, py(0.0), _LEFT + plot_w, py(0.0)), fill=(160, 160, 160))
    draw.rectangle((_LEFT, top, _LEFT + plot_w, bottom), outline=(120, 120, 120))
    if with_unit:
        draw.text((_LEFT - 6, top), unit or "(no unit)", fill=TEXT_COLOUR, font=small, anchor="ra")
    return py


#: Each series' dash (on, off pixels; ``()``: solid) and marker, in order, beside its colour.
_DASHES: tuple[tuple[int, ...], ...] = ((), (9, 5), (3, 4), (12, 4, 3, 4))
_MARKERS = ("circle", "square", "triangle", "diamond")


def _draw_series(draw: ImageDraw.ImageDraw, index: int, runs: list[list[tuple[float, float]]]) -> None:
    colour = SERIES_COLOURS[index % len(SERIES_COLOURS)]
    dash = _DASHES[index % len(_DASHES)]
    marker = _MARKERS[(index // len(_DASHES) + index) % len(_MARKERS)]
    for run in runs:
        if len(run) > 1:
            _dashed(draw, run, colour, dash, width=3 if index == 0 else 2)
        if len(run) <= 40:
            for point in run:
                _marker(draw, point, marker, colour)
        else:
            # A marker every ~60 pixels along a long line, offset per series so coinciding ones alternate.
            step = max(1, len(run) // max(1, int((run[-1][0] - run[0][0]) / 60) or 1))
            for point in run[(index * step) // 3 :: step]:
                _marker(draw, point, marker, colour)


def _dashed(
    draw: ImageDraw.ImageDraw,
    points: Sequence[tuple[float, float]],
    colour: tuple[int, int, int],
    dash: tuple[int, ...],
    width: int,
) -> None:
    """A polyline, solid or cut into the ``dash`` pattern (continued across its vertices)."""
    if not dash:
        draw.line(list(points), fill=colour, width=width)
        return
    phase, on = 0.0, True
    part = 0
    for (x0, y0), (x1, y1) in itertools.pairwise(points):
        length = math.hypot(x1 - x0, y1 - y0)
        done = 0.0
        while done < length:
            left = dash[part] - phase
            step = min(left, length - done)
            if on:
                a, b = done / length, (done + step) / length
                draw.line(
                    (x0 + (x1 - x0) * a, y0 + (y1 - y0) * a, x0 + (x1 - x0) * b, y0 + (y1 - y0) * b),
                    fill=colour,
                    width=width,
                )
            done += step
            phase += step
            if phase >= dash[part] - 1e-9:
                phase, part, on = 0.0, (part + 1) % len(dash), not on


def _marker(
    draw: ImageDraw.ImageDraw, point: tuple[float, float], kind: str, colour: tuple[int, int, int]
) -> None:
    x, y = point
    r = 3
    if kind == "circle":
        draw.ellipse((x - r, y - r, x + r, y + r), fill=colour)
    elif kind == "square":
        draw.rectangle((x - r, y - r, x + r, y + r), outline=colour, width=2)
    elif kind == "triangle":
        draw.polygon([(x, y - r - 1), (x + r + 1, y + r), (x - r - 1, y + r)], outline=colour, width=2)
    else:
        draw.polygon(
            [(x, y - r - 1), (x + r + 1, y), (x, y + r + 1), (x - r - 1, y)], outline=colour, width=2
        )


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


def _legend(
    image: Image.Image,
    draw: ImageDraw.ImageDraw,
    series: Sequence[Series],
    units: set[str],
    *,
    plot_w: int,
    bottom: int,
) -> None:
    """The legend in the plot's corner where it hides the fewest drawn points."""
    small = font(11)
    show_units = len(units) > 1
    names = [s.label + (f" ({s.unit})" if show_units and s.unit else "") for s in series]
    widths = [draw.textbbox((0, 0), n, font=small)[2] for n in names]
    box_w = math.ceil(max(widths, default=0)) + 34
    box_h = 16 * len(names) + 6
    left, right = _LEFT + 8, max(_LEFT + 8, _LEFT + plot_w - 8 - box_w)
    top, low = _TOP + 6, max(_TOP + 6, bottom - 6 - box_h)
    corners = [(left, top), (right, top), (left, low), (right, low)]
    colours = set(SERIES_COLOURS)

    def hidden(corner: tuple[int, int]) -> int:
        x, y = corner
        found = image.crop((x, y, x + box_w, y + box_h)).getcolors(maxcolors=box_w * box_h) or []
        return sum(count for count, colour in found if colour in colours)

    x0, y0 = min(corners, key=hidden)
    draw.rectangle((x0, y0, x0 + box_w, y0 + box_h), fill=(255, 255, 255), outline=(180, 180, 180))
    for index, name in enumerate(names):
        colour = SERIES_COLOURS[index % len(SERIES_COLOURS)]
        y = y0 + 11 + 16 * index
        _dashed(draw, [(x0 + 4, y), (x0 + 24, y)], colour, _DASHES[index % len(_DASHES)], 2)
        _marker(draw, (x0 + 14, y), _MARKERS[(index // len(_DASHES) + index) % len(_MARKERS)], colour)
        draw.text((x0 + 30, y), name, fill=TEXT_COLOUR, font=small, anchor="lm")
