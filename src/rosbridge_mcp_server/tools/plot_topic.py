"""``plot_topic``: numeric fields of topics over some seconds, as a chart with per-series figures."""

from __future__ import annotations

import asyncio
from typing import Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.series import FieldError, Series, TopicFields, collect
from rosbridge_mcp_server.tools.arguments import FROM_JSON_TEXT
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    LongWork,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolImage,
    ToolSpec,
)
from rosbridge_mcp_server.tools.typed_topics import typed_topic

__all__ = ["SPEC", "PlotAnswer", "run"]

MAX_SERIES = 8
_EXAMPLE = '["/cmd_vel linear.x", "/odom twist.twist.linear.x"]'


class SeriesFigures(BaseModel):
    """One field's samples."""

    topic: str
    field: str
    unit: str
    samples: int
    min: float | None
    max: float | None
    mean: float | None
    last: float | None
    rate_hz: float | None


class PlotAnswer(BaseModel):
    """What was collected and drawn over ``duration`` seconds."""

    duration: float
    series: list[SeriesFigures]
    notes: list[str]


SPEC = ToolSpec(
    name="plot_topic",
    title="Plot topics over time",
    description=(
        "Chart numeric fields (dotted paths) of topics over some seconds, with min/max/mean/"
        "last and rate. Read-only. Example: "
        '{"series": ["/odom twist.twist.linear.x"], "duration": 5}'
    ),
    hints=READS_ROBOT,
    output=PlotAnswer,
    long_work=LongWork(),
)


async def run(
    ctx: ToolContext,
    *,
    series: Annotated[
        list[str],
        Field(
            min_length=1,
            max_length=MAX_SERIES,
            description=f'"TOPIC FIELD [FIELD...]", e.g. {_EXAMPLE}',
        ),
        FROM_JSON_TEXT,
    ],
    duration: Annotated[float, Field(gt=0, le=60, description="Seconds, e.g. 5")] = 5.0,
    max_size: Annotated[int, Field(ge=200, le=2048, description="Width in pixels, e.g. 800")] = 800,
) -> ToolAnswer:
    """Subscribe to every topic at once, collect the fields, chart them off the event loop."""
    wanted: dict[str, list[str]] = {}
    for item in series:
        words = item.split()
        if len(words) < 2:
            raise ToolFailure(
                f'series {item!r} needs a topic and at least one field, e.g. "/odom twist.twist.linear.x".'
            )
        fields = wanted.setdefault(words[0], [])
        fields.extend(f.strip(".") for f in words[1:] if f.strip(".") not in fields)
    total = sum(len(f) for f in wanted.values())
    if total > MAX_SERIES:
        raise ToolFailure(f"{total} fields asked for; a chart holds at most {MAX_SERIES}.")
    topics = []
    for topic, fields in wanted.items():
        name, msg_type = await typed_topic(ctx, topic, "series", accepts=lambda _t: True, kind="")
        topics.append(TopicFields(name, msg_type, tuple(fields)))
    try:

        async def progress(listened: float) -> None:
            await ctx.report_progress(round(listened, 1), duration, f"{listened:.0f} of {duration:g} s")

        lines, counts = await collect(ctx.client, topics, duration, on_progress=progress)
    except FieldError as exc:
        raise ToolFailure(f"{exc} Nothing was plotted; fix the field and call again.") from None
    notes = [f"No message on {t} in {duration:g} s." for t, n in counts.items() if n == 0]
    if all(n == 0 for n in counts.values()):
        raise ToolFailure(
            f"No message arrived on {', '.join(counts)} within {duration:g} s. Are their publishers running? "
            "get_topic_info shows them; a longer duration waits longer."
        )
    image = await asyncio.to_thread(_draw, lines, duration, max_size)
    figures = [_figures(line, counts[line.topic], duration) for line in lines]
    answer = PlotAnswer(duration=duration, series=figures, notes=notes)
    return ToolAnswer(text=_text(answer), data=answer, images=(ToolImage(image, "image/png"),))


def _draw(lines: list[Series], duration: float, width: int) -> bytes:
    from rosbridge_mcp_server.pictures.charts import draw_chart  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.pictures.drawing import png_bytes  # noqa: PLC0415 - on first use

    return png_bytes(draw_chart(lines, duration, width, max(160, width // 2)))


def _figures(line: Series, messages: int, duration: float) -> SeriesFigures:
    from rosbridge_mcp_server.pictures.charts import stats  # noqa: PLC0415 - on first use

    found = stats(line)
    times = line.times
    rate = (len(times) - 1) / (times[-1] - times[0]) if len(times) > 1 and times[-1] > times[0] else None

    def r(value: float | None) -> float | None:
        return None if value is None else float(f"{value:.6g}")

    return SeriesFigures(
        topic=line.topic,
        field=line.path,
        unit=line.unit,
        samples=found.count,
        min=r(found.min),
        max=r(found.max),
        mean=r(found.mean),
        last=r(found.last),
        rate_hz=None if rate is None else round(rate, 2),
    )


def _text(answer: PlotAnswer) -> str:
    rows = []
    for s in answer.series:
        unit = f" {s.unit}" if s.unit else ""
        if s.min is None:
            rows.append(f"{s.topic} {s.field}: {s.samples} samples, none numeric")
            continue
        rate = f", {s.rate_hz:g} Hz" if s.rate_hz is not None else ""
        rows.append(
            f"{s.topic} {s.field}{unit and f' ({s.unit})'}: min {s.min:g} max {s.max:g} mean {s.mean:g} "
            f"last {s.last:g}, {s.samples} samples{rate}"
        )
    text = f"{answer.duration:g} s: " + "; ".join(rows) + "."
    if answer.notes:
        text += " " + " ".join(answer.notes)
    return text
