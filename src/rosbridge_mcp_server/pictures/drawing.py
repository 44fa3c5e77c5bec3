"""What the robot's pictures share: colours, a font, round tick steps, a scale bar, a robot marker, PNG bytes.

The maps, scans and charts of ``maps.py``, ``scans.py`` and ``charts.py`` are drawn with
Pillow only. Pure: no I/O; the tools run the drawing in a worker thread.
"""

from __future__ import annotations

import functools
import io
import math

from PIL import Image, ImageDraw, ImageFont

__all__ = [
    "OBSTACLE_COLOUR",
    "PATH_COLOUR",
    "ROBOT_COLOUR",
    "SERIES_COLOURS",
    "TEXT_COLOUR",
    "Rgb",
    "draw_robot",
    "draw_scale_bar",
    "font",
    "label",
    "nice_step",
    "png_bytes",
    "round_down",
    "ticks",
]

Rgb = tuple[int, int, int]

#: The robot's marker (a filled arrow at its pose), the plan, the laser's hits, and writing.
ROBOT_COLOUR: Rgb = (0, 90, 255)
PATH_COLOUR: Rgb = (0, 170, 60)
OBSTACLE_COLOUR: Rgb = (230, 0, 0)
TEXT_COLOUR: Rgb = (20, 20, 20)
#: Line colours of a chart's series, in order (distinct for the common kinds of colour blindness).
SERIES_COLOURS: tuple[Rgb, ...] = (
    (0, 114, 178),
    (213, 94, 0),
    (0, 158, 115),
    (204, 121, 167),
    (86, 180, 233),
    (230, 159, 0),
    (120, 120, 120),
    (0, 0, 0),
)


@functools.cache
def font(size: int = 12) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    """Pillow's bundled font (FreeType when Pillow has it, else its bitmap font)."""
    return ImageFont.load_default(size=size)


def nice_step(span: float, parts: int = 5) -> float:
    """A round step (1, 2 or 5 × 10^k) that cuts ``span`` into about ``parts`` pieces."""
    if not math.isfinite(span) or span <= 0:
        return 1.0
    raw = span / parts
    power = 10 ** math.floor(math.log10(raw))
    for factor in (1, 2, 5, 10):
        if raw <= factor * power:
            return float(factor * power)
    return float(10 * power)


def round_down(value: float) -> float:
    """The largest 1, 2 or 5 × 10^k not above ``value`` (``value`` itself when not positive and finite)."""
    if not math.isfinite(value) or value <= 0:
        return value
    power = 10 ** math.floor(math.log10(value))
    for factor in (5, 2, 1):
        if factor * power <= value * (1 + 1e-9):
            return float(factor * power)
    return float(power)


def ticks(low: float, high: float, parts: int = 5) -> list[float]:
    """Round values from ``low`` to ``high`` (inclusive) a :func:`nice_step` apart; none when the span is not
    a finite number (a robot's 1e308 must not make the loop endless)."""
    if not math.isfinite(high - low):
        return []
    step = nice_step(high - low, parts)
    first = math.ceil(low / step - 1e-9)
    values: list[float] = []
    k = first
    while k * step <= high + 1e-9 * step and len(values) <= 4 * parts + 2:
        values.append(round(k * step, 10))
        k += 1
    return values


def label(value: float, unit: str = "") -> str:
    """A tick or bar label: no trailing zeros, with its unit."""
    text = f"{value:.6g}"
    return f"{text} {unit}" if unit else text


def draw_scale_bar(
    draw: ImageDraw.ImageDraw, pixels_per_metre: float, corner: tuple[int, int], *, boxed: bool = True
) -> float:
    """A labelled bar of a round length (about a fifth of the picture) with its left end at ``corner``
    (bottom-left of the bar); returns the length in metres. ``boxed``: on a white box with the label above
    (over a picture); else the label right of the bar (in a margin, where nothing is hidden)."""
    width = draw.im.size[0]
    metres = round_down(width * 0.25 / pixels_per_metre)
    length = max(1, round(metres * pixels_per_metre))
    x, y = corner
    text = label(metres, "m")
    if not boxed:
        draw.line((x, y, x + length, y), fill=TEXT_COLOUR, width=3)
        draw.line((x, y - 5, x, y), fill=TEXT_COLOUR, width=1)
        draw.line((x + length, y - 5, x + length, y), fill=TEXT_COLOUR, width=1)
        draw.text((x + length + 6, y), text, fill=TEXT_COLOUR, font=font(), anchor="lm")
        return metres
    box = draw.textbbox((0, 0), text, font=font())
    pad = 4
    draw.rectangle(
        (x - pad, y - 10 - (box[3] - box[1]) - pad, x + max(length, box[2]) + pad, y + pad),
        fill=(255, 255, 255),
        outline=(150, 150, 150),
    )
    draw.line((x, y, x + length, y), fill=TEXT_COLOUR, width=3)
    draw.line((x, y - 5, x, y), fill=TEXT_COLOUR, width=1)
    draw.line((x + length, y - 5, x + length, y), fill=TEXT_COLOUR, width=1)
    draw.text((x, y - 8 - (box[3] - box[1])), text, fill=TEXT_COLOUR, font=font())
    return metres


def draw_robot(draw: ImageDraw.ImageDraw, centre: tuple[float, float], heading: float, radius: float) -> None:
    """The robot as a filled arrow pointing along ``heading`` (radians, counter-clockwise from the picture's
    +x axis, which points right), ``radius`` pixels from centre to tip, with a white rim; never smaller than
    a twentieth of the picture's long side (16 px at least), so it is seen at a glance."""
    radius = max(radius, 16.0, max(draw.im.size) / 20)
    cx, cy = centre

    def at(angle: float, r: float) -> tuple[float, float]:
        return (cx + r * math.cos(heading + angle), cy - r * math.sin(heading + angle))

    outline = [at(0, radius), at(2.5, radius), at(math.pi, radius * 0.35), at(-2.5, radius)]
    draw.polygon(outline, fill=ROBOT_COLOUR, outline=(255, 255, 255), width=2)


def png_bytes(image: Image.Image) -> bytes:
    """The picture as a small PNG: drawings have few colours, so a 64-colour palette keeps them small."""
    if image.mode == "RGB":
        image = image.quantize(colors=64, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)
    out = io.BytesIO()
    image.save(out, "PNG", optimize=False, compress_level=6)
    return out.getvalue()
