"""``get_transform``: where one frame is relative to another, from /tf and /tf_static."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.frames import look_up_transform
from rosbridge_mcp_server.robot.namespaces import SeveralNamespacesError
from rosbridge_mcp_server.tools.base import READS_ROBOT, ToolAnswer, ToolContext, ToolSpec
from rosbridge_mcp_server.tools.namespaces import (
    NamespaceArgument,
    choose_one,
    given_namespace,
    non_defaults,
)

__all__ = ["SPEC", "TransformAnswer", "run"]


class Vector(BaseModel):
    """A translation in metres."""

    x: float
    y: float
    z: float


class Rotation(BaseModel):
    """A rotation: unit quaternion and roll/pitch/yaw in degrees."""

    x: float
    y: float
    z: float
    w: float
    roll: float = Field(description="Degrees about x")
    pitch: float = Field(description="Degrees about y")
    yaw: float = Field(description="Degrees about z")


class TransformAnswer(BaseModel):
    """The pose of the source frame in the target frame."""

    target_frame: str
    source_frame: str
    translation: Vector
    rotation: Rotation
    chain: list[str] = Field(description="Frames walked, target first")
    age: float | None = Field(description="Seconds since the newest moving link arrived; None if all static")
    static: bool = Field(description="True when every link used came from /tf_static")
    namespace: str = Field(default="", description='The robot\'s namespace whose tf answered ("" = none)')


SPEC = ToolSpec(
    name="get_transform",
    title="Frame transform",
    description=(
        "Where source_frame is in target_frame (/tf, /tf_static). Read-only. Example: "
        '{"target_frame": "odom", "source_frame": "base_link"}'
    ),
    hints=READS_ROBOT,
    output=TransformAnswer,
)


async def run(
    ctx: ToolContext,
    target_frame: Annotated[str, Field(description="Answer in this frame, e.g. map")],
    source_frame: Annotated[str, Field(description="Frame to locate, e.g. base_link")],
    timeout: Annotated[float, Field(gt=0, le=60, description="Seconds to listen, e.g. 3")] = 3.0,
    namespace: NamespaceArgument = None,
) -> ToolAnswer:
    """Listen to /tf and /tf_static until the frames connect, then compose the links."""
    try:
        found = await look_up_transform(
            ctx.client,
            ctx.graph,
            target_frame,
            source_frame,
            timeout=timeout,
            namespace=given_namespace(ctx, namespace),
        )
    except SeveralNamespacesError as exc:
        given = {"target_frame": target_frame, "source_frame": source_frame, "timeout": timeout}
        raise choose_one(exc, SPEC.name, non_defaults(run, given)) from None
    lookup = found.lookup
    t = lookup.transform.translation
    q = lookup.transform.rotation
    roll, pitch, yaw = lookup.transform.rpy_degrees()
    answer = TransformAnswer(
        target_frame=lookup.target,
        source_frame=lookup.source,
        translation=Vector(x=_r(t[0]), y=_r(t[1]), z=_r(t[2])),
        rotation=Rotation(
            x=_r(q[0]), y=_r(q[1]), z=_r(q[2]), w=_r(q[3]), roll=_r(roll), pitch=_r(pitch), yaw=_r(yaw)
        ),
        chain=list(lookup.chain),
        age=round(found.age, 3) if found.age is not None else None,
        static=lookup.static_only,
        namespace=found.namespace,
    )
    freshness = "static links only" if answer.static else f"newest link {answer.age:.3f} s old"
    text = (
        f"{answer.source_frame} in {answer.target_frame}: translation x={answer.translation.x:g} "
        f"y={answer.translation.y:g} z={answer.translation.z:g} m; rotation roll={answer.rotation.roll:g}° "
        f"pitch={answer.rotation.pitch:g}° yaw={answer.rotation.yaw:g}° (quaternion x={answer.rotation.x:g} "
        f"y={answer.rotation.y:g} z={answer.rotation.z:g} w={answer.rotation.w:g}); chain "
        f"{' → '.join(answer.chain)}; {freshness}."
    )
    if found.note is not None:
        text = f"{found.note}\n{text}"
    elif found.namespace:
        text = f"{text.removesuffix('.')} (tf of {found.namespace})."
    return ToolAnswer(text=text, data=answer)


def _r(value: float) -> float:
    rounded = round(value, 6)
    return 0.0 if rounded == 0 else rounded
